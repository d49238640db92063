"""`jaxslosh run` (simulate a scene, write the result file) and `jaxslosh check` (validate it; what it
will simulate)."""
from __future__ import annotations

import os
import sys

from ..assemble.cost import check_cost, describe_cost, estimate
from ..assemble.damping import describe_damping
from ..assemble.check import effects_summary
from ..assemble.effects import describe
from ..io.output import OutputError
from ..io.status import Status
from ..run.progress import wanted
from ..run.tofile import run_to_file
from .common import (COMMANDS, EXIT_INTERRUPTED, EXIT_IO, EXIT_NUMERICAL, EXIT_OK, InputError, setup_jax, load, overridden,
                     positive, writable_output)


def add_parsers(sub):
    r = sub.add_parser("run", help=COMMANDS["run"][1])
    r.add_argument("scene")
    r.add_argument("-o", "--output", help="result file (default: the scene's name with .h5, here)")
    r.add_argument("--duration", type=float, help="override simulation.duration (s)")
    r.add_argument("--dt", type=float, help="override simulation.dt (s)")
    r.add_argument("--no-progress", action="store_true",
                   help="no progress on stderr (drawn only on a terminal unless JAXSLOSH_PROGRESS=1)")
    r.add_argument("--no-fields", action="store_true", help="do not store the liquid displacement fields")
    r.add_argument("--force", action="store_true", help="run even when the scene's cost estimate exceeds this machine")
    c = sub.add_parser("check", help=COMMANDS["check"][1])
    c.add_argument("scene")
    c.add_argument("--force", action="store_true", help="exit 0 even when the cost estimate exceeds this machine")


def cmd_run(a):
    positive("duration", a.duration)
    positive("dt", a.dt)
    scene = overridden(load(a.scene), a)
    dt = scene.simulation.dt
    out = a.output or os.path.splitext(os.path.basename(a.scene))[0] + ".h5"
    replacing = writable_output("-o", out, inputs=(a.scene,))
    check_cost(scene, force=a.force)
    setup_jax()
    if replacing:
        print(f"note: replacing the existing result file {out}", file=sys.stderr)
    try:
        rep = run_to_file(scene, out, progress=wanted(a.no_progress), save_fields=False if a.no_fields else None)
    except OutputError as e:
        raise InputError(f"-o: {e.strerror}") from None
    for w in rep.warnings:
        print(f"warning: {w}", file=sys.stderr)
    code = Status(rep.code)
    if code == Status.OK:
        print(f"done: {rep.steps} steps to t = {rep.steps * dt:.6g} s in {timing(rep.times)} -> {out}")
        return EXIT_OK
    if code.numerical:
        print(f"jaxslosh: numerical failure at {rep.status}; {rep.steps} steps kept in {out}", file=sys.stderr)
        return EXIT_NUMERICAL
    if code == Status.INTERRUPTED:
        print(f"jaxslosh: {rep.status}; {rep.steps} steps kept in {out}", file=sys.stderr)
        return EXIT_INTERRUPTED
    print(f"error: {out}: {rep.status}; {rep.steps} steps kept", file=sys.stderr)
    return EXIT_IO


def timing(times: dict) -> str:
    """"12.34 s wall (build 0.50 s, compile 10.20 s, stepping 1.64 s)": the phases of the run on
    the progress display's clock, so the total is the elapsed time it showed last."""
    parts = ", ".join(f"{name} {s:.2f} s" for name, s in times.items())
    return f"{sum(times.values()):.2f} s wall ({parts})"


def cmd_check(a):
    scene = load(a.scene)
    print(describe(scene))
    for line in describe_damping(scene):
        print(line)
    print(effects_summary(scene))
    print(describe_cost(estimate(scene)))
    check_cost(scene, force=a.force)
    return EXIT_OK
