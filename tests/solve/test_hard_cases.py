"""Hard cases (issue 7), short versions; the long ones are in benchmarks/validation/stress.py.

- long runs: energy of the paper example (coarse mesh) with HHT and with the trapezoidal rule;
- stiffness: c = 1500 m/s at dt = 0.0025 ... 0.05 s stays bounded, and HHT removes the acoustic
  ringing that the trapezoidal rule keeps after an abrupt start;
- resonance: roll forced at the first sloshing frequency grows linearly, as linear modal theory says;
- geometry: nearly empty, nearly full, elongated elements, a one-element tank.

Compilations cost seconds each, so the runs share scene structures: every run of the paper scene
here takes the same number of steps (one compiled loop per scheme) and the odd geometries share
one scene with four tanks.
"""
import functools
import os

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.liquid.modes import analytic_sloshing_table, liquid_modes

from helpers import zero_crossing_period
from test_coupled import ship_with_tank

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
G = 9.81
N_STEPS = 2000              # every paper-scene run below: one compilation per scheme
MESH = (3, 3, 2)            # coarse version of the paper's 5 x 5 x 5 liquid mesh
ALPHA_STIFF = 0.05          # HHT alpha of the stiffness runs


def paper_scene(scheme="hht", alpha=0.01, dt=0.01, steps=N_STEPS, mesh=MESH, extra=""):
    text = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    for old, new in (("mesh = [5, 5, 5]", f"mesh = {list(mesh)}"), ("duration = 20.0", f"duration = {steps * dt!r}"),
                     ("dt = 0.01", f"dt = {dt!r}"),
                     ('scheme = "hht"\nalpha = 0.01', f'scheme = "{scheme}"\nalpha = {alpha!r}{extra}')):
        assert old in text
        text = text.replace(old, new, 1)
    return js.load_scene(text)


@functools.lru_cache(maxsize=None)
def paper_run(scheme, alpha, dt):
    r = js.simulate(paper_scene(scheme, alpha, dt))
    assert r.status == "ok", r.status
    return r


def energy(r):
    return np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)


def quaternion_drift(r):
    return np.max(np.abs(np.linalg.norm(np.asarray(r.vessel.quaternion), axis=1) - 1.0))


def all_finite(r):
    arrays = [r.time, r.vessel.position, r.vessel.quaternion, r.vessel.angular_velocity, r.energy.kinetic,
              r.energy.potential] + [p.position for p in r.probes.values()] + [t.displacement for t in r.tanks.values()]
    return all(np.all(np.isfinite(np.asarray(a))) for a in arrays)


def spectral_radius(wdt, alpha_m, alpha_f, beta, gamma):
    """Spectral radius of the generalized-alpha step map (Chung & Hulbert) for x'' + w^2 x = 0 at w*dt;
    state (x, dt v, dt^2 a)."""
    W2 = wdt * wdt
    A1 = np.array([[1.0, 0.0, -beta], [0.0, 1.0, -gamma], [(1 - alpha_f) * W2, 0.0, 1 - alpha_m]])
    A0 = np.array([[1.0, 1.0, 0.5 - beta], [0.0, 1.0, 1 - gamma], [-alpha_f * W2, 0.0, -alpha_m]])
    return np.max(np.abs(np.linalg.eigvals(np.linalg.solve(A1, A0))))


def hht(alpha):
    return 0.0, alpha, 0.25 * (1 + alpha) ** 2, 0.5 + alpha


# ------------------------------------------------------------------------------------------------
# Long runs (20 s of the paper example on a 3 x 3 x 2 mesh; 300 s on 5 x 5 x 5 in benchmarks/validation/stress.py)


def test_paper_example_with_hht_loses_energy_slowly_and_never_gains_it():
    """HHT (alpha = 0.01) only dissipates: the total energy never rises above its initial value and
    falls by far less than a percent in 20 s (its damping acts on omega*dt ~ 1, sloshing is at 0.024);
    |q| = 1 to round-off (rotations on the group)."""
    r = paper_run("hht", 0.01, 0.01)
    E = energy(r)
    rel = E / E[0] - 1
    assert np.max(rel) < 1e-9, np.max(rel)                  # no upward drift at any step
    assert -5e-3 < rel[-1] < 0.0, rel[-1]                   # a small loss
    q = len(rel) // 4
    assert np.max(rel[-q:]) < np.max(rel[q:2 * q])          # the energy keeps going down, not back up
    assert quaternion_drift(r) < 1e-12


def test_paper_example_with_the_trapezoidal_rule_conserves_energy_to_second_order():
    """The trapezoidal rule (scheme = "newmark") conserves a linear system's energy exactly; the
    nonlinear coupled motion leaves an O(dt^2) energy error (measured 1.7e-6 relative in 20 s at
    dt = 0.01 on this mesh: NOT within 1e-6), which halving the step divides by 4."""
    r1 = paper_run("newmark", 0.0, 0.01)
    r2 = paper_run("newmark", 0.0, 0.005)
    errs = []
    for r in (r1, r2):
        E = energy(r)
        t = np.asarray(r.time)
        err = np.abs(E / E[0] - 1)
        assert quaternion_drift(r) < 1e-12
        errs.append(np.max(err[t <= 10.0 + 1e-9]))           # the span both runs cover
    full = np.max(np.abs(energy(r1) / energy(r1)[0] - 1))
    assert full < 5e-6, full
    assert 3.0 < errs[0] / errs[1] < 5.0, errs


def test_energy_projection_holds_the_energy_and_leaves_the_motion_to_the_trapezoidal_rule():
    """`simulation.energy_projection`: after each trapezoidal step the velocities are scaled back to
    the initial energy. The energy then holds to round-off (measured 2.7e-15; the plain rule: 1.7e-6),
    and the motion
    moves from the plain rule's by far less than the plain rule's own step error, its distance from
    the run at half the step (measured 2.8e-8 against 8.9e-5 rad/s): the projection only removes
    the O(dt^2) energy error."""
    r1, r2 = paper_run("newmark", 0.0, 0.01), paper_run("newmark", 0.0, 0.005)
    rp = js.simulate(paper_scene("newmark", 0.0, 0.01, extra="\nenergy_projection = true"))
    assert rp.status == "ok", rp.status
    rel = np.abs(energy(rp) / energy(rp)[0] - 1)
    assert np.max(rel) < 1e-12, np.max(rel)
    assert quaternion_drift(rp) < 1e-12
    t = np.asarray(r1.time)
    span = t <= 10.0 + 1e-9                                      # the span the half-step run covers
    w1, wp = (np.asarray(r.vessel.angular_velocity)[span] for r in (r1, rp))
    w2 = np.asarray(r2.vessel.angular_velocity)[::2][:len(w1)]
    step_error, moved = np.max(np.abs(w1 - w2)), np.max(np.abs(wp - w1))
    assert moved < 0.01 * step_error, (moved, step_error)


@pytest.mark.parametrize("extra, why", [("\n[vessel.forced]\ndof = \"roll\"\namplitude = 0.05\nfrequency = 1.0", "forced"),
                                        ("\n[effects]\ncoriolis = false", "coriolis")])
def test_energy_projection_is_refused_where_energy_is_not_conserved(extra, why):
    text = paper_scene("newmark", 0.0).text.replace('alpha = 0.0', 'alpha = 0.0\nenergy_projection = true', 1) + extra
    with pytest.raises(js.SceneError) as info:
        js.load_scene(text)
    assert info.value.key == "simulation.energy_projection" and why in str(info.value), str(info.value)


# ------------------------------------------------------------------------------------------------
# Stiffness: c = 1500 m/s, dt from 0.0025 to 0.05 s (acoustic omega*dt from 2 to 40)

DTS = (0.0025, 0.01, 0.05)


def test_stiff_liquid_stays_bounded_for_every_step_size():
    """Abrupt start (angular velocity (0.1, 0.05, 0) rad/s); 2000 steps at each dt. Both schemes are
    unconditionally stable: the trapezoidal rule keeps the energy to O(dt^2) (measured 9.5e-9, 1.7e-6,
    5.3e-5 at dt = 0.0025, 0.01, 0.05; bound 0.05 dt^2), HHT never adds any, and the peak free-surface
    elevation over the first 5 s agrees with the finest step's (measured within 2 %)."""
    peak = {}
    for scheme, alpha in (("newmark", 0.0), ("hht", ALPHA_STIFF)):
        for dt in DTS:
            r = paper_run(scheme, alpha, dt)
            assert all_finite(r) and quaternion_drift(r) < 1e-12
            rel = energy(r) / energy(r)[0] - 1
            if scheme == "newmark":
                assert np.max(np.abs(rel)) < 0.05 * dt ** 2, (dt, np.max(np.abs(rel)))
            else:
                assert np.max(rel) < 1e-9, (dt, np.max(rel))
            t = np.asarray(r.time)
            eta = np.asarray(r.probes["B"].displacement)[:, 2] - np.asarray(r.probes["A"].displacement)[:, 2]
            peak[scheme, dt] = np.max(np.abs(eta[t <= 5.0 + 1e-9]))
    for scheme in ("newmark", "hht"):
        ref = peak[scheme, DTS[0]]
        assert 0.05 < ref < 1.0, ref                        # the surface moves, and stays below the 1 m freeboard
        for dt in DTS[1:]:
            assert abs(peak[scheme, dt] / ref - 1) < 0.05, (scheme, dt, peak[scheme, dt], ref)


def _acoustic_ringing(r):
    """Energy (J) of the step-to-step oscillation in the liquid's acoustic modes, per step.

    The liquid field is projected on all modes of the tank's liquid (mass-normalised); a fourth
    difference (x[n-2] - 4 x[n-1] + 6 x[n] - 4 x[n+1] + x[n+2]) / 16 keeps an oscillation of
    period 2 steps whole (where the trapezoidal rule puts every mode with omega*dt >> 1) and removes
    the smooth quasi-static response to (omega_load*dt)^4 / 16."""
    m = build_liquid((5.0, 5.0, 4.0), 3.0, MESH, 1000.0, 1500.0, G)
    nf = int(np.asarray(m.free).sum())
    modes = liquid_modes(m, n=nf)
    acoustic = np.array([k == "acoustic" for k in modes.kind])
    assert acoustic.sum() >= 5 and modes.omega[acoustic].min() > 500.0
    M3 = np.kron(np.asarray(m.mass), np.eye(3))
    D = np.asarray(r.tanks["tank"].displacement)
    D = D.reshape(D.shape[0], -1)
    eta = (D - D[0]) @ (modes.shapes @ M3).T
    d4 = (eta[4:] - 4 * eta[3:-1] + 6 * eta[2:-2] - 4 * eta[1:-3] + eta[:-4]) / 16
    w = modes.omega[acoustic]
    return 0.5 * np.sum(w ** 2 * d4[:, acoustic] ** 2, axis=1), w


def test_hht_removes_the_acoustic_ringing_that_the_trapezoidal_rule_keeps():
    """After the abrupt start, the acoustic modes (826 rad/s and up: omega*dt = 2 to 220) ring at
    the step-to-step period. The trapezoidal rule keeps that ringing for the whole run (energy
    constant to a factor 3); HHT (alpha = 0.05) damps it as its spectral radius rho(omega dt) says:
    the ringing energy of steps 20-40 over that of steps 0-20 lies between 0.5 min(rho)^40 and
    1.5 max(rho)^40 over the acoustic modes (at dt = 0.01: measured 0.031, bounds 0.009 and 0.047),
    and in the second half of the run it is below 1e-4 of the trapezoidal level (measured 1e-5 to
    1e-6)."""
    for dt in DTS:
        ring_n, w = _acoustic_ringing(paper_run("newmark", 0.0, dt))
        ring_h, _ = _acoustic_ringing(paper_run("hht", ALPHA_STIFF, dt))
        early_n, late_n = np.mean(ring_n[:20]), np.max(ring_n[len(ring_n) // 2:])
        assert early_n > 1e-8, early_n                           # there is ringing to remove
        assert 0.3 < np.mean(ring_n[-200:]) / early_n < 3.0      # undamped: it persists
        late_h = np.max(ring_h[len(ring_h) // 2:])
        assert late_h < 1e-4 * late_n, (dt, late_h, late_n)
        if dt == 0.01:
            # decay over the first 20 steps against theory
            rho = [spectral_radius(wi * dt, *hht(ALPHA_STIFF)) for wi in w]
            measured = np.mean(ring_h[20:40]) / np.mean(ring_h[:20])
            assert 0.5 * min(rho) ** 40 < measured < 1.5 * max(rho) ** 40, (measured, min(rho) ** 40, max(rho) ** 40)


def test_newmark_with_alpha_is_refused_and_the_message_says_why():
    """gamma = 1/2, beta = 1/4 with alpha != 0 (a literal reading of the paper) amplifies: its
    spectral radius exceeds 1 (PHYSICS.md item 7); the loader refuses it, says so and names the fix."""
    scene = paper_scene("newmark", 0.0, 0.01).text.replace("alpha = 0.0", "alpha = 0.05")
    with pytest.raises(js.SceneError) as e:
        js.load_scene(scene)
    msg = str(e.value)
    assert msg.startswith("simulation.alpha") and "\n" not in msg
    assert "amplif" in msg and "trapezoidal" in msg and 'scheme = "hht"' in msg and "1/2 + alpha" in msg, msg
    # the claim: HHT's alpha with the trapezoidal gamma and beta has spectral radius > 1 somewhere
    rho = max(spectral_radius(wdt, 0.0, 0.05, 0.25, 0.5) for wdt in np.geomspace(0.1, 100, 60))
    assert rho > 1.001, rho
    # and the consistent HHT coefficients do not
    assert max(spectral_radius(wdt, *hht(0.05)) for wdt in np.geomspace(0.01, 1000, 60)) <= 1 + 1e-12


# ------------------------------------------------------------------------------------------------
# Resonance: roll forced at the first sloshing frequency

RES_SIZE, RES_FILL, RES_MESH = (1.0, 2.0, 2.0), 1.0, (2, 8, 4)
RES_PERIODS, RES_STEPS_PER_PERIOD = 16, 80


def _resonance_linear_theory():
    """Modal superposition of the linear liquid forced from rest by theta = theta0 sin(w1 t) about the
    vessel's x axis (the tank bottom 1 m below the COG): f(t) = f_a theta'' + f_th theta with
    f_a = -M (e_x x r) (Euler force), f_th = -g M e_y - C e_x (gravity turning, rotation penalty).
    Mode i (mass-normalised, frequency w_i) has F_i = phi_i . (f_th - w1^2 f_a) theta0 and, from rest,
    eta_1 = F_1 / (2 w1^2) (sin w1 t - w1 t cos w1 t): an envelope F_1 t / (2 w1) that grows linearly;
    eta_i = F_i / (w_i^2 - w1^2) (sin w1 t - w1 / w_i sin w_i t) for the others."""
    a, b, _ = RES_SIZE
    m = build_liquid(RES_SIZE, RES_FILL, RES_MESH, 1000.0, 1500.0, G)
    nf = int(np.asarray(m.free).sum())
    md = liquid_modes(m, n=nf)
    assert md.kind[0] == "sloshing"
    nodes = np.asarray(m.nodes)
    node = int(np.flatnonzero(np.isclose(nodes[:, 1], b) & np.isclose(nodes[:, 2], RES_FILL)
                              & np.isclose(nodes[:, 0], a / 2))[0])
    M3 = np.kron(np.asarray(m.mass), np.eye(3))
    r_vessel = nodes + np.array([-a / 2, -b / 2, -1.0])
    f_a = -M3 @ np.cross([1.0, 0.0, 0.0], r_vessel).reshape(-1)
    f_th = -G * M3 @ np.tile([0.0, 1.0, 0.0], len(nodes)) - np.asarray(m.rotation_coupling)[:, 0]
    w1 = float(md.omega[0])
    F = md.shapes @ (f_th - w1 ** 2 * f_a)                   # per unit theta0

    def elevation(t, theta0):
        w = md.omega
        eta = np.empty((len(t), len(w)))
        eta[:, 0] = F[0] / (2 * w1 ** 2) * (np.sin(w1 * t) - w1 * t * np.cos(w1 * t))
        for i in range(1, len(w)):
            eta[:, i] = F[i] / (w[i] ** 2 - w1 ** 2) * (np.sin(w1 * t) - w1 / w[i] * np.sin(w[i] * t))
        return theta0 * (eta @ md.shapes[:, 3 * node + 2])

    slope = abs(F[0] * md.shapes[0, 3 * node + 2]) / (2 * w1)   # envelope growth per unit theta0, m/s
    return w1, node, elevation, slope


def _resonance_run(w1, theta0):
    T1 = 2 * np.pi / w1
    extra = f'[vessel.forced]\ndof = "roll"\namplitude = {theta0!r}\nfrequency = {w1!r}\nramp = 0.0'
    scene = ship_with_tank(mesh=RES_MESH, size=RES_SIZE, fill=RES_FILL, duration=float(RES_PERIODS * T1),
                           dt=float(T1 / RES_STEPS_PER_PERIOD), scheme="newmark", alpha=0.0, extra_vessel=extra)
    r = js.simulate(scene)
    assert r.status == "ok" and all_finite(r)
    return r


def _envelope(t, x, w1):
    """Amplitude at w1 in each whole period after the first (least squares: sin, cos, offset)."""
    T1 = 2 * np.pi / w1
    tc, amp = [], []
    for k in range(1, int(t[-1] / T1 + 1e-9)):
        win = (t >= k * T1 - 1e-9) & (t < (k + 1) * T1 - 1e-9)
        X = np.column_stack([np.sin(w1 * t[win]), np.cos(w1 * t[win]), np.ones(win.sum())])
        c = np.linalg.lstsq(X, x[win], rcond=None)[0]
        tc.append((k + 0.5) * T1)
        amp.append(np.hypot(c[0], c[1]))
    return np.array(tc), np.array(amp)


def test_roll_forced_at_the_first_sloshing_frequency_grows_as_linear_theory_says():
    """Undamped resonance grows linearly in time: the envelope slope of the wall elevation against
    the linear modal prediction F_1 phi_1 / (2 w1) (measured within 0.01 %), the whole time history
    against the modal superposition (within 5 % of its peak: the trapezoidal rule's period error),
    and proportional to the forcing amplitude (x10 gives x10, even at 0.02 rad, 0.24 m elevation)."""
    w1, node, elevation, slope = _resonance_linear_theory()
    eta = {}
    for theta0 in (2e-4, 2e-3, 2e-2):
        r = _resonance_run(w1, theta0)
        t = np.asarray(r.time)
        D = np.asarray(r.tanks["tank"].displacement)
        eta[theta0] = D[:, node, 2] - D[0, node, 2]
        tc, amp = _envelope(t, eta[theta0], w1)
        fit = np.polyfit(tc, amp, 1)
        assert abs(fit[0] / (slope * theta0) - 1) < 0.02, (theta0, fit[0], slope * theta0)
        # linear, not exponential: the growth in the last periods is that of the first ones
        growth = np.diff(amp)
        assert abs(np.mean(growth[-4:]) / np.mean(growth[:4]) - 1) < 0.05, growth
        if theta0 == 2e-3:
            lin = elevation(t, theta0)
            assert np.max(np.abs(eta[theta0] - lin)) < 0.05 * np.max(np.abs(lin))
    peak = {k: np.max(np.abs(v)) for k, v in eta.items()}
    assert abs(peak[2e-3] / peak[2e-4] / 10 - 1) < 0.005, peak
    assert abs(peak[2e-2] / peak[2e-3] / 10 - 1) < 0.02, peak
    assert peak[2e-2] < 0.5                                   # bounded by linear growth: 16 periods, 0.24 m


# ------------------------------------------------------------------------------------------------
# Geometry: nearly empty, nearly full, elongated elements, one element

GEOMETRIES = {
    # name: (size, fill depth, mesh); every tank is centred under the COG (they overlap in space,
    # which the model allows: each liquid moves on its own), so that heave couples with nothing
    "shallow": ((5.0, 5.0, 4.0), 0.25, (6, 6, 1)),      # one element layer, 6 % full, elements 0.83 x 0.83 x 0.25
    "brimful": ((5.0, 5.0, 4.0), 3.96, (4, 4, 3)),      # 99 % full
    "elongated": ((5.0, 2.5, 4.0), 3.0, (2, 10, 3)),    # elements 2.5 x 0.25 x 1 m: aspect 10
    "single": ((1.0, 1.0, 1.0), 0.5, (1, 1, 1)),        # one hexahedron
}


def _first_sloshing(size, fill, mesh):
    m = build_liquid(size, fill, mesh, 1000.0, 1500.0, G)
    md = liquid_modes(m, n=12)
    slosh = [w for w, k in zip(md.omega, md.kind) if k == "sloshing"]
    return md, slosh


@pytest.mark.parametrize("size,fill,mesh,tol", [
    ((5.0, 5.0, 4.0), 0.1, (6, 6, 1), 0.02),       # 2.5 % full, one layer of 0.83 x 0.83 x 0.1 m: +1.32 %
    ((5.0, 5.0, 4.0), 0.1, (5, 5, 1), 0.025),      # the same, elements of aspect 10: +1.92 %
    ((5.0, 5.0, 4.0), 0.25, (6, 6, 1), 0.02),      # 6 % full, one layer: +1.39 %
    ((5.0, 5.0, 4.0), 3.96, (4, 4, 3), 0.005),     # 99 % full: +0.25 %
    ((5.0, 5.0, 4.0), 4.0, (4, 4, 3), 0.005),      # full to the lid: +0.23 %
    ((5.0, 5.0, 4.0), 3.0, (2, 20, 3), 0.005),     # elements 2.5 x 0.25 x 1 m (aspect 10): +0.15 %
], ids=["empty-0.1", "empty-0.1-aspect10", "empty-0.25", "brimful", "full", "elongated"])
def test_first_sloshing_frequency_of_odd_geometries(size, fill, mesh, tol):
    """The lowest mode classified as sloshing against omega^2 = g k tanh(k h), k = pi / a (the
    measured errors are beside the cases). Not asserted: which modes lie below it -- with the
    elongated elements three spurious (surface hourglass) modes do, at 1.24, 2.40 and 2.41 rad/s.
    The one-element tank has no sloshing mode at all (liquid.py: a direction with one element
    carries none); it is only run, below."""
    _, slosh = _first_sloshing(size, fill, mesh)
    exact = analytic_sloshing_table(size[0], size[1], fill, G, 1)[0][0]
    assert slosh, "no sloshing mode found"
    err = slosh[0] / exact - 1
    print(f"{size} h={fill} {mesh}: first sloshing {slosh[0]:.5f} rad/s, exact {exact:.5f}, error {100 * err:+.3f} %")
    assert abs(err) < tol, (slosh[0], exact)


def test_odd_geometries_run_and_carry_their_liquid():
    """All four tanks in one vessel (one compilation): heaved 5 cm and rolled, the run finishes with
    finite values, the trapezoidal rule keeps the energy, the heave period counts every tank's
    liquid, and the liquid's vertical displacement stays small (below 0.2 m; measured 0.03-0.07 m)."""
    tanks, probes, mass_liquid = [], [], 0.0
    for name, (size, fill, mesh) in GEOMETRIES.items():
        tanks.append(f'[[tanks]]\nname = "{name}"\norigin = [{-size[0] / 2!r}, {-size[1] / 2!r}, -1.0]\nsize = {list(size)}\n'
                     f"fill_depth = {fill!r}\nmesh = {list(mesh)}\n")
        probes.append(f'[[probes]]\nname = "{name}"\ntank = "{name}"\npoint = [{size[0]!r}, {size[1] / 2!r}, {fill!r}]\n')
        mass_liquid += 1000.0 * size[0] * size[1] * fill
    m_vessel, Aw = 4.0e5, 200.0
    text = f"""
title = "odd tanks"
[simulation]
duration = 10.0
dt = 0.01
scheme = "newmark"
[vessel]
mass = {m_vessel!r}
inertia = [4.9e6, 1.45e7, 1.6e7]
[vessel.hydrostatics]
waterplane_area = {Aw!r}
displaced_volume = {(m_vessel + mass_liquid) / 1025.0!r}
gm_t = 1.67
gm_l = 14.2
[vessel.initial]
position = [0.0, 0.0, 0.05]
angular_velocity = [0.02, 0.0, 0.0]
""" + "".join(tanks) + "".join(probes)
    r = js.simulate(js.load_scene(text))
    assert r.status == "ok" and all_finite(r), r.status
    assert quaternion_drift(r) < 1e-12
    E = energy(r)
    assert np.max(np.abs(E / E[0] - 1)) < 1e-5
    T = zero_crossing_period(r.time, np.asarray(r.vessel.position)[:, 2])
    expected = 2 * np.pi * np.sqrt((m_vessel + mass_liquid) / (1025.0 * G * Aw))
    assert abs(T / expected - 1) < 0.01, (T, expected)
    for name, (size, fill, mesh) in GEOMETRIES.items():
        D = np.asarray(r.tanks[name].displacement)
        rise = np.max(np.abs(D[:, :, 2] - D[:1, :, 2]))
        assert rise < 0.2, (name, rise)
