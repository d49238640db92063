"""`jaxslosh mooring`: the moored scene's static equilibrium, line tensions, the lines' stiffness
and the offset curve (docs/guide/moorings.md)."""
from __future__ import annotations

import json
import math
import sys

import numpy as np

from ..mooring.statics import StaticFailure, mooring
from ..plot.mooring import plot_mooring
from .common import COMMANDS, EXIT_NUMERICAL, EXIT_OK, InputError, figure_file, load, setup_jax

DOF_NAMES = ("surge", "sway", "heave", "roll", "pitch", "yaw")


def add_parsers(sub):
    s = sub.add_parser("mooring", help=COMMANDS["mooring"][1])
    s.add_argument("scene")
    s.add_argument("--offsets", help="X1,X2,... horizontal offsets (m) of the offset curve "
                                     "(default: 0 to 10 %% of the depth in 11 steps)")
    s.add_argument("--direction", type=float, default=0.0,
                   help="the offsets' direction, degrees from +X towards +Y (default 0)")
    s.add_argument("--json", action="store_true", help="print one JSON object (SI units, angles in rad)")
    s.add_argument("-o", "--output", help="a figure of the lines' shapes and of the offset curve")


def _pose(eq) -> str:
    """x, y, z (m) and roll, pitch, yaw (deg) of an equilibrium (rad)."""
    return ", ".join(f"{n} {v:.6g} {'m' if i < 3 else 'deg'}"
                     for i, (n, v) in enumerate(zip(DOF_NAMES, np.r_[eq[:3], np.degrees(eq[3:])])))


def parse_offsets(text):
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"--offsets: expected numbers X1,X2,... in m, got {text!r}") from None
    if not values or not all(math.isfinite(v) for v in values):
        raise InputError(f"--offsets: expected finite numbers X1,X2,... in m, got {text!r}")
    return values


def cmd_mooring(a):
    offsets = parse_offsets(a.offsets)
    if not math.isfinite(a.direction):
        raise InputError(f"--direction: must be a finite angle in degrees, got {a.direction}")
    scene = load(a.scene)
    if not scene.mooring:
        raise InputError(f"{a.scene}: the scene has no [[mooring]] lines")
    out = figure_file("-o", a.output) if a.output else None
    setup_jax()
    try:
        r = mooring(scene, offsets=offsets, direction=math.radians(a.direction))
    except StaticFailure as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_NUMERICAL
    if out:
        plot_mooring(r, out, title=scene.title)
    if a.json:
        print(json.dumps(r.as_dict()))
        return EXIT_OK
    print("static equilibrium in still water (COG from its rest position):")
    print(("  vessel: " if r.bodies else "  ") + _pose(r.equilibrium))
    for name, b in r.bodies.items():     # each body's angles about its own axes
        print(f"  {name}: {_pose(b['equilibrium'])}")
    print(f"{'line':>12} {'fairlead N':>13} {'anchor N':>13} {'H N':>13} {'V N':>13} {'on seabed m':>12}")
    for line in r.lines:
        print(f"{line['name']:>12} {line['fairlead_tension']:13.6g} {line['anchor_tension']:13.6g} "
              f"{line['horizontal']:13.6g} {line['vertical']:13.6g} {line['seabed_length']:12.5g}")
    print(f"the {'vessel' + chr(39) + 's ' if r.bodies else ''}lines' stiffness about the COG, K = -dF/dx "
          "(N/m, N/rad, N m/m, N m/rad):")
    for row in r.stiffness:
        print("  " + " ".join(f"{v:11.4g}" for v in row))
    for name, b in r.bodies.items():
        if np.any(b["stiffness"]):
            print(f"{name}'s lines' stiffness about its COG:")
            for row in b["stiffness"]:
                print("  " + " ".join(f"{v:11.4g}" for v in row))
    print(f"offset curve along {a.direction:g} deg: offset m, restoring N, most loaded line's fairlead tension N")
    for o, f, t in zip(r.offsets, r.restoring, r.max_tension):
        print(f"  {o:10.4g} {f:13.6g} {t:13.6g}")
    if out:
        print(f"wrote {out}")
    return EXIT_OK
