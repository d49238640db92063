"""`jaxslosh export RESULT.h5 --paraview OUT.xdmf`: a result as ParaView's XDMF time series."""
from __future__ import annotations

import os
import sys
import time

from ..io.output import OutputError, OutputLock
from ..io.paraview import export_paraview, no_fields_why
from ..io.result import load_result
from .common import COMMANDS, EXIT_OK, InputError, read, output_folder


def add_parsers(sub):
    e = sub.add_parser("export", help=COMMANDS["export"][1])
    e.add_argument("result")
    e.add_argument("--paraview", required=True, metavar="OUT.xdmf",
                   help="the liquid's XDMF file; the free surface, vessel, structures and probes go beside it "
                        "(OUT_surface.xdmf, ...), their arrays into OUT_paraview.h5")
    e.add_argument("--every", type=int, default=1, help="every N-th saved frame (default 1: all)")


def cmd_export(a):
    if not a.paraview.endswith(".xdmf"):
        raise InputError(f"--paraview: {a.paraview}: give an .xdmf file name")
    if a.every < 1:
        raise InputError(f"--every: must be at least 1, got {a.every}")
    output_folder("--paraview", a.paraview)
    data = os.path.splitext(a.paraview)[0] + "_paraview.h5"
    if os.path.exists(a.result) and os.path.exists(data) and os.path.samefile(a.result, data):
        raise InputError(f"--paraview: {data} would overwrite the result file; choose another name")
    r = read(load_result, a.result)
    try:
        lock = OutputLock(data)
    except OutputError as e:
        raise InputError(f"--paraview: {e.strerror}") from None
    t0 = time.perf_counter()
    try:
        files = export_paraview(r, a.paraview, a.every)
    finally:
        lock.release()
    if not r.tanks:
        print(f"note: the result keeps no liquid fields: {no_fields_why(r)}", file=sys.stderr)
    n = len(r.time[::a.every])
    print(f"done: {n} frames in {time.perf_counter() - t0:.2f} s -> {', '.join(files)}")
    return EXIT_OK
