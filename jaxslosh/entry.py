"""The `jaxslosh` program (and `python -m jaxslosh`): what it does before the package is imported.

A second `jaxslosh run` of a command line spends most of its start importing jaxslosh and loading
the executables of its two programs (docs/guide/compilation-cache.md). Both take about as long; the loading
is XLA's work, outside Python's lock. So the executables the last run of the same command line used
start loading here (executables.preload), and the package is imported while they load.

Before either, the command's scene is read and checked, without JAX (`check_scene_first`): JAX's
import takes seconds, and a bad scene is answered (one line, exit 2) before it."""
from __future__ import annotations

import hashlib
import os
import sys
from importlib import import_module

from .cache import executables
from .run.guard import stop_on_signals


#: the commands whose one positional argument is a scene file (jaxslosh/cli/common.COMMANDS)
SCENE_COMMANDS = ("run", "check", "modes", "identify", "sweep", "hydro", "rao", "campaign", "stability")


def main() -> int:
    """The program: the command's exit status ends the process (os._exit, past the interpreter's
    teardown). Python callers use jaxslosh.cli.main.main(argv), which returns it."""
    # first: Ctrl-C from here on stops the command with one line and exit 130, JAX's import included
    stop_on_signals()
    args = sys.argv[1:]
    code = check_scene_first(args)
    if code is not None:
        return code
    if next((w for w in args if not w.startswith("-")), None) == "run":
        executables.preload(executables.cache_folder()[1], command_hint(args))
    # imported now, not above: the point is to import it while the executables load
    code = import_module(".cli.main", __package__).main()
    # The command's work is done and its files are closed: the process ends here, not in the
    # interpreter's teardown, where Python has given SIGINT back its default action (a Ctrl-C there
    # killed the process with no message and status -2) and XLA's thread pools take their time to stop.
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(code if isinstance(code, int) else 0)


def scene_argument(args) -> str | None:
    """The scene file a command line names, found without the command's parser (which imports the
    command's module, and JAX): the one word after a scene command that is neither an option nor
    an option's value (a missing file too: that is answered at once as well). None where it is not
    that plain (help asked for, a flag before the scene, ...): the command's own parser then reads
    the line."""
    words = list(args)
    if not words or words[0] not in SCENE_COMMANDS or any(w in ("-h", "--help") for w in words):
        return None
    found = [w for prev, w in zip(words, words[1:])
             if not w.startswith("-") and not (prev.startswith("-") and "=" not in prev)]
    return found[0] if len(found) == 1 else None


def check_scene_first(args) -> int | None:
    """Read and check the command line's scene before JAX is imported: a bad scene's one-line
    error and exit status 2 (cli/main.py's), None otherwise (the scene is kept for the command)."""
    path = scene_argument(args)
    if path is None:
        return None
    common = import_module(".cli.common", __package__)
    try:
        common.read_first(path)
    except common.SceneError as e:
        print("error: " + " ".join(str(e).split()), file=sys.stderr)
        return common.EXIT_INPUT
    return None


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
