"""The multimodal tank's third-order system (tanks.expansion = "third-order",
liquid/multimodal/expansion.py): its backbone against the closed-form third-order standing wave of
Tadjbakhsh & Keller (1960) on both sides of the critical depth h / L = 0.3368, its departure from the
exact system (fourth order in the amplitude), its linear frequencies, a run against the exact tank's
and a gradient through a run."""
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.liquid.multimodal.term import modal_tank
from jaxslosh.liquid.multimodal.expansion import third_order
from jaxslosh.liquid.multimodal.tank3d import cylinder_tank
from test_multimodal3d_tank import BOX, _transfer
from test_multimodal3d_tank import FORCED as FORCED_3D
from test_multimodal import RK4_STAGES
from test_multimodal_tank import FORCED, _amplitude

G = 9.81
Z3 = jnp.zeros(3)
GB = jnp.array([0.0, 0.0, -G])


def _tadjbakhsh_keller(hL):
    """(omega / omega_1 - 1) / (k a)^2 of the third-order standing wave, k = pi / L, a the amplitude of
    its first harmonic (Tadjbakhsh & Keller 1960; zero at h / L = 0.3368)."""
    T = np.tanh(np.pi * hL)
    return (9 / T ** 4 - 12 / T ** 2 - 3 - 2 * T ** 2) / 64


def _acc(t, y):
    n = t.n
    be, bd = y[:n], y[n:]
    r = lambda a: t.rows(Z3, Z3, be, bd, Z3, Z3, a, GB)[2]  # noqa: E731
    z = jnp.zeros(n)
    return jnp.concatenate([bd, -jnp.linalg.solve(jax.jacfwd(r)(z), r(z))])


def _rk4(t, y, dt, steps):
    def step(y, _):
        # the four stages as a loop: the program holds the rows once, not four times
        def stage(carry, c):
            total, k = carry
            k = _acc(t, y + c[0] * dt * k)
            return (total + c[1] * k, k), None
        (total, _), _ = jax.lax.scan(stage, (jnp.zeros_like(y), jnp.zeros_like(y)), RK4_STAGES)
        y = y + dt / 6 * total
        return y, y
    return jax.lax.scan(step, y, None, length=steps)


@eqx.filter_jit
def _standing_wave_period(t, a, steps: int = 160):
    """The period of the free standing wave whose first mode starts at rest at beta_1 = a: the orbit
    is even in time, so the higher modes' starting values and the half period are those that bring
    every modal velocity to rest again (shooting: Newton through the RK4 integration)."""
    n = t.n
    T0 = 2 * jnp.pi / t.omega_linear(G)[0]

    def miss(x):
        y0 = jnp.concatenate([jnp.array([a]), x[:n - 1], jnp.zeros(n)])
        y, _ = _rk4(t, y0, 0.5 * x[-1] / steps, steps)
        return y[n:] * x[-1]
    x = jnp.concatenate([jnp.zeros(n - 1), jnp.array([T0])])
    x = jax.lax.fori_loop(0, 4, lambda i, x: x - jnp.linalg.solve(jax.jacfwd(miss)(x), miss(x)), x)
    return x[-1], jnp.max(jnp.abs(miss(x)))


@pytest.mark.parametrize("hL", [0.5, 0.3, 0.2])
def test_backbone_is_the_third_order_standing_wave(hL):
    """The free oscillation's frequency against amplitude: (omega(a) / omega(0) - 1) / (k a)^2, taken
    to a -> 0 (Richardson, two amplitudes), is Tadjbakhsh & Keller's coefficient, soft above the
    critical depth, hard below it."""
    t = third_order(modal_tank(1.0, 0.1, hL, 1000.0, (0.0, 0.0, 0.0), 4))
    k = np.pi
    T = {}
    for a in (1e-6, 0.01, 0.005):
        # the amplitude an array, not a static argument: one program for the three (and every depth)
        T[a], miss = _standing_wave_period(t, jnp.asarray(a))
        assert miss < 1e-12                       # the orbit closes
    c = {a: (T[1e-6] / T[a] - 1.0) / (k * a) ** 2 for a in (0.01, 0.005)}
    c0 = (4 * c[0.005] - c[0.01]) / 3
    ref = _tadjbakhsh_keller(hL)
    assert (c0 < 0) if hL > 0.3368 else (c0 > 0)
    assert c0 == pytest.approx(ref, rel=5e-3)


@eqx.filter_jit
def _rows(t, a, state):
    """The tank's rows at a state of amplitude a: the body's velocities and accelerations, the modal
    amplitudes, rates and accelerations all a times `state`'s (under gravity tilted by 0.03 rad)."""
    n = t.n
    s = a * state
    return t.rows(s[:3], s[3:6], s[6:6 + n], s[6 + n:6 + 2 * n], s[6 + 2 * n:9 + 2 * n], s[9 + 2 * n:12 + 2 * n],
                  s[12 + 2 * n:], G * jnp.array([0.03, 0.0, -1.0]))


def test_departs_from_the_exact_system_at_fourth_order():
    """The force, moment and modal rows of the two systems at the same state (every velocity,
    acceleration and amplitude of the order a): their difference falls like a^4 (16 times per
    halving), while the rows themselves fall like a."""
    exact = modal_tank(1.0, 0.4, 0.5, 1000.0, (-0.5, -0.2, -0.3), 4, D=0.8)
    poly = third_order(exact)
    state = jnp.asarray(np.random.default_rng(1).normal(size=12 + 3 * 4))
    diffs = {}
    for a in (0.01, 0.005, 0.0025):
        e, p = _rows(exact, a, state), _rows(poly, a, state)
        diffs[a] = np.array([float(jnp.max(jnp.abs(x - y))) for x, y in zip(e[1:], p[1:])])
        scale = np.array([float(jnp.max(jnp.abs(x))) for x in e[1:]])
        assert np.all(diffs[a] < 1e-3 * scale)
    np.testing.assert_allclose(diffs[0.01] / diffs[0.005], 16.0, rtol=0.15)
    np.testing.assert_allclose(diffs[0.005] / diffs[0.0025], 16.0, rtol=0.08)


# (every two-dimensional tank of this file on 4 modes: one program forms their coefficients)
@pytest.mark.parametrize("make", [lambda: modal_tank(1.0, 0.1, 0.4, 1000.0, (0.0, 0.0, 0.0), 4),
                                  lambda: cylinder_tank(0.5, 0.4, 1000.0, (0.0, 0.0, 0.0), 5)])
def test_small_amplitude_frequencies_are_linear_theory(make):
    """The rows' modal mass and stiffness at rest give sqrt(g k tanh(k h)) for every mode."""
    t = third_order(make())
    z = jnp.zeros(t.n)
    r = lambda be, bdd: t.rows(Z3, Z3, be, z, Z3, Z3, bdd, GB)[2]  # noqa: E731
    M, K = jax.jacfwd(lambda a: r(z, a))(z), jax.jacfwd(lambda be: r(be, z))(z)
    w = np.sort(np.sqrt(np.linalg.eigvals(np.linalg.solve(M, K)).real))
    np.testing.assert_allclose(w, np.sort(np.asarray(t.omega_linear(G))), rtol=1e-9)


@pytest.mark.slow      # the three-dimensional coefficients' program and the scene's: a minute of CPU
def test_three_dimensional_box_in_a_scene_is_linear_theory_at_small_amplitude():
    """A `flow = "3d"` box on its third-order system, 1 mm of surge: the steady elevation at the wall
    on the surge axis is linear theory's (within 1 %, as the exact tank's test asks)."""
    w = 4.0
    text = FORCED_3D.format(duration=7.0, dt=0.04, amplitude=0.001, w=w, ratio=0.4, shape=BOX)
    r = js.simulate(js.load_scene(text.replace("modes = 5", 'modes = 5\nexpansion = "third-order"')))
    assert r.status == "ok"
    t, z = np.asarray(r.time), np.asarray(r.probes["wall"].displacement)[:, 2]
    assert _amplitude(t, z, w, 4.5) == pytest.approx(0.001 * _transfer(BOX, w, 0.4), rel=1e-2)


def _wall(text, expansion):
    r = js.simulate(js.load_scene(text.replace("modes = 5", f'modes = 5\nexpansion = "{expansion}"')))
    assert r.status == "ok"
    return np.asarray(r.probes["wall"].displacement)[:, 2]


@pytest.mark.slow
def test_forced_run_near_resonance_is_the_exact_tanks():
    """Surge at 5 rad/s (the first mode at 5.32), 5 % damping, 10 s: at 8 mm crests of 7 cm at the wall
    of a 1 m tank, where the third-order tank's elevation is within 0.1 % rms of the exact tank's; the
    difference falls like the amplitude^4 (two scene programs: the amplitude is an input)."""
    d = {}
    for amp in (0.008, 0.004, 0.002):
        text = FORCED.format(duration=10.0, amplitude=amp, w=5.0, ratio=0.05)
        e, p = _wall(text, "exact"), _wall(text, "third-order")
        d[amp] = np.sqrt(np.mean((e - p) ** 2))
        if amp == 0.008:
            assert e.max() > 0.06
            assert d[amp] < 1e-3 * np.sqrt(np.mean(e ** 2))
    assert 12 < d[0.004] / d[0.002] < 20


def test_expansion_key():
    """`expansion` is read for multimodal tanks only, "exact" by default, and a wrong value names the key."""
    base = FORCED.format(duration=1.0, amplitude=0.001, w=4.0, ratio=0.1)
    assert js.load_scene(base).tanks[0].expansion == "exact"
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.expansion"):
        js.load_scene(base.replace("modes = 5", 'modes = 5\nexpansion = "second-order"'))
    fem = base.replace('model = "multimodal"\nmodes = 5', 'expansion = "third-order"')
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.expansion"):
        js.load_scene(fem)
