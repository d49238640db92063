"""Probe B of the paper example (scenes/paper_ship_tank.toml) with its tank as finite elements on
refined meshes and as a multimodal tank: the peak and rms of the free surface's elevation at B over
the run, the finite elements' converged value by Richardson extrapolation (where the sequence is
monotone), and each variant's difference from it. Prints a table.

    python -m benchmarks.validation.paper_probe_b [--duration T] [--meshes 5,8,10] [--modes 6,12]
        [--flow3d 5,8,12] [--no-coriolis 8] [--omega 0.1,0.05,0] [--scale s] [--expansion third-order]
        [--save out.npz] [--quick]
    python -m benchmarks.validation.paper_probe_b --table a.npz,b.npz,...

--element sets the finite elements' `tanks.fluid.element` ("rt": the face-normal element).
--scale multiplies the initial angular velocity and divides the elevations by it (s = 0.01: the
linear limit, where the second-order part of the response vanishes). --expansion is the multimodal
tanks' `tanks.expansion`. --save writes every variant's record as soon as it has run (one .npz,
rewritten after each), and --table prints the table of saved records without running anything
(their variants in the order given; the finite elements' meshes among them give the reference).

--modes are two-dimensional multimodal tanks (waves along x only), --flow3d three-dimensional ones
(flow = "3d": the lowest modes of the square base, whole degenerate pairs), --no-coriolis finite
elements with `[effects] coriolis = false` (the 2 omega x d_dot load on the liquid's relative motion,
second order, that makes most of their roll-driven elevation at B).

The elevation is probe B's vertical displacement (B sits on the free surface at the tank's
centre line, 0.5 m from the wall at x = +2.5 m). `--quick`: 0.5 s, mesh 5 and 6 modes."""
from __future__ import annotations

import time

import numpy as np
from scipy.optimize import brentq

import jaxslosh as js
from benchmarks.harness import parser, scene


def _richardson(h, f):
    """(f at h = 0, order p) of f = f0 + C h^p through three points (h descending), or None where
    the differences change sign (not monotone: no extrapolation)."""
    (h1, h2, h3), (f1, f2, f3) = h, f
    if (f1 - f2) * (f2 - f3) <= 0:
        return None

    def g(p):     # (f1 - f2) / (f2 - f3) against (h1^p - h2^p) / (h2^p - h3^p)
        return (h1 ** p - h2 ** p) / (h2 ** p - h3 ** p) - (f1 - f2) / (f2 - f3)

    try:
        p = brentq(g, 0.05, 8.0)
    except ValueError:
        return None
    C = (f2 - f3) / (h2 ** p - h3 ** p)
    return f3 - C * h3 ** p, p


def main():
    ap = parser(__doc__)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--meshes", default="5,8,10")
    ap.add_argument("--modes", default="6,12")
    ap.add_argument("--flow3d", "--modes3d", default="", help="modes of a flow = \"3d\" multimodal tank (comma list)")
    ap.add_argument("--no-coriolis", default="", help="finite-element meshes run without the Coriolis load (comma list)")
    ap.add_argument("--save", default="", help="write probe B's vertical displacement of every variant here (.npz)")
    ap.add_argument("--omega", default="0.1,0.05,0.0", help="the initial angular velocity (rad/s; the paper's)")
    ap.add_argument("--scale", type=float, default=1.0, help="multiplies the initial angular velocity; "
                    "the elevations are divided by it")
    ap.add_argument("--expansion", default="exact", help="the multimodal tanks' tanks.expansion")
    ap.add_argument("--element", default="", help="the finite elements' tanks.fluid.element (the scene's "
                    "default: \"stabilized\")")
    ap.add_argument("--table", default="", help="print the table of these saved records (comma list) and stop")
    args = ap.parse_args()
    if args.quick:
        args.duration, args.meshes, args.modes, args.flow3d, args.no_coriolis = 0.5, "5", "6", "", ""
    if args.table:
        stats, t = {}, None
        for f in args.table.split(","):
            with np.load(f) as d:
                t = d["time"] if t is None else t
                for k in d.files:
                    if k != "time":
                        z = d[k]
                        stats[k] = (np.abs(z).max(), np.sqrt(np.mean(z ** 2)), z)
        _table(stats)
        return
    omega = [args.scale * float(x) for x in args.omega.split(",")]
    base = js.scene_with(scene("paper_ship_tank"), {"simulation.duration": args.duration,
                                                     "vessel.initial.angular_velocity": omega})
    tag = "" if args.expansion == "exact" else f", {args.expansion}"
    multimodal = {"tanks[0].mesh": None, "tanks[0].walls": None, "tanks[0].model": "multimodal"}
    if args.expansion != "exact":
        multimodal["tanks[0].expansion"] = args.expansion
    fe = {"tanks[0].fluid.element": args.element} if args.element else {}
    el = f", {args.element}" if args.element else ""
    variants = {}
    for n in [int(x) for x in args.meshes.split(",") if x]:
        variants[f"fem {n}x{n}x{n}{el}"] = js.scene_with(base, {**fe, "tanks[0].mesh": [n, n, n]})
    for m in [int(x) for x in args.modes.split(",") if x]:
        variants[f"multimodal 2d, {m} modes{tag}"] = js.scene_with(base, {**multimodal, "tanks[0].modes": m})
    for m in [int(x) for x in args.flow3d.split(",") if x]:
        variants[f"multimodal 3d, {m} modes{tag}"] = js.scene_with(base, {**multimodal, "tanks[0].flow": "3d",
                                                                           "tanks[0].modes": m})
    for n in [int(x) for x in args.no_coriolis.split(",") if x]:
        variants[f"fem {n}x{n}x{n}, no Coriolis"] = js.scene_with(base, {"tanks[0].mesh": [n, n, n],
                                                                         "effects.coriolis": False})
    stats = {}
    for name, t in variants.items():
        t0 = time.perf_counter()
        r = js.simulate(t, throw=False)
        z = np.asarray(r.probes["B"].displacement)[:, 2] / args.scale
        stats[name] = (np.abs(z).max(), np.sqrt(np.mean(z ** 2)), z)
        print(f"# {name}: {r.status}, {time.perf_counter() - t0:.0f} s, peak {stats[name][0]:.5f} m, "
              f"rms {stats[name][1]:.5f} m", flush=True)
        if args.save:
            np.savez(args.save, time=np.asarray(r.time), **{k: v[2] for k, v in stats.items()})
    _table(stats)


def _table(stats):
    fem = sorted((k for k in stats if k.startswith("fem") and "Coriolis" not in k),
                 key=lambda k: int(k.split()[1].split("x")[0]))
    ref = {}
    if len(fem) >= 3:
        h = [1.0 / int(k.split()[1].split("x")[0]) for k in fem[-3:]]
        for j, what in enumerate(("peak", "rms")):
            ex = _richardson(h, [stats[k][j] for k in fem[-3:]])
            if ex is not None:
                ref[what] = ex
    finest = fem[-1] if fem else None
    print(f"\n{'tank':<40} {'peak m':>9} {'rms m':>9} {'peak vs ref':>12} {'rms vs ref':>11} "
          f"{'rms diff vs finest':>19}")
    for name, (pk, rms, z) in stats.items():
        cols = []
        for j, v in enumerate((pk, rms)):
            r0 = ref.get(("peak", "rms")[j])
            base = r0[0] if r0 is not None else (stats[finest][j] if finest else np.nan)
            cols.append(100 * (v / base - 1))
        zf = stats[finest][2] if finest else None
        n = min(len(z), len(zf)) if finest else 0     # a run that stopped early: over its steps
        d = 100 * np.sqrt(np.mean((z[:n] - zf[:n]) ** 2)) / stats[finest][1] if finest else np.nan
        print(f"{name:<40} {pk:9.5f} {rms:9.5f} {cols[0]:+11.2f}% {cols[1]:+10.2f}% {d:18.2f}%")
    for what in ("peak", "rms"):
        if what in ref:
            print(f"# {what}: Richardson over {', '.join(fem[-3:])}: {ref[what][0]:.5f} m (order {ref[what][1]:.2f})")
        else:
            why = ("not monotone, or no order p in (0.05, 8) fits" if len(fem) >= 3
                   else "fewer than three meshes")
            print(f"# {what}: the finite elements' sequence: {why}: no extrapolation; differences against {finest}")


if __name__ == "__main__":
    main()
