"""Print the validation tables (docs/validation.md): what was checked against what, with measured numbers.

    python -m benchmarks.validation.validation [--quick]

Each row is computed here, in one run (the tests assert the same facts with tolerances). The
references and scenes the tests share are imported from tests/ (run from the repository root);
the liquid's blocks and modes from jaxslosh's fem/ and assemble/ (the quantities checked have no
public API). `--quick`: the rows that take seconds (no waves).
"""
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

import jaxslosh as js
from jaxslosh.liquid.modes import effective_roll_inertia
from jaxslosh.assemble.system import build
from jaxslosh.physics.kinematics import rotation_matrix
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.liquid.modes import analytic_sloshing_omegas, liquid_modes
from benchmarks.harness import ROOT, Table, machine, parser, scene
from tests.helpers import vessel_scene, zero_crossing_period


def ship_with_tank(mesh, rpy):
    """The paper example at rest, its tank's liquid the stabilized element on `mesh`, heeled by `rpy`."""
    return js.scene_with(scene("paper_ship_tank"), {
        "tanks[0].mesh": list(mesh), "tanks[0].fluid.element": "stabilized", "tanks[0].fluid.sound_speed": None,
        "vessel.initial.angular_velocity": [0.0, 0.0, 0.0], "vessel.initial.roll_pitch_yaw": list(rpy)})

rows = []


def row(check, reference, measured):
    rows.append((check, reference, measured))
    print(f"  {check}: {measured}", file=sys.stderr, flush=True)       # progress; the table at the end
    sys.stdout.flush()


def vessel_periods():
    I, V, GM, rho, g = 5.0e6, 390.0, 1.5, 1025.0, 9.81
    T = 2 * np.pi * np.sqrt(I / (rho * g * V * GM))
    r = js.simulate(vessel_scene(duration=6 * T, scheme="newmark", alpha=0.0, omega=(1e-3, 0, 0)))
    Tm = zero_crossing_period(r.time, r.vessel.roll_pitch_yaw[:, 0])
    row("small roll period, vessel alone", f"2 pi sqrt(I/(rho g V GM_T)) = {T:.4f} s", f"{Tm:.4f} s ({100 * (Tm / T - 1):+.3f} %)")
    Th = 2 * np.pi * np.sqrt(4.0e5 / (rho * g * 200.0))
    r = js.simulate(vessel_scene(duration=6 * Th, position=(0, 0, 0.05)))
    Tm = zero_crossing_period(r.time, r.vessel.position[:, 2])
    row("small heave period, vessel alone (HHT 0.01)", f"2 pi sqrt(m/(rho g A_w)) = {Th:.4f} s", f"{Tm:.4f} s ({100 * (Tm / Th - 1):+.3f} %)")


def torque_free():
    text = open(os.path.join(ROOT, "tests", "physics", "test_vessel.py")).read()
    free = text.split('FREE = """')[1].split('"""')[0]
    scene = js.load_scene(free)
    I = np.array([1.0, 2.0, 3.0])
    for dt in (0.05, 0.002):
        r = js.simulate(scene, dt=dt)
        t = np.asarray(r.time)
        w = np.asarray(r.vessel.angular_velocity)
        ref = solve_ivp(lambda _, x: -np.cross(x, I * x) / I, (0, t[-1]), [0.1, 0.05, 0.0], t_eval=t,
                        rtol=1e-12, atol=1e-14, method="DOP853").y.T
        err = np.max(np.linalg.norm(w - ref, axis=1)) / np.linalg.norm([0.1, 0.05])
        E = 0.5 * np.sum(I * w * w, axis=1)
        row(f"torque-free body I = (1, 2, 3), 400 s, dt = {dt}", "Euler's equations (DOP853, rtol 1e-12)",
            f"omega error {err:.2e} relative; energy {np.max(np.abs(E / E[0] - 1)):.1e}")


def sloshing():
    a, b, h, g = 5.0, 5.0, 3.0, 9.81
    ref = analytic_sloshing_omegas(a, b, h, g, 8)
    distinct = [ref[0], ref[2], ref[3], ref[5]]
    for mesh in ((5, 5, 5), (10, 10, 6)):
        m = liquid_modes(build_liquid((a, b, 4.0), h, mesh, 1000.0, 1500.0, g), n=12)
        w = [x for x, k in zip(m.omega, m.kind) if k == "sloshing"]
        got = [w[0], w[2], w[3], w[5]]
        errs = ", ".join(f"{100 * (x / y - 1):+.2f}" for x, y in zip(got, distinct))
        row(f"sloshing 5 x 5 x 3 m tank, mesh {mesh}", "g k tanh(k h): 2.4261, 2.9382, 3.5092, 3.7117 rad/s",
            f"errors {errs} %")
    m = liquid_modes(build_liquid((0.8, 0.1, 0.5), 0.3, (16, 2, 6), 1000.0, 1400.0, g), n=8)
    f = [x / (2 * np.pi) for x, k in zip(m.omega, m.kind) if k == "sloshing"][:4]
    pub = [0.8983, 1.3845, 1.7095, 1.9755]
    row("Code_Aster slab 0.8 x 0.1 x 0.3 m, mesh 16 x 2 x 6", "V8.21.101: 0.8983, 1.3845, 1.7095, 1.9755 Hz",
        "errors " + ", ".join(f"{100 * (x / y - 1):+.2f}" for x, y in zip(f, pub)) + " %")


def free_surface_moment():
    phi = 0.02
    for mesh in ((5, 5, 5), (10, 10, 6)):
        b = build(ship_with_tank(mesh=mesh, rpy=(phi, 0, 0)))
        L = b.system.liquid
        D = np.asarray(L.full(b.c0.d))
        A = np.asarray(rotation_matrix(b.c0.q))
        m = np.cross(np.asarray(L.m_nodes) @ D, A.T @ np.array([0, 0, -9.81]))[0]
        ref = 1000 * 9.81 * 5 * 125 / 12 * np.sin(phi)
        row(f"static heel 0.02 rad, free-surface moment, mesh {mesh}", "rho g i_T sin(phi)",
            f"{100 * (m / ref - 1):+.2f} %")


def inertia():
    for size, mesh, sj in (((2.0, 4.0, 4.0), (2, 16, 16), 0.1565), ((2.0, 8.0, 4.0), (2, 32, 8), 0.45)):
        I_eff, _, I_fr = effective_roll_inertia(size, mesh)
        I_rel, _, _ = effective_roll_inertia(size, mesh, absolute_rotation=False)
        I_pap, _, _ = effective_roll_inertia(size, mesh, element="paper")
        row(f"effective roll inertia, closed {size[1]:g} x {size[2]:g} m section",
            f"Stokes-Joukowski {sj} of frozen",
            f"default {I_eff / I_fr:.4f}; relative-rotation penalty {I_rel / I_fr:.4f}; paper form {I_pap / I_fr:.4f}")


def waves():
    """The rows of tests/hydro/test_waves.py: the regular-wave RAO and the Cummins memory, Capytaine's box."""
    from tests.hydro import test_waves as tw
    from jaxslosh.hydro.capytaine import capytaine_hydrostatics
    from jaxslosh.scene.types import BoxHull
    w, Bv = 0.9, [0.0, 0.0, 0.0, 8.0e5, 0.0, 0.0]
    scene = tw.box_scene(tw.regular(w), duration=180.0, extra_hydro=f'viscous_damping = {Bv}\nexcitation = "froude-krylov"\n')
    r = js.simulate(scene)
    t = np.asarray(r.time)
    k = t > 100.0
    roll = tw._harmonic(t[k], np.asarray(r.vessel.roll_pitch_yaw)[k, 0], w)
    X = tw.froude_krylov_box(w, np.pi / 2, tw.L, tw.B, tw.T, tw.KG, tw.RHO, tw.G)[0]
    ref = 0.2 * tw._reference(scene, w, X, viscous=np.diag(Bv)[None])[3]
    row("regular beam wave 0.2 m, 0.9 rad/s, box 20 x 10 x 2 m, Froude-Krylov", "linear RAO (6 dof, Capytaine A(w), B(w))",
        f"roll {abs(roll):.5f} rad vs {abs(ref):.5f} rad ({100 * (abs(roll) / abs(ref) - 1):+.2f} %)")
    M0, Bv = 5.0e4, [0.0, 0.0, 0.0, 6.0e5, 0.0, 0.0]
    exc = (f"headings = [1.5707963267948966]\nviscous_damping = {Bv}\n"
           f"excitation_amplitude = {[[0, 0, 0, M0, 0, 0]] * 20}\nexcitation_phase = {[[0.0] * 6] * 20}\n")
    errs = []
    for w in (0.7, 0.9, 1.1, 1.3, 1.5):
        scene = tw.box_scene(tw.regular(w, amplitude=1.0), duration=240.0, extra_hydro=exc, excitation=False)
        r = js.simulate(scene)
        t = np.asarray(r.time)
        k = t > 140.0
        roll = tw._harmonic(t[k], np.asarray(r.vessel.roll_pitch_yaw)[k, 0], w)
        ref = tw._reference(scene, w, np.array([0, 0, 0, M0, 0, 0], dtype=complex), viscous=np.diag(Bv)[None])[3]
        errs.append(f"{100 * (abs(roll) / abs(ref) - 1):+.2f}")
    row("Cummins memory, harmonic roll moment at 0.7, 0.9, 1.1, 1.3, 1.5 rad/s", "frequency domain with A(w), B(w)",
        "amplitude errors " + ", ".join(errs) + " %")
    hs = capytaine_hydrostatics(BoxHull(length=20.0, beam=10.0, draft=2.0, kg=2.5))
    closed = {"displaced_volume": 400.0, "waterplane_area": 200.0, "bm_t": 100 / 24, "bm_l": 400 / 24}
    row("Capytaine hydrostatics, box 20 x 10 x 2 m", "V, A_w, BM_T = B^2/12T, BM_L = L^2/12T",
        "errors " + ", ".join(f"{100 * (hs[k] / v - 1):+.3f}" for k, v in closed.items()) + " %")


def main():
    a = parser(__doc__).parse_args()
    t0 = time.perf_counter()
    vessel_periods()
    torque_free()
    sloshing()
    free_surface_moment()
    inertia()
    if not a.quick:
        waves()
    table = Table(("check", "{}"), ("reference", "{}"), ("measured", "{}"))
    for r in rows:
        table.add(*r)
    table.print(a.markdown)
    print(f"\n({time.perf_counter() - t0:.0f} s; {machine()})")


if __name__ == "__main__":
    main()
