"""`jaxslosh run` (simulate a scene, write the result file) and `jaxslosh check` (validate it; what it
will simulate)."""
from __future__ import annotations

import os
import sys
import time

from ..build.effects import describe, effects_summary
from ..run.tofile import run_to_file
from .common import EXIT_NUMERICAL, EXIT_OK, enable_x64, load, output_folder, overridden, positive


def add_parsers(sub):
    r = sub.add_parser("run", help="simulate a scene, write the result file")
    r.add_argument("scene")
    r.add_argument("-o", "--output", help="result file (default: the scene's name with .h5, here)")
    r.add_argument("--duration", type=float, help="override simulation.duration (s)")
    r.add_argument("--dt", type=float, help="override simulation.dt (s)")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.add_argument("--no-fields", action="store_true", help="do not store the liquid displacement fields")
    c = sub.add_parser("check", help="validate a scene; list what it will simulate")
    c.add_argument("scene")


def cmd_run(a):
    positive("duration", a.duration)
    positive("dt", a.dt)
    scene = overridden(load(a.scene), a)
    dt = scene.simulation.dt
    out = a.output or os.path.splitext(os.path.basename(a.scene))[0] + ".h5"
    output_folder("-o", out, scene=a.scene)
    enable_x64()
    t0 = time.perf_counter()
    status, steps, wall = run_to_file(scene, out, progress=not a.no_progress,
                                      save_fields=False if a.no_fields else None)
    total = time.perf_counter() - t0
    if status != "ok":
        print(f"jaxslosh: numerical failure at {status}; {steps} steps kept in {out}", file=sys.stderr)
        return EXIT_NUMERICAL
    print(f"done: {steps} steps to t = {steps * dt:.6g} s in {total:.2f} s wall, compilation included "
          f"({wall:.2f} s after the first chunk) -> {out}")
    return EXIT_OK


def cmd_check(a):
    scene = load(a.scene)
    print(describe(scene))
    print(effects_summary(scene))
    return EXIT_OK
