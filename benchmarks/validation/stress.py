"""Stress runs of issue 7 (the long versions of tests/solve/test_hard_cases.py): long runs, stiffness,
resonance, odd tank geometries. Prints one table: case, steps, energy drift, constraint drift
(max ||q| - 1|), wall time, and a note with the case's own measure.

    python -m benchmarks.validation.stress            # all cases, several minutes
    python -m benchmarks.validation.stress --quick    # every case 10x shorter (checks the script)

Energy drift: max |E/E0 - 1| over the run, E = kinetic + potential; for HHT also the largest rise
above E0 ("up"), which must stay at round-off. No assertion here: the numbers are reported. The
runs go through `jaxslosh run`'s own chunked loop (jaxslosh/run/tofile.run_to_file, an internal:
its report's stepping time is what is measured).
"""
import os
import sys
import tempfile
import time

import numpy as np

import jaxslosh as js
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.liquid.modes import analytic_sloshing_table, liquid_modes
from jaxslosh.run.tofile import run_to_file
from benchmarks.harness import machine, parser, scene

G = 9.81
ROWS = []


def paper_text(scheme="hht", alpha=0.01, dt=0.01, duration=300.0, mesh=(5, 5, 5), projection=False) -> js.Scene:
    """The paper example with another scheme, step, duration or mesh (the name kept from the TOML days)."""
    keys = {"tanks[0].mesh": list(mesh), "simulation.duration": duration, "simulation.dt": dt,
            "simulation.scheme": scheme, "simulation.alpha": alpha}
    if projection:
        keys["simulation.energy_projection"] = True
    return js.scene_with(scene("paper_ship_tank"), keys)


def ship_text(size, fill, mesh, duration, dt, scheme="newmark", alpha=0.0, initial="", extra="", sim=""):
    """A ship with one tank centred under its COG (tank bottom 1 m below it), probes A (bottom) and B
    (surface) at the middle of the +y wall."""
    a, b, H = size
    return f"""
title = "stress"
[simulation]
duration = {duration!r}
dt = {dt!r}
scheme = "{scheme}"
alpha = {alpha!r}
{sim}
[vessel]
mass = 3.35e5
inertia = [4.9e6, 1.45e7, 1.6e7]
{extra}
[vessel.hydrostatics]
waterplane_area = 160.0
displaced_volume = {(3.35e5 + 1000.0 * a * b * fill) / 1025.0!r}
gm_t = 1.67
gm_l = 14.2
[vessel.initial]
{initial}
[[tanks]]
name = "tank"
origin = [{-a / 2!r}, {-b / 2!r}, -1.0]
size = {list(size)}
fill_depth = {fill!r}
mesh = {list(mesh)}
[[probes]]
name = "A"
tank = "tank"
point = [{a / 2!r}, {b!r}, 0.0]
[[probes]]
name = "B"
tank = "tank"
point = [{a / 2!r}, {b!r}, {fill!r}]
"""


def run(text, fields=False):
    """Through the CLI's chunked loop (no liquid fields unless asked): (result, wall s, loop s)."""
    sc = text if isinstance(text, js.Scene) else js.load_scene(text)
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "r.h5")
        t0 = time.perf_counter()
        rep = run_to_file(sc, out, progress=False, save_fields=fields)
        loop = rep.times["stepping"]
        wall = time.perf_counter() - t0
        r = js.load_result(out)
    return r, wall, loop


def energy_cols(r, hht=False):
    E = np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)
    rel = E / E[0] - 1
    s = f"max {np.max(np.abs(rel)):.2e}, end {rel[-1]:+.2e}"
    if hht:
        s += f", up {max(np.max(rel), 0.0):.1e}"
    return s


def q_drift(r):
    return float(np.max(np.abs(np.linalg.norm(np.asarray(r.vessel.quaternion), axis=1) - 1.0)))


def row(case, r, energy, wall, loop, note=""):
    res = np.asarray(r.solver.residual)[1:]
    tol = js.load_scene(r.scene_text).simulation.tolerance
    # the iterations stop at max(tolerance, the round-off floor eps |K| |d| of the liquid's rows): with
    # the stiff acoustic block (c = 1500 m/s) the floor is above 1e-10 once the liquid moves
    note += f"; Newton residual max {res.max():.1e} (tolerance {tol:g} or the round-off floor)"
    ROWS.append((case, r.steps_done, energy, f"{q_drift(r):.1e}", f"{wall:.1f} ({loop:.1f})",
                 ("FAILED: " + r.status + "; " if r.status != "ok" else "") + note))
    print(f"  {case}: {ROWS[-1][1]} steps, energy {energy}, |q|-1 {ROWS[-1][3]}, wall {ROWS[-1][4]} s, {ROWS[-1][5]}",
          file=sys.stderr, flush=True)


# ------------------------------------------------------------------------------------------------

def long_runs(k):
    T = 300.0 / k
    for scheme, alpha, dt, proj in (("hht", 0.01, 0.01, False), ("newmark", 0.0, 0.01, False),
                                    ("newmark", 0.0, 0.005, False), ("newmark", 0.0, 0.01, True)):
        r, wall, loop = run(paper_text(scheme, alpha, dt, T, projection=proj))
        E = np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)
        rel = E / E[0] - 1
        n = len(rel)
        note = (f"|E/E0-1| max by thirds {np.max(np.abs(rel[:n // 3])):.1e} {np.max(np.abs(rel[n // 3:2 * n // 3])):.1e} "
                f"{np.max(np.abs(rel[2 * n // 3:])):.1e}")
        row(f"paper 5x5x5 {scheme}{' a=' + str(alpha) if scheme == 'hht' else ''}{' + energy projection' if proj else ''}"
            f" dt={dt} {T:g} s", r,
            energy_cols(r, scheme == "hht"), wall, loop, note)


def _ringing(r, size, fill, mesh):
    """Energy of the step-to-step (4th difference) part of the acoustic modal coordinates, per step."""
    m = build_liquid(size, fill, mesh, 1000.0, 1500.0, G)
    modes = liquid_modes(m, n=int(np.asarray(m.free).sum()))
    ac = np.array([k == "acoustic" for k in modes.kind])
    D = np.asarray(r.tanks["tank"].displacement)
    D = D.reshape(D.shape[0], -1)
    eta = (D - D[0]) @ (modes.shapes @ np.kron(np.asarray(m.mass), np.eye(3))).T
    d4 = (eta[4:] - 4 * eta[3:-1] + 6 * eta[2:-2] - 4 * eta[1:-3] + eta[:-4]) / 16
    return 0.5 * np.sum(modes.omega[ac] ** 2 * d4[:, ac] ** 2, axis=1)


def stiffness(k):
    steps = 4000 // k
    for scheme, alpha in (("newmark", 0.0), ("hht", 0.05), ("hht", 0.1)):
        for dt in (0.0025, 0.01, 0.05):
            r, wall, loop = run(paper_text(scheme, alpha, dt, steps * dt), fields=True)
            ring = _ringing(r, (5.0, 5.0, 4.0), 3.0, (5, 5, 5))
            eta = np.asarray(r.probes["B"].displacement)[:, 2] - np.asarray(r.probes["A"].displacement)[:, 2]
            note = (f"acoustic ringing J: first 20 steps {np.mean(ring[:20]):.1e}, last half max "
                    f"{np.max(ring[len(ring) // 2:]):.1e}; max surface elevation {np.max(np.abs(eta)):.3f} m")
            row(f"c=1500 {scheme}{' a=' + str(alpha) if alpha else ''} dt={dt}", r, energy_cols(r, scheme == "hht"),
                wall, loop, note)


def resonance(k):
    size, fill, mesh = (1.0, 2.0, 2.0), 1.0, (2, 8, 4)
    m = build_liquid(size, fill, mesh, 1000.0, 1500.0, G)
    md = liquid_modes(m, n=int(np.asarray(m.free).sum()))
    w1 = float(md.omega[0])
    nodes = np.asarray(m.nodes)
    node = int(np.flatnonzero(np.isclose(nodes[:, 1], 2.0) & np.isclose(nodes[:, 2], fill) & np.isclose(nodes[:, 0], 0.5))[0])
    M3 = np.kron(np.asarray(m.mass), np.eye(3))
    r_v = nodes + np.array([-0.5, -1.0, -1.0])
    f = -G * M3 @ np.tile([0.0, 1.0, 0.0], len(nodes)) - np.asarray(m.rotation_coupling)[:, 0] \
        + w1 ** 2 * M3 @ np.cross([1.0, 0.0, 0.0], r_v).reshape(-1)
    T1 = 2 * np.pi / w1
    periods = 100 // k
    for scheme, alpha, theta0, tol in (("newmark", 0.0, 2e-3, None), ("newmark", 0.0, 2e-2, None),
                                       ("newmark", 0.0, 2e-2, 1e-7), ("hht", 0.05, 2e-3, None)):
        slope = abs(md.shapes[0] @ f * md.shapes[0, 3 * node + 2]) / (2 * w1) * theta0
        extra = f'[vessel.forced]\ndof = "roll"\namplitude = {theta0!r}\nfrequency = {w1!r}\nramp = 0.0'
        r, wall, loop = run(ship_text(size, fill, mesh, float(periods * T1), float(T1 / 80), scheme, alpha, extra=extra,
                                      sim=f"tolerance = {tol!r}" if tol else ""), fields=True)
        t = np.asarray(r.time)
        D = np.asarray(r.tanks["tank"].displacement)
        eta = D[:, node, 2] - D[0, node, 2]
        amp = []
        done = int(t[-1] / T1 + 1e-9)                 # whole periods computed (fewer if the run failed)
        for j in range(1, done):
            win = (t >= j * T1 - 1e-9) & (t < (j + 1) * T1 - 1e-9)
            X = np.column_stack([np.sin(w1 * t[win]), np.cos(w1 * t[win]), np.ones(win.sum())])
            c = np.linalg.lstsq(X, eta[win], rcond=None)[0]
            amp.append(np.hypot(c[0], c[1]))
        amp = np.array(amp)
        nw = min(10, len(amp) // 2)
        tc = (np.arange(1, len(amp) + 1) + 0.5) * T1
        early = np.polyfit(tc[:nw], amp[:nw], 1)[0]
        late = np.polyfit(tc[-nw:], amp[-nw:], 1)[0]
        note = (f"envelope slope first {nw} periods / linear theory {early / slope:.4f}, last {nw} {late / slope:.4f}; "
                f"amplitude in period {done} {amp[-1]:.3f} m (linear undamped {slope * (done - 0.5) * T1:.3f} m)")
        row(f"roll forced at w1={w1:.4f} {scheme}{' a=' + str(alpha) if alpha else ''} theta0={theta0} {periods} T1"
            + (f" tolerance {tol:g}" if tol else ""),
            r, "n/a (forced)", wall, loop, note)


GEOMETRIES = {
    "shallow h=0.1 m (6,6,1)": ((5.0, 5.0, 4.0), 0.1, (6, 6, 1)),
    "shallow h=0.1 m (5,5,1), aspect 10": ((5.0, 5.0, 4.0), 0.1, (5, 5, 1)),
    "brimful 3.96/4 m (4,4,3)": ((5.0, 5.0, 4.0), 3.96, (4, 4, 3)),
    "elongated (2,20,3), aspect 10": ((5.0, 5.0, 4.0), 3.0, (2, 20, 3)),
    "reference (6,6,4)": ((5.0, 5.0, 4.0), 3.0, (6, 6, 4)),
    "deep one layer (10,10,1), aspect 6": ((5.0, 5.0, 4.0), 3.0, (10, 10, 1)),
    "one element 1x1x0.5 (1,1,1)": ((1.0, 1.0, 1.0), 0.5, (1, 1, 1)),
    "shallow h=0.1 m (6,6,1), tolerance 1e-7": ((5.0, 5.0, 4.0), 0.1, (6, 6, 1)),
    "shallow h=0.1 m (5,5,1), aspect 10, tolerance 1e-7": ((5.0, 5.0, 4.0), 0.1, (5, 5, 1)),
}


def geometry(k):
    duration = 30.0 / k
    peaks = {}
    for name, (size, fill, mesh) in GEOMETRIES.items():
        m = build_liquid(size, fill, mesh, 1000.0, 1500.0, G)
        md = liquid_modes(m, n=16)
        slosh = [i for i, kd in enumerate(md.kind) if kd == "sloshing"]
        exact = analytic_sloshing_table(size[0], size[1], fill, G, 1)[0][0]
        if slosh:
            below = sum(1 for i in range(slosh[0]) if md.kind[i] != "sloshing")
            note = (f"first sloshing {md.omega[slosh[0]]:.4f} rad/s vs {exact:.4f}: {100 * (md.omega[slosh[0]] / exact - 1):+.2f} %; "
                    f"{below} non-sloshing mode(s) below it (lowest {md.omega[0]:.3f} rad/s, {md.kind[0]})")
        else:
            note = f"no sloshing mode among the first 16 (lowest {md.omega[0]:.3f} rad/s, {md.kind[0]}); exact {exact:.4f}"
        sim = "tolerance = 1e-7" if "tolerance 1e-7" in name else ""
        r, wall, loop = run(ship_text(size, fill, mesh, duration, 0.01, sim=sim,
                                      initial="position = [0.0, 0.0, 0.05]\nangular_velocity = [0.05, 0.0, 0.0]"))
        eta = np.asarray(r.probes["B"].displacement)[:, 2] - np.asarray(r.probes["A"].displacement)[:, 2]
        peaks[name] = np.max(np.abs(eta))
        note += f"; max surface elevation at B {peaks[name]:.4f} m"
        row(f"geometry: {name}", r, energy_cols(r), wall, loop, note)


def main():
    ap = parser(__doc__)      # --quick: every case 10x shorter
    ap.add_argument("--only", choices=["long", "stiffness", "resonance", "geometry"])
    a = ap.parse_args()
    k = 10 if a.quick else 1
    print(machine(), flush=True)
    t0 = time.perf_counter()
    for name, fn in (("long", long_runs), ("stiffness", stiffness), ("resonance", resonance), ("geometry", geometry)):
        if a.only in (None, name):
            fn(k)
    head = ("case", "steps", "energy drift |E/E0-1|", "max||q|-1|", "wall s (after 1st chunk)", "note")
    widths = [max(len(str(x[i])) for x in ROWS + [head]) for i in range(5)]
    print(" | ".join(h.ljust(w) for h, w in zip(head, widths + [0])))
    print("-+-".join("-" * w for w in widths + [4]))
    for x in ROWS:
        print(" | ".join(str(c).ljust(w) for c, w in zip(x, widths + [0])))
    print(f"total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
