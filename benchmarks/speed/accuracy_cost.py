"""The accuracy-cost map (issue item 3(d)): error against wall time over meshes, steps and modal
reductions of the paper example, a CSV table and a Pareto plot.

    python -m benchmarks.speed.accuracy_cost [--duration 5] [-o docs/accuracy_cost] [--quick]
    python -m benchmarks.speed.accuracy_cost --plot-only [-o docs/accuracy_cost]   # redraw the PNG from the CSV

Every setting runs the paper scene for `duration` seconds. Errors:
  * first sloshing frequency: the mesh's first natural frequency of the liquid (tank held fixed),
    with the step's period error (trapezoidal rule: omega_h = (2/h) atan(omega h / 2)), against the
    closed form g k tanh(k h) = 2.4261 rad/s of the 5 x 5 x 3 m tank (modes keep the mesh's value);
  * probe B: the largest difference of its vertical displacement from the reference run's over the
    run, over the reference's peak. Reference: mesh 20 x 20 x 12, full order, dt = 0.0025 s (or
    --ref-dt).
Wall time: seconds of computing per simulated second, after compilation (the run's steps timed by
benchmarks/harness.py's time_scene: one compiled scan, no frames kept), on this machine (named in
the CSV and the plot). Probe B's history is `js.simulate`'s.
"""
import csv
import os
import platform
import tempfile

import jax
import numpy as np
from matplotlib.transforms import Bbox

import jaxslosh as js
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.liquid.modes import analytic_sloshing_omegas
from jaxslosh.liquid.modal.reduction import tank_basis
from benchmarks.harness import ROOT, parser, scene as load, time_scene
from benchmarks.speed.bench_paper import paper_variant


def machine() -> str:
    name = platform.processor() or platform.machine()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                name = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores, {name}"


def run(sc, duration, timed=True):
    """(time, probe B z-displacement, wall seconds per simulated second, unknowns, steps/s); the
    reference run (timed=False) is not timed."""
    sc = js.scene_with(sc, {"simulation.duration": duration})
    r = js.simulate(sc)
    assert r.status == "ok", f"a run failed: {r.status}"
    z = np.asarray(r.probes["B"].position[:, 2])
    t = np.asarray(r.time)
    if not timed:
        return t, z - z[0], float("nan"), 0, float("nan")
    rec = time_scene("accuracy-cost", sc, int(round(duration / sc.simulation.dt)), repeat=1)
    return t, z - z[0], rec.run_s / duration, rec.unknowns, rec.steps_per_s


def first_omega(mesh, scene):
    t = scene.tanks[0]
    sparse = (mesh[0] + 1) * (mesh[1] + 1) * (mesh[2] + 1) > 2000
    model = build_liquid(t.size, t.fill_depth, mesh, t.fluid.density, t.fluid.sound_speed,
                         scene.environment.gravity, sparse=sparse)
    return float(tank_basis(model, t.origin, 1, static_correction=False).omega[0])


def settings(quick):
    meshes = [(3, 3, 2), (5, 5, 5), (10, 10, 6), (20, 20, 12)]
    dts = [0.04, 0.02, 0.005, 0.0025]
    modes = [2, 8, 20, 40]
    if quick:
        meshes, dts, modes = [(3, 3, 2), (5, 5, 5)], [0.02], [2]
    out = [("mesh", m, 0.01, 0) for m in meshes]
    out += [("step", (5, 5, 5), dt, 0) for dt in dts]
    out += [("modes", (20, 20, 12) if not quick else (5, 5, 5), 0.01, n) for n in modes]
    return out


def main():
    ap = parser(__doc__)      # --quick: a few coarse settings, an 8x8x6 reference, 0.5 s (unless --duration)
    ap.add_argument("--duration", type=float, default=None, help="simulated seconds (5; --quick: 0.5)")
    ap.add_argument("--ref-dt", type=float, default=0.0025)
    ap.add_argument("-o", "--output", help="the CSV's and PNG's path less its suffix (docs/accuracy_cost; "
                                           "--quick: a temporary folder, never the docs' map)")
    ap.add_argument("--plot-only", action="store_true", help="redraw OUTPUT.png from OUTPUT.csv, running nothing")
    a = ap.parse_args()
    a.duration = a.duration or (0.5 if a.quick else 5.0)
    a.output = a.output or (os.path.join(tempfile.mkdtemp(), "accuracy_cost") if a.quick
                            else os.path.join(ROOT, "docs", "accuracy_cost"))
    if a.plot_only:
        rows, host = read_csv(a.output + ".csv")
        plot(rows, a.output + ".png", host)
        print(f"wrote {a.output}.png from {a.output}.csv")
        return
    paper = scene = load("paper_ship_tank")
    t = scene.tanks[0]
    exact = float(analytic_sloshing_omegas(t.size[0], t.size[1], t.fill_depth, scene.environment.gravity, 1)[0])
    ref_mesh = (8, 8, 6) if a.quick else (20, 20, 12)
    print(f"reference: mesh {ref_mesh}, dt = {a.ref_dt} s, {a.duration} s ...", flush=True)
    t_ref, z_ref, _, _, _ = run(paper_variant(paper, mesh=ref_mesh, dt=a.ref_dt), a.duration, timed=False)
    peak = np.abs(z_ref).max()
    omegas = {}
    rows = []
    print(f"{'family':6} {'mesh':>10} {'dt':>7} {'modes':>5} {'unknowns':>8} {'steps/s':>9} {'wall/sim s':>10} "
          f"{'omega1 err':>10} {'B err':>9}", flush=True)
    for family, mesh, dt, modes in settings(a.quick):
        tt, z, wall, n, sps = run(paper_variant(paper, mesh=mesh, modes=modes or None, dt=dt), a.duration)
        if mesh not in omegas:
            omegas[mesh] = first_omega(mesh, scene)
        w = omegas[mesh]
        w_h = 2.0 / dt * np.arctan(w * dt / 2.0)
        w_err = w_h / exact - 1.0
        b_err = np.abs(np.interp(t_ref, tt, z) - z_ref).max() / peak
        row = dict(family=family, mesh="x".join(map(str, mesh)), dt=dt, modes=modes, unknowns=n,
                   steps_per_s=round(sps, 1), wall_per_sim_s=wall, omega1=w_h, omega1_err=w_err, B_err=b_err)
        rows.append(row)
        print(f"{family:6} {row['mesh']:>10} {dt:7.4f} {modes:5d} {n:8d} {sps:9.0f} {wall:10.4f} {w_err:+10.4%} "
              f"{b_err:9.4%}", flush=True)
    host = machine()
    with open(a.output + ".csv", "w", newline="") as f:
        f.write(f"# jaxslosh accuracy-cost map, paper example, {a.duration} s; reference mesh "
                f"{'x'.join(map(str, ref_mesh))} dt {a.ref_dt}; machine: {host}; jax {jax.__version__}\n")
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot(rows, a.output + ".png", host)
    print(f"wrote {a.output}.csv and {a.output}.png")


def read_csv(path):
    """The rows a run wrote (numbers as numbers) and the machine named in its first line."""
    with open(path) as f:
        head = f.readline()
        rows = list(csv.DictReader(f))
    host = head.split("machine: ", 1)[1].split(";", 1)[0].strip() if "machine: " in head else "machine not recorded"
    for r in rows:
        for k, v in r.items():
            if k not in ("family", "mesh"):
                r[k] = int(v) if k in ("modes", "unknowns") else float(v)
    return rows, host


def pareto(points):
    """Indices of the points no other point beats in both cost and error."""
    order = sorted(range(len(points)), key=lambda i: points[i])
    front, best = [], np.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def plot(rows, path, host):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    labelled = []
    style = {"mesh": ("o", "C0"), "step": ("s", "C1"), "modes": ("^", "C2")}
    for ax, key, label in ((axes[0], "B_err", "probe B error (max over the run / peak)"),
                           (axes[1], "omega1_err", "first sloshing frequency error |relative|")):
        pts = [(r["wall_per_sim_s"], max(abs(r[key]), 1e-7)) for r in rows]
        for fam, (mk, col) in style.items():
            sel = [i for i, r in enumerate(rows) if r["family"] == fam]
            ax.loglog([pts[i][0] for i in sel], [pts[i][1] for i in sel], mk, color=col, label=fam)
        front = pareto(pts)
        ax.loglog([pts[i][0] for i in front], [pts[i][1] for i in front], "k--", lw=0.8, label="Pareto front")
        ax.set_xlabel("wall seconds per simulated second (after compilation)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        tags = [r["mesh"] if r["family"] == "mesh" else (f"dt {r['dt']:g}" if r["family"] == "step"
                                                          else f"{r['modes']} modes") for r in rows]
        labelled.append((ax, pts, tags, [pts[i] for i in front]))
    fig.suptitle(f"jaxslosh accuracy-cost map, paper example ({host})", fontsize=10)
    fig.tight_layout()
    for ax, pts, tags, front in labelled:      # after the layout: the placement works in pixels
        place_labels(ax, pts, tags, front)
    fig.savefig(path, dpi=110)
    return fig


#: where a label may go around its point, tried in order: (dx, dy) in points, alignment
_SPOTS = [(dx * r, dy * r, ha, va) for r in (1, 2.5, 4.5)
          for dx, dy, ha, va in ((4, 3, "left", "bottom"), (4, -3, "left", "top"), (-4, 3, "right", "bottom"),
                                 (-4, -3, "right", "top"), (0, 6, "center", "bottom"), (0, -6, "center", "top"))]


def place_labels(ax, pts, tags, front, merge_px=6.0):
    """Label the points without overlaps: points drawn on top of each other share one label ("8,
    20 modes"); each label takes the first spot around its point (_SPOTS, nearest first) where it
    overlaps no label placed before it, no marker, no stretch of the Pareto front, the legend
    nor the axes' edge; a label set off further than the nearest ring gets a leader line."""
    fig = ax.figure
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    xy = ax.transData.transform(np.asarray(pts))
    groups = []                                # [indices] of points within merge_px of each other
    for i in np.argsort(xy[:, 0]):
        for g in groups:
            if np.hypot(*(xy[g[0]] - xy[i])) < merge_px:
                g.append(i)
                break
        else:
            groups.append([i])
    obstacles = [Bbox.from_bounds(x - 4, y - 4, 8, 8) for x, y in xy]
    line = ax.transData.transform(np.asarray(front)) if len(front) > 1 else np.zeros((0, 2))
    for a, b in zip(line[:-1], line[1:]):
        for s in np.linspace(0, 1, 25):
            p = a + s * (b - a)
            obstacles.append(Bbox.from_bounds(p[0] - 1.5, p[1] - 1.5, 3, 3))
    leg = ax.get_legend()
    if leg is not None:
        obstacles.append(leg.get_window_extent(renderer))
    frame = ax.get_window_extent(renderer)
    for g in groups:
        words = sorted((tags[i] for i in g), key=lambda w: (len(w), w))      # "8, 20 modes", not "20, 8"
        unit = words[0].split(" ", 1)[1] if all(" " in w for w in words) else ""
        if unit and all(w.endswith(" " + unit) and w[0].isdigit() for w in words) and len(words) > 1:
            text = ", ".join(w.split(" ", 1)[0] for w in words) + " " + unit     # "8, 20 modes"
        else:
            text = ", ".join(words)
        best = None
        for k, (dx, dy, ha, va) in enumerate(_SPOTS):
            ann = ax.annotate(text, pts[g[0]], xytext=(dx, dy), textcoords="offset points", fontsize=7,
                              ha=ha, va=va)
            box = ann.get_window_extent(renderer).expanded(1.05, 1.1)
            clash = sum(box.overlaps(o) for o in obstacles) + (0 if frame.contains(box.x0, box.y0)
                                                                and frame.contains(box.x1, box.y1) else 10)
            clash *= 10
            # a label about as near another point as its own would be read as that point's: a
            # smaller cost than any overlap, growing as the other point comes nearer than its own
            gap = np.hypot(np.maximum(0, np.maximum(box.x0 - xy[:, 0], xy[:, 0] - box.x1)),
                           np.maximum(0, np.maximum(box.y0 - xy[:, 1], xy[:, 1] - box.y1)))
            clash += max(0.0, gap[g].min() + 12 - np.delete(gap, g).min(initial=np.inf)) / 12
            if best is None or clash < best[0]:
                if best is not None:
                    best[1].remove()
                best = (clash, ann, box, k)
            else:
                ann.remove()
            if clash == 0:
                break
        _, ann, box, k = best
        if k >= 6:                             # set off from its point: a leader line says whose it is
            ann.remove()
            dx, dy, ha, va = _SPOTS[k]
            ann = ax.annotate(text, pts[g[0]], xytext=(dx, dy), textcoords="offset points", fontsize=7, ha=ha,
                              va=va, arrowprops=dict(arrowstyle="-", lw=0.5, color="0.4", shrinkA=0, shrinkB=3))
        obstacles.append(box)


if __name__ == "__main__":
    main()
