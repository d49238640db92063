"""`jaxslosh sweep`: a grid of parameter values run as one vmapped batch, written to one file."""
from __future__ import annotations

import itertools
import os
import sys
import time

import numpy as np

from ..io.sweep import write_sweep
from ..run.batch import check_runs, simulate_batch
from ..scene.keys import scene_values, traceable
from ..scene.types import SceneError
from .common import COMMANDS, InputError, load, overridden, positive, setup_jax, writable_output


def parse_grid(items):
    """["vessel.hydrostatics.gm_t=1.2,1.5,1.8", ...] -> {key: values}; raises ValueError naming the item."""
    grid = {}
    for item in items:
        if "=" not in item:
            raise ValueError(f"--param {item!r}: expected KEY=V1,V2,...")
        key, vals = item.split("=", 1)
        try:
            values = [float(v) for v in vals.split(",") if v.strip()]
        except ValueError:
            raise ValueError(f"--param {key}: values must be numbers, got {vals!r}") from None
        if not values:
            raise ValueError(f"--param {key}: no values")
        key = key.strip()
        if key in grid:
            raise ValueError(f"--param {key}: given twice; give each key once, with all its values")
        grid[key] = values
    return grid


def check_grid(scene, grid):
    """The keys: traceable values of this scene, each given once, each a single number per run (a
    vector or an inertia (`vessel.inertia`, `bodies.<name>.inertia`) is refused: its runs are swept from Python, js.simulate_batch)."""
    try:
        traceable(scene, grid)
    except SceneError as e:
        raise InputError(f"--param {e}") from None
    values = scene_values(scene)
    for key in grid:
        shape = np.shape(values[key])
        if shape != ():
            what = "3 diagonal values or a 3 x 3 matrix" if len(shape) == 2 else f"{shape[0]} numbers"
            raise InputError(f"--param {key}: holds {what}, and a sweep gives each run one number; sweep it "
                             f"from Python: js.simulate_batch(scene, {{{key!r}: an array with a row per run}})")


def grid_product(grid):
    keys = list(grid)
    combos = list(itertools.product(*(grid[k] for k in keys)))
    return {k: np.array([c[i] for c in combos]) for i, k in enumerate(keys)}


def add_parsers(sub):
    s = sub.add_parser("sweep", help=COMMANDS["sweep"][1])
    s.add_argument("scene")
    s.add_argument("--param", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="a dotted scene key and its values; several --param make a grid")
    s.add_argument("-o", "--output", help="sweep file (default: the scene's name with _sweep.h5)")
    s.add_argument("--duration", type=float)
    s.add_argument("--dt", type=float)


def cmd_sweep(a):
    if not a.param:
        raise InputError("--param: give at least one KEY=V1,V2,...")
    try:
        grid = parse_grid(a.param)
    except ValueError as e:
        raise InputError(str(e)) from None
    positive("duration", a.duration)
    positive("dt", a.dt)
    scene = overridden(load(a.scene), a)
    check_grid(scene, grid)
    out = a.output or os.path.splitext(os.path.basename(a.scene))[0] + "_sweep.h5"
    writable_output("-o", out, inputs=(a.scene,))
    params = grid_product(grid)
    n = len(next(iter(params.values())))
    try:             # every run checked as a scene file with its values would be, before computing
        runs = check_runs(scene, params)
    except SceneError as e:
        raise InputError(f"--param {e}") from None
    for i, run in enumerate(runs):
        for w in run.warnings:
            if w not in scene.warnings:
                shown = ", ".join(f"{k} = {params[k][i]:g}" for k in params)
                print(f"warning: run {i} ({shown}): {w}", file=sys.stderr)
    setup_jax()
    print(f"sweep: {n} runs of {a.scene} in one batch", file=sys.stderr)
    t0 = time.perf_counter()
    result, statuses = simulate_batch(scene, params)
    wall = time.perf_counter() - t0
    write_sweep(out, scene, params, result, statuses)
    rpy = np.asarray(result.vessel.roll_pitch_yaw)
    keys = list(params)
    print(" ".join(f"{k:>28}" for k in keys) + f" {'max |roll| deg':>15} {'max |pitch| deg':>16}  status")
    for i in range(n):
        vals = " ".join(f"{params[k][i]:28.6g}" for k in keys)
        print(f"{vals} {np.degrees(np.abs(rpy[i, :, 0]).max()):15.4f} {np.degrees(np.abs(rpy[i, :, 1]).max()):16.4f}"
              f"  {statuses[i]}")
    print(f"done: {n} runs in {wall:.2f} s wall, compilation included -> {out}")
    return 0 if all(s == "ok" for s in statuses) else 3
