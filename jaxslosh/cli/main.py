"""The `jaxslosh` command (SPEC section 2): the parser of every subcommand and the one place where
exceptions become messages and exit codes (0 done, 2 bad input, 3 numerical failure)."""
from __future__ import annotations

import os
import sys

from ..scene.types import SceneError
from . import campaign, export, hydro, identify, modes, plot, rao, simulate, sweep
from .common import EXIT_INPUT, EXIT_INTERRUPTED, InputError, Parser

COMMANDS = {"run": simulate.cmd_run, "check": simulate.cmd_check, "plot": plot.cmd_plot, "modes": modes.cmd_modes,
            "identify": identify.cmd_identify, "sweep": sweep.cmd_sweep, "hydro": hydro.cmd_hydro,
            "rao": rao.cmd_rao, "export": export.cmd_export,
            "campaign": campaign.cmd_campaign}


def parser() -> Parser:
    p = Parser(prog="jaxslosh", description="Floating vessels carrying sloshing liquid (Gonzalez & Park 2013).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for module in (simulate, plot, modes, identify, sweep, hydro, rao, export, campaign):
        module.add_parsers(sub)
    return p


def main(argv=None) -> int:
    """Run a command; `argv` None: the program's own arguments (then an interruption ends the
    process at once, past the interpreter's teardown, which XLA's threads could still be in)."""
    try:
        a = parser().parse_args(argv)
        return COMMANDS[a.command](a)
    except (InputError, SceneError) as e:
        # one line, whatever a library's message held (h5py's and the OS's carry newlines)
        print("error: " + " ".join(str(e).split()), file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        if argv is None:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(EXIT_INTERRUPTED)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    raise SystemExit(main())
