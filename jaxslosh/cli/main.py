"""The `jaxslosh` command (docs/reference/commands.md): the parser of every subcommand and the one place where
exceptions become messages and exit codes (0 done, 2 bad input, 3 numerical failure).

Only the module of the command asked for is imported (common.COMMANDS): the others appear in the
parser by name and help alone."""
from __future__ import annotations

import os
import sys
from importlib import import_module

from ..scene.types import SceneError
from ..cache.executables import settle
from .common import COMMANDS, EXIT_INPUT, EXIT_INTERRUPTED, InputError, Parser


def _asked(argv) -> str | None:
    """The command named on the command line (the first word that is not an option), if it is one."""
    word = next((w for w in argv if not w.startswith("-")), None)
    return word if word in COMMANDS else None


def parser(argv=()) -> Parser:
    """The parser; the command named in `argv` complete, every other one by name and help."""
    p = Parser(prog="jaxslosh", description="Floating vessels carrying sloshing liquid (Gonzalez & Park 2013).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    asked = _asked(argv)
    module = COMMANDS[asked][0] if asked else None
    for name, (mod, text) in COMMANDS.items():
        if mod == module:
            if name == asked:
                import_module(f".{mod}", __package__).add_parsers(sub)
        else:
            sub.add_parser(name, help=text)
    return p


def main(argv=None) -> int:
    """Run a command; `argv` None: the program's own arguments (then an interruption ends the
    process at once, past the interpreter's teardown, which XLA's threads could still be in)."""
    args = sys.argv[1:] if argv is None else list(argv)
    try:
        a = parser(args).parse_args(args)
        return getattr(import_module(f".{COMMANDS[a.command][0]}", __package__), f"cmd_{a.command}")(a)
    except (InputError, SceneError) as e:
        # one line, whatever a library's message held (h5py's and the OS's carry newlines)
        print("error: " + " ".join(str(e).split()), file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt as e:
        # a command that knows what an interruption leaves says it (a campaign: cases done, --resume)
        print(getattr(e, "report", None) or "interrupted", file=sys.stderr)
        if argv is None:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(EXIT_INTERRUPTED)
        return EXIT_INTERRUPTED
    finally:
        settle()        # executables loading ahead (jaxslosh/entry.py) that the command did not use


if __name__ == "__main__":
    raise SystemExit(main())
