"""The `jaxslosh` program (and `python -m jaxslosh`): what it does before the package is imported.

A second `jaxslosh run` of a command line spends most of its start importing jaxslosh and loading
the executables of its two programs (README "Compile time"). Both take about as long; the loading
is XLA's work, outside Python's lock. So the executables the last run of the same command line used
start loading here (executables.preload), and the package is imported while they load."""
from __future__ import annotations

import hashlib
import os
import sys
from importlib import import_module

from .cache import executables


def main() -> int:
    args = sys.argv[1:]
    if next((w for w in args if not w.startswith("-")), None) == "run":
        executables.preload(executables.cache_folder()[1], command_hint(args))
    # imported now, not above: the point is to import it while the executables load
    return import_module(".cli.main", __package__).main()


def command_hint(args) -> str:
    """A name for what a command line computes: its words in this folder, the output file and the
    options that change only how it reports left out, and the contents of the files it names (the
    scene). Only a hint (executables.preload): two command lines that compute the same program
    under different names load nothing ahead; a stale name loads what is not used."""
    words, skip = [], False
    for w in args:
        if skip:
            skip = False
        elif w in ("-o", "--output"):
            skip = True
        elif not (w in ("--no-progress", "--force") or w.startswith(("--output=", "-o"))):
            words.append(w)
    h = hashlib.sha256(repr((os.getcwd(), words)).encode())
    for w in words:
        try:
            if os.path.isfile(w):
                with open(w, "rb") as f:
                    h.update(f.read())
        except OSError:
            pass
    return h.hexdigest()
