"""Past the multimodal method's range: the steep-wave damping (jaxslosh/liquid/multimodal/steep.py,
docs/guide/nonlinear-sloshing.md, "Past the method's range"). A 1 x 1 m tank with 0.5 m of water surged
10 mm at 0.95 of its first frequency: the inviscid method's Newton iterations fail at 9.8 s (6 modes,
dt = 0.02 s) where its crests outgrow its modes; with the damping the run goes on to 12 s and says so
once. Within the range the damping is exactly zero (the existing results are the inviscid method's).
(The damping's names are imported in the tests that use them: the resonant run's test imports only
what was there before it, so that it runs, and fails, on the code before the damping.)"""
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

import jaxslosh as js
from jaxslosh.liquid.multimodal.term import modal_tank
from jaxslosh.run.tofile import run_to_file

L, H, G = 1.0, 0.5, 9.81
W1 = np.sqrt(G * np.pi / L * np.tanh(np.pi * H / L))

RESONANT = f"""
[environment]
gravity = {G}
[simulation]
duration = {{duration}}
dt = 0.02
scheme = "newmark"
[vessel]
mass = 1.0e3
inertia = [1.0e3, 1.0e3, 1.0e3]
[vessel.forced]
dof = "surge"
amplitude = {{amplitude}}
frequency = {0.95 * W1}
[[tanks]]
name = "tank"
origin = [-0.5, -0.5, -0.5]
size = [1.0, 1.0, 1.0]
fill_depth = 0.5
model = "multimodal"
[[probes]]
name = "wall"
tank = "tank"
point = [0.0, 0.5, 0.5]
"""


def _tank(n=6):
    return modal_tank(L, 1.0, H, 1000.0, [-0.5, -0.5, -0.5], n, D=1.0)


def test_resonant_surge_runs_its_12_s_with_one_warning(tmp_path):
    """10 mm at 0.95 omega_1, undamped: the crests outgrow the 6 modes at about 6 s (the inviscid
    method's Newton iterations fail at 9.8 s); the run goes on to its 12 s with the steep-wave damping
    and one warning, which says when the damping took over and that the surface passed the breaking
    slope."""
    scene = js.load_scene(RESONANT.format(duration=12.0, amplitude=0.01))
    report = run_to_file(scene, str(tmp_path / "r.h5"), progress=False)
    assert report.status == "ok" and report.steps == 600, report.status
    assert len(report.warnings) == 1, report.warnings
    msg = report.warnings[0]
    assert "tanks[0]" in msg and "steep-wave damping" in msg and "slope" in msg, msg


def test_surface_past_the_roof_is_said(tmp_path):
    """The same tank filled to 0.95 m of its 1 m, the same surge: the crest passes the roof and the run
    says that the multimodal liquid is outside its validity, naming the tank. (As long a run as the
    resonant one: it takes that run's compiled programs, the depth and the forcing being their inputs.)"""
    text = RESONANT.format(duration=12.0, amplitude=0.01).replace("fill_depth = 0.5", "fill_depth = 0.95")
    report = run_to_file(js.load_scene(text.replace("point = [0.0, 0.5, 0.5]", "point = [0.0, 0.5, 0.95]")),
                         str(tmp_path / "r.h5"), progress=False)
    roof = [w for w in report.warnings if "roof" in w]
    assert len(roof) == 1 and "tanks[0]" in roof[0] and "multimodal" in roof[0], report.warnings


def test_damping_is_zero_within_the_range_and_dissipates_past_it():
    """The force on the modal rows is exactly zero while the crest index is below STEEP_ON (a 0.1 m
    crest on 6 modes of a 1 m tank: index 1.4), grows past it, and always takes energy
    (beta_dot . force >= 0); it is the eddy viscosity's, heavier on the higher modes."""
    from jaxslosh.liquid.multimodal.steep import STEEP_FULL, STEEP_ON, crest_index, steep_damping
    t = _tank()
    rng = np.random.default_rng(0)
    bd = jnp.asarray(rng.normal(size=6))
    low = jnp.array([0.1, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert float(crest_index(t, low)) < STEEP_ON
    assert np.all(np.asarray(steep_damping(t, low, bd, G)) == 0.0)
    high = jnp.array([0.25, 0.06, 0.03, 0.015, 0.007, 0.003])      # the resonant run's crest at 9.8 s
    assert float(crest_index(t, high)) > STEEP_FULL
    f = np.asarray(steep_damping(t, high, bd, G))
    assert float(bd @ f) > 0
    c = f / np.asarray(bd)                  # diagonal: c_n = 2 zeta_n omega_n m_n
    om, m = np.asarray(t.omega_linear(G)), np.asarray(t.modal_mass())
    zeta = c / (2 * om * m)
    np.testing.assert_allclose(zeta[-1], 0.5, rtol=1e-12)
    np.testing.assert_allclose(zeta, 0.5 * (np.arange(1, 7) / 6) ** 2 * om[-1] / om, rtol=1e-12)


def test_switch_is_smooth():
    """Newton linearises the damping: its derivative in beta is continuous through the switch
    (jax against central differences, inside the ramp and at its start)."""
    from jaxslosh.liquid.multimodal.steep import STEEP_FULL, STEEP_ON, crest_index, steep_damping
    t = _tank()
    bd = jnp.linspace(1.0, -0.5, 6)
    base = jnp.array([0.2, 0.05, 0.02, 0.01, 0.005, 0.002])
    for target in (0.5 * (STEEP_ON + STEEP_FULL), STEEP_ON + 1e-3):
        s = brentq(lambda u: float(crest_index(t, u * base)) - target, 0.1, 3.0, xtol=1e-14)
        beta = s * base
        J = np.asarray(jax.jacfwd(steep_damping, argnums=1)(t, beta, bd, G))
        e = 1e-7
        fd = np.stack([(np.asarray(steep_damping(t, beta.at[j].add(e), bd, G))
                        - np.asarray(steep_damping(t, beta.at[j].add(-e), bd, G))) / (2 * e) for j in range(6)], 1)
        scale = np.abs(J).max() + np.abs(np.asarray(steep_damping(t, beta, bd, G))).max()
        np.testing.assert_allclose(J, fd, rtol=1e-4, atol=1e-7 * scale)


def test_watch_reads_the_crest_index_as_the_liquid():
    """The validity watch's crest index is the liquid's (the same points and weights); a frame below
    STEEP_ON says nothing, one past it is said once with the frame's time."""
    from jaxslosh.liquid.multimodal.steep import crest_index
    from jaxslosh.run.validity import Watch, _crest_index, _surface_tables
    scene = js.load_scene(RESONANT.format(duration=1.0, amplitude=0.001))
    ((off, _, Z, w, kN, _),), cuts = _surface_tables(scene)
    assert cuts == {}                  # 6 modes: its rows keep them all
    t = _tank()
    betas = np.array([[0.05, 0.0, 0.0, 0.0, 0.0, 0.0], [0.25, 0.06, 0.03, 0.015, 0.007, 0.003]])
    np.testing.assert_allclose(_crest_index(Z, w, kN, betas), [float(crest_index(t, jnp.asarray(b))) for b in betas],
                               rtol=1e-12)
    watch = Watch(scene)
    z = np.zeros((1, 1, 2))
    watch.update(np.array([0.5]), z, np.zeros(1), betas[:1])
    assert watch.warnings() == []
    watch.update(np.array([0.7]), z, np.zeros(1), betas[1:])
    watch.update(np.array([0.9]), z, np.zeros(1), betas[1:])
    msg = watch.warnings()
    assert len(msg) == 1 and "from t = 0.7 s" in msg[0] and "steep-wave damping" in msg[0], msg


def test_the_watchs_steepness_cut_is_the_liquids():
    """A two-dimensional tank on 16 modes: the watch's cut (whose round-off floor it takes past
    STEEP_FULL) is the liquid's answer, the 10th mode's k = 10 pi / L and omega^2 = g k tanh(k h),
    the highest its rows keep (liquid/multimodal/steep.py); a three-dimensional one has none."""
    from jaxslosh.liquid.multimodal.steep import STEEP_MODES
    from jaxslosh.run.validity import Watch
    text = RESONANT.format(duration=1.0, amplitude=0.001)
    cut = Watch(js.load_scene(text.replace('model = "multimodal"', 'model = "multimodal"\nmodes = 16'))).cut
    k = STEEP_MODES * np.pi / L
    assert STEEP_MODES == 10 and cut == {0: (10, k, G * k * np.tanh(k * H))}
    flat = Watch(js.load_scene(text.replace('model = "multimodal"', 'model = "multimodal"\nflow = "3d"\nmodes = 12')))
    assert flat.cut == {}


def _hos_record(modes, order, dt, amplitude=0.01):
    """The fully nonlinear potential flow (tests/hos_sloshing.py) at the wall, to 0.3 s before it
    breaks down itself (its crests, too, outgrow its modes: 16 modes, fourth order, at 6.1 s)."""
    from hos_sloshing import hos_tank
    w = 0.95 * W1
    with np.errstate(all="ignore"):
        t, z = hos_tank(L, H, G, lambda s: -amplitude * w ** 2 * np.sin(w * s), 12.0, dt, 0.0, modes=modes, order=order)
    bad = ~np.isfinite(z) | (np.abs(z) > H)
    if bad.any():
        keep = t < t[np.argmax(bad)] - 0.3
        t, z = t[keep], z[keep]
    return t, z


def _misfit(t, z, th, zh, a, b):
    """max |z - z_ref| / max |z_ref| over [a, b]."""
    m = (t >= a) & (t <= b)
    zi = np.interp(t[m], th, zh)
    return np.abs(z[m] - zi).max() / np.abs(zi).max()


@pytest.mark.slow
def test_resonant_surge_against_the_fully_nonlinear_potential_flow():
    """The 10 mm resonant surge on 6 modes, dt = 0.01 s, 12 s, against the high-order spectral
    solution (HOS): within 1.5 % of its largest elevation over 1 to 5 s and 2.5 % over 5 s to its
    breakdown (16 modes, fourth order, to 5.8 s; 16 and 12 modes differ there by 3.6 %), where the
    damping has not switched on yet (from 6.1 s); past the switch, to the breakdown of HOS on 12
    modes, third order (7.0 s), within 5 %: the model's share is small while HOS holds. Past 7 s there
    is no converged potential-flow reference (HOS on 8 modes, third order, breaks down at 8.2 s, on
    more modes sooner)."""
    scene = js.load_scene(RESONANT.format(duration=12.0, amplitude=0.01).replace("dt = 0.02", "dt = 0.01"))
    r = js.simulate(scene)
    assert r.status == "ok"
    t, z = np.asarray(r.time), np.asarray(r.probes["wall"].displacement)[:, 2]
    th, zh = _hos_record(16, 4, 0.0025)
    assert 5.5 < th[-1] < 6.5
    assert _misfit(t, z, th, zh, 1.0, 5.0) < 0.015
    assert _misfit(t, z, th, zh, 5.0, th[-1]) < 0.025
    th, zh = _hos_record(12, 3, 0.005)
    assert 6.5 < th[-1] < 7.5
    assert _misfit(t, z, th, zh, 6.1, th[-1]) < 0.05


def test_the_first_modes_of_a_tank_are_the_tank_on_fewer_modes():
    """The truncation's nonlinear part: the first 10 modes sliced from a 16-mode tank (its finer
    quadrature) are the 10-mode tank, rows and all (1e-11)."""
    from jaxslosh.liquid.multimodal.steep import low_tank
    t16, t10 = _tank(16), _tank(10)
    rng = np.random.default_rng(1)
    be, bd = jnp.asarray(0.05 * rng.normal(size=10) / np.arange(1, 11) ** 2), jnp.asarray(0.1 * rng.normal(size=10))
    args = (jnp.array([0.1, 0.0, 0.02]), jnp.array([0.0, 0.2, 0.0]), be, bd, jnp.full(3, 0.3), jnp.full(3, 0.1),
            2.0 * bd, jnp.array([0.1, 0.0, -G]))
    # each side's rows one program (eager, each of their operations compiles on its own)
    rows = eqx.filter_jit(lambda t, a: t.rows(*a))
    for a, b in zip(rows(low_tank(t16, 10), args), rows(t10, args)):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=0, atol=1e-11 * np.abs(np.asarray(b)).max())


def test_truncated_rows_are_the_linearised_rows_with_the_oscillators_damping():
    """The frozen modes' rows are the 16-mode tank's linearised about rest (its mass matrix and
    weight at rest, the vortical flow's share of the pitch inertia) plus the damping of the switch
    full: at rest, under accelerations, a tilted gravity and rates of 1e-6 m/s, the truncated rows
    are the full rows plus that damping (1e-9: the rates' second-order terms)."""
    from jaxslosh.liquid.multimodal.steep import STEEP_MODES, STEEP_RATIO, truncated_rows
    t = _tank(16)
    rng = np.random.default_rng(2)
    bd = jnp.asarray(1e-6 * rng.normal(size=16))
    z3 = jnp.zeros(3)
    args = (z3, z3, jnp.zeros(16), bd, jnp.array([0.3, 0.0, 0.1]), jnp.array([0.0, 0.2, 0.0]),
            jnp.asarray(rng.normal(size=16)), jnp.array([0.5, 0.0, -G]))
    # both sides in one program (eager, each of their operations compiles on its own)
    both = eqx.filter_jit(lambda t, a: (truncated_rows(t, *a, G), t.rows(*a)))(t, args)
    f, m, r = (np.asarray(a) for a in both[0])
    F, Mo, R = (np.asarray(a) for a in both[1])
    om, mm, k = (np.asarray(a) for a in (t.omega_linear(G), t.modal_mass(), t.k))
    c = 2.0 * STEEP_RATIO * (k / k[-1]) ** 2 * (om[-1] / om) * om * mm
    R = R + np.where(np.arange(16) >= STEEP_MODES, c * np.asarray(bd), 0.0)
    assert np.abs(c * np.asarray(bd))[STEEP_MODES:].min() > 1e-7 * np.abs(R).max()     # the damping is seen
    for a, b in ((f, F), (m, Mo), (r, R)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * np.abs(b).max())


def test_third_order_rows_are_unchanged_within_their_margin_and_exact_past_it():
    """The third-order system's rows are its own, bitwise, while the margin of its modal mass stays
    above DEFINITE_ON (a 2 cm first mode: 0.9), and its exact tank's past DEFINITE_FULL (the resonant
    run's state where its Newton iterations failed: margin below 0.1, the exact tank's 0.4)."""
    from jaxslosh.liquid.multimodal.expansion import third_order
    from jaxslosh.liquid.multimodal.steep import (DEFINITE_FULL, DEFINITE_ON, definiteness, steep_damping,
                                                   steep_rows)
    t3 = third_order(_tank(6))
    z3 = jnp.zeros(3)
    bd = jnp.linspace(0.5, -0.2, 6)
    small = jnp.array([0.02, 0.003, 0.001, 0.0, 0.0, 0.0])
    assert float(definiteness(t3, small)) > DEFINITE_ON
    args = (z3, z3, small, bd, jnp.full(3, 0.3), z3, bd, jnp.array([0.0, 0.0, -G]))

    # the steep rows and their references in one program (eager, each operation compiles on its
    # own); the amplitudes are its input, so the steep state below runs the same program
    @eqx.filter_jit
    def sides(t3, args):
        f, m, r = t3.rows(*args)
        return steep_rows(t3, *args, G), (f, m, r + steep_damping(t3, args[2], args[3], G)), \
            steep_rows(t3.exact, *args, G)
    got, own, _ = sides(t3, args)
    for a, b in zip(got, own):
        assert np.array_equal(np.asarray(a), np.asarray(b))
    steep = jnp.array([0.105, 0.012, 0.004, 0.002, 0.001, 0.0005])
    assert float(definiteness(t3, steep)) < DEFINITE_FULL
    args = (z3, z3, steep, bd, jnp.full(3, 0.3), z3, bd, jnp.array([0.0, 0.0, -G]))
    got, _, exact = sides(t3, args)
    for a, b in zip(got, exact):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-13)


@pytest.mark.slow
@pytest.mark.parametrize("tank_keys", ["modes = 16", 'expansion = "third-order"'])
def test_resonant_surge_past_the_range_of_16_modes_and_of_the_third_order_system(tmp_path, tank_keys):
    """The 10 mm resonant surge, 12 s: on 16 modes the rows were round-off past a 0.13 m crest (Newton
    failed at 4.76 s) and the third-order system's modal mass lost its definiteness (3.62 s); with
    the modes above the 10th carried as damped linear oscillators, and the third-order rows blended
    into the exact ones, both run the 12 s with one warning that says so (the fast facts of each stage
    are the tests above)."""
    text = RESONANT.format(duration=12.0, amplitude=0.01).replace('model = "multimodal"',
                                                                  'model = "multimodal"\n' + tank_keys)
    report = run_to_file(js.load_scene(text), str(tmp_path / "r.h5"), progress=False)
    assert report.status == "ok" and report.steps == 600, report.status
    assert len(report.warnings) == 1, report.warnings
    msg = report.warnings[0]
    said = "above the 10th as damped linear oscillators" if "16" in tank_keys else "blended into the exact"
    assert "tanks[0]" in msg and "steep-wave damping" in msg and said in msg, msg
