"""`jaxslosh modes`: natural frequencies of a tank's liquid or a flexible structure, vessel held fixed."""
from __future__ import annotations

import json
import math

from ..analysis.modes import sloshing_modes, structure_modes
from .common import EXIT_OK, InputError, setup_jax, load


def add_parsers(sub):
    m = sub.add_parser("modes", help="natural frequencies of a tank's liquid, or of a flexible structure, with the "
                                     "vessel held fixed")
    m.add_argument("scene")
    g = m.add_mutually_exclusive_group()
    g.add_argument("--tank")
    g.add_argument("--structure")
    m.add_argument("-n", type=int, default=10, help="number of modes (default 10)")
    m.add_argument("--json", action="store_true", help="print one JSON object")


def cmd_modes(a):
    if a.n < 1:
        raise InputError(f"-n: must be at least 1, got {a.n}")
    scene = load(a.scene)
    setup_jax()
    if a.structure is not None:
        return _structure_modes(scene, a)
    tank = a.tank
    if tank is None:
        if not scene.tanks:
            raise InputError(f"{a.scene}: the scene has no tanks")
        tank = scene.tanks[0].name
    modes = sloshing_modes(scene, tank=tank, n=a.n)
    if a.json:
        print(json.dumps({"tank": tank, "omega": [float(w) for w in modes.omega], "kind": list(modes.kind),
                          "free_surface_share": [float(s) for s in modes.free_surface_share]}))
    else:
        print(f"liquid modes of tank {tank!r} (vessel held fixed):")
        print(f"{'#':>3} {'omega rad/s':>12} {'f Hz':>10} {'period s':>10} {'surface share':>14}  kind")
        for i, (w, k, s) in enumerate(zip(modes.omega, modes.kind, modes.free_surface_share)):
            f = w / (2 * math.pi)
            print(f"{i + 1:>3} {w:12.5f} {f:10.5f} {1 / f if f > 0 else float('inf'):10.4f} {s:14.3f}  {k}")
    return EXIT_OK


def _structure_modes(scene, a):
    names = [s.name for s in scene.structures]
    if a.structure not in names:
        raise InputError(f"--structure: no structure named {a.structure!r} (structures: {', '.join(names) or 'none'})")
    modes = structure_modes(scene, a.structure, n=a.n)
    if a.json:
        print(json.dumps({"structure": a.structure, "omega": [float(w) for w in modes.omega], "kind": list(modes.kind),
                          "shares": {k: [float(x) for x in v] for k, v in modes.shares.items()}}))
        return EXIT_OK
    print(f"modes of structure {a.structure!r} (held at its attachment, vessel fixed):")
    print(f"{'#':>3} {'omega rad/s':>12} {'f Hz':>10} {'period s':>10} {'share':>6}  kind")
    for i, (w, k) in enumerate(zip(modes.omega, modes.kind)):
        f = w / (2 * math.pi)
        print(f"{i + 1:>3} {w:12.5f} {f:10.5f} {1 / f if f > 0 else float('inf'):10.4f} {modes.shares[k][i]:6.3f}  {k}")
    return EXIT_OK
