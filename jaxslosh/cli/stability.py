"""`jaxslosh stability`: GZ curves with the tank liquids frozen and level, GM0, the angle of vanishing
stability and the IS Code 2008 Part A 2.2 criteria (docs/guide/stability.md)."""
from __future__ import annotations

import json
import sys

import numpy as np

from ..analysis.bodystability import LinearStability
from ..analysis.stability import DEFAULT_DEGREES, StabilityFailure, stability
from ..plot.stability import plot_stability
from .common import COMMANDS, EXIT_NUMERICAL, EXIT_OK, InputError, load, output_folder, setup_jax


def add_parsers(sub):
    s = sub.add_parser("stability", help=COMMANDS["stability"][1])
    s.add_argument("scene")
    s.add_argument("--angles", help="LOW:HIGH:COUNT heels in degrees (default 0:80:81)")
    s.add_argument("--axis", choices=("roll", "pitch"), default="roll",
                   help="the heel's axis (default roll; the criteria are for roll)")
    s.add_argument("--json", action="store_true", help="print one JSON object (angles in rad)")
    s.add_argument("-o", "--output", help="a figure of both GZ curves and the criteria (PNG)")


def parse_angles(text):
    """LOW:HIGH:COUNT degrees -> rad."""
    if text is None:
        return np.radians(np.linspace(*DEFAULT_DEGREES))
    try:
        lo, hi, n = text.split(":")
        lo, hi, n = float(lo), float(hi), int(n)
    except ValueError:
        raise InputError(f"--angles: expected LOW:HIGH:COUNT in degrees, got {text!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and n >= 1 and lo <= hi and (n == 1 or lo < hi)):
        raise InputError(f"--angles: need finite LOW <= HIGH (LOW < HIGH when COUNT > 1) and COUNT >= 1, got {text!r}")
    if max(abs(lo), abs(hi)) >= 180.0:
        raise InputError(f"--angles: heels must lie within (-180, 180) degrees, got {text!r}")
    return np.radians(np.linspace(lo, hi, n))


def cmd_stability(a):
    angles = parse_angles(a.angles)
    scene = load(a.scene)
    if a.output:
        output_folder("-o", a.output, scene=a.scene)
    setup_jax()
    try:
        s = stability(scene, angles, axis=a.axis)
    except StabilityFailure as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_NUMERICAL
    if a.output:
        plot_stability(s, a.output, title=scene.title)
    if a.json:
        print(json.dumps(s.as_dict()))
        return EXIT_OK
    if s.model == "linear":      # a vessel without a hull beside bodies: its curve as theirs
        h = scene.vessel.hydrostatics
        if scene.tanks:          # its liquids frozen (its GM's) and level
            print(f"vessel {scene.vessel.name} (its linear hydrostatics, GM_T {h.gm_t:.5f} m, GM_L {h.gm_l:.5f} m "
                  "with the liquids frozen; neither sinking nor trimming):")
            print_vessel(s, a.axis, "vessel", judged=False)
        else:
            print_body(LinearStability(scene.vessel.name, s.angle, s.gz, s.gm0, h.gm_t, h.gm_l, s.vanishing_angle,
                                       s.axis), "vessel")
        print("IS Code 2008 Part A 2.2: not judged on linear hydrostatics (the criteria are for a hull's curve)")
    else:
        print_vessel(s, a.axis)
    for b in s.bodies.values():
        if b["model"] == "hull":        # a body with its own hull: the vessel's table of its curves
            print(f"body {b.name}:")
            print_vessel(b, a.axis, "body")
        elif "gz_frozen" in b.as_dict():       # linear hydrostatics and tanks: both curves, no criteria
            print(f"body {b.name} (its linear hydrostatics with the liquids frozen; neither sinking nor trimming):")
            print_vessel(b, a.axis, "body", judged=False)
        else:
            print_body(b)
    if a.output:
        print(f"wrote {a.output}")
    return EXIT_OK


def print_vessel(s, axis: str, who: str = "vessel", judged: bool = True):
    """The vessel's (or a body's: `who`) curves from its hull and the criteria (`judged`)."""
    print(f"GZ about the {axis} axis (m), the {who} " + ("free to sink and trim at its displacement:" if judged
                                                        else "at its displacement:"))
    print(f"{'heel deg':>9} {'GZ level':>10} {'GZ frozen':>10}")
    for ang, g, gf in zip(s.angle, s.gz, s.gz_frozen):
        print(f"{np.degrees(ang):9.3f} {g:10.5f} {gf:10.5f}")
    print(f"GM0 {s.gm0:.5f} m with the liquids level, {s.gm0_frozen:.5f} m frozen "
          f"(free-surface correction {s.gm0_frozen - s.gm0:.5f} m)")
    va = s.vanishing_angle
    print("angle of vanishing stability: " + ("none in the range" if va is None else f"{np.degrees(va):.3f} deg"))
    if not judged:
        return
    if s.criteria:
        print("IS Code 2008 Part A 2.2 (liquids level):")
        for c in s.criteria:
            deg = f"  ({np.degrees(c.value):.2f} deg >= {np.degrees(c.limit):.0f})" if "(rad)" in c.name and \
                "angle" in c.name else ""
            print(f"  {'pass' if c.passed else 'FAIL'}  {c.name:<30} {c.value:10.5f}  (>= {c.limit:.5g}){deg}")
    else:
        print("IS Code 2008 Part A 2.2: criteria for heel about the roll axis only")


def print_body(b, what="body"):
    """A [[bodies]] body's curve (analysis/bodystability.py LinearStability), as the vessel's table."""
    print(f"{what} {b.name}: GZ about the {b.axis} axis (m) of its linear hydrostatics, "
          f"GM_T {b.gm_t:.5f} m, GM_L {b.gm_l:.5f} m:")
    print(f"{'heel deg':>9} {'GZ':>10}")
    for ang, g in zip(b.angle, b.gz):
        print(f"{np.degrees(ang):9.3f} {g:10.5f}")
    va = b.vanishing_angle
    print(f"GM0 {b.gm0:.5f} m; angle of vanishing stability: "
          + ("none in the range" if va is None else f"{np.degrees(va):.3f} deg"))
