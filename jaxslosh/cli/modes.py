"""`jaxslosh modes`: natural frequencies of a tank's liquid or a flexible structure, vessel held fixed."""
from __future__ import annotations

import json
import math

from ..analysis.coupled import PENALTY_LABEL, coupled_modes
from ..analysis.modes import sloshing_modes, structure_modes
from ..liquid.modes import KIND_NOTES, others_in_band
from .common import COMMANDS, EXIT_OK, InputError, setup_jax, load


def add_parsers(sub):
    m = sub.add_parser("modes", help=COMMANDS["modes"][1])
    m.add_argument("scene")
    g = m.add_mutually_exclusive_group()
    g.add_argument("--tank")
    g.add_argument("--structure")
    g.add_argument("--coupled", action="store_true",
                   help="the coupled system's modes (vessel, liquid, structures), linearised about rest")
    m.add_argument("-n", type=int, default=10, help="number of modes (default 10)")
    m.add_argument("--json", action="store_true", help="print one JSON object")


def cmd_modes(a):
    if a.n < 1:
        raise InputError(f"-n: must be at least 1, got {a.n}")
    scene = load(a.scene)
    setup_jax()
    if a.coupled:
        return _coupled_modes(scene, a)
    if a.structure is not None:
        return _structure_modes(scene, a)
    names = [t.name for t in scene.tanks]
    if a.tank is not None:
        if a.tank not in names:
            raise InputError(f"--tank: no tank named {a.tank!r} (tanks: {', '.join(names) or 'none'})")
        names = [a.tank]
    elif not names:
        raise InputError(f"{a.scene}: the scene has no tanks")
    # without --tank, every tank in the scene's order, each labelled (`--tank NAME` for one)
    found = [_tank_json(name, sloshing_modes(scene, tank=name, n=a.n)) for name in names]
    if a.json:
        # one object: the first tank's fields at the top (the documented form), every tank's under "tanks"
        print(json.dumps(dict(found[0], tanks=found) if a.tank is None else found[0]))
        return EXIT_OK
    for j, m in enumerate(found):
        if j:
            print()
        print(f"liquid modes of tank {m['tank']!r}"
              + (f" ({j + 1} of {len(found)})" if len(found) > 1 else "") + " (vessel held fixed):")
        # the sloshing modes first; any other mode among them (below the highest sloshing one listed)
        # apart, labelled; the rest, above the band, after them. '#' is the place in frequency order.
        band = set(m["others_in_sloshing_band"])
        rows = list(zip(range(len(m["omega"])), m["omega"], m["kind"], m["free_surface_share"]))
        _rows([r for r in rows if r[0] not in band])
        if band:
            kinds = sorted({m["kind"][i] for i in band})
            print(f"not sloshing, among the sloshing modes above ({len(band)}):")
            _rows([r for r in rows if r[0] in band])
            for k in kinds:
                print(f"  {k}: {KIND_NOTES.get(k, k)}")
        if m["circulation_modes_left_out"]:
            print(f"({m['circulation_modes_left_out']} circulation modes at zero frequency left out: "
                  f"divergence-free flow with no free-surface motion, which the face-normal element holds at "
                  f"exactly zero)")
    return EXIT_OK


def _rows(rows):
    print(f"{'#':>3} {'omega rad/s':>12} {'f Hz':>10} {'period s':>10} {'surface share':>14}  kind")
    for i, w, k, s in rows:
        f = w / (2 * math.pi)
        print(f"{i + 1:>3} {w:12.5f} {f:10.5f} {1 / f if f > 0 else float('inf'):10.4f} {s:14.3f}  {k}")


def _tank_json(name, modes) -> dict:
    return {"tank": name, "omega": [float(w) for w in modes.omega], "kind": list(modes.kind),
            "free_surface_share": [float(s) for s in modes.free_surface_share],
            # (a tank with elastic walls has no such count: its liquid element is a nodal one)
            "circulation_modes_left_out": int(getattr(modes, "circulation", 0)),
            "others_in_sloshing_band": others_in_band(modes.kind)}


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


def _coupled_modes(scene, a):
    m = coupled_modes(scene, n=a.n)
    if a.json:
        print(json.dumps({"coupled": True, "omega": [float(w) for w in m.omega],
                          "damped_omega": [float(w) for w in m.damped],
                          "damping_ratio": [float(z) for z in m.damping_ratio], "dominant": list(m.dominant),
                          "shares": [{k: float(v) for k, v in s.items()} for s in m.shares],
                          "radiation": list(m.radiation), "not_oscillating": m.not_oscillating,
                          "label": list(m.label), "penalty_share": [float(p) for p in m.penalty_share]}))
        return EXIT_OK
    print("coupled modes (vessel, liquid and structures, linearised about rest; radiation A(w), B(w) at each "
          "mode's frequency where the tables reach it):")
    print(f"{'#':>3} {'omega rad/s':>12} {'damped rad/s':>13} {'period s':>10} {'damping':>9}  {'dominant':<18} "
          f"{'share':>6}  radiation")
    for i in range(len(m.omega)):
        w, wd, z, dom = m.omega[i], m.damped[i], m.damping_ratio[i], m.dominant[i]
        print(f"{i + 1:>3} {w:12.5f} {wd:13.5f} {2 * math.pi / wd:10.4f} {z:9.5f}  {dom:<18} {m.shares[i][dom]:6.3f}  "
              f"{m.radiation[i]}" + (f"  <- {m.label[i]}" if m.label[i] != dom else ""))
    for i in (i for i, lb in enumerate(m.label) if lb == PENALTY_LABEL):
        print(f"(mode {i + 1}: {PENALTY_LABEL}: {m.penalty_share[i]:.1%} of its potential energy is the liquid "
              f"element's rotation penalty, which holds the liquid's absolute rotation; an inviscid liquid has no "
              f"such stiffness: a numerical mode of the element, not one of the ship)")
    if m.not_oscillating:
        print(f"({m.not_oscillating} non-oscillating modes left out: rigid-body modes without restoring, such as "
              f"surge and sway, or overdamped ones)")
    return EXIT_OK
