"""The lumped-mass mooring line (jaxslosh/mooring/lumped.py): its quasi-static limit against an
independent elastic catenary (scipy's fsolve, lumped_reference.py), convergence in the number of
segments, the dynamic tension at wave periods, and energy at a ship's step."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxslosh.mooring import lumped as lm
from lumped_reference import OC3, OC3_HV, oc3_catenary


def oc3_line(segments=20, **kw):
    c = OC3
    kw = dict(dict(diameter=c["diameter"], mass=c["mass"], seabed_z=-c["depth"]), **kw)
    return lm.lumped_line(c["anchor"], c["length"], c["weight"], c["ea"], segments=segments, **kw)


F0 = jnp.array(OC3["fairlead"])
ZERO = jnp.zeros(3)


@jax.jit
def _static_force(line, fair):
    # compiled once per number of segments (eagerly, a few hundred one-operation programs)
    r, ok = lm.static_shape(line, fair)
    return lm.fairlead_force(line, r, jnp.zeros_like(r), fair, ZERO), ok


def static_force(line, fair):
    F, ok = _static_force(line, fair)
    assert bool(ok)
    return np.asarray(F)


def test_reference_is_the_published_oc3_line():
    H, V, LB = oc3_catenary()
    assert abs(H / OC3_HV[0] - 1) < 2e-6 and abs(V / OC3_HV[1] - 1) < 2e-6 and abs(LB - OC3_HV[2]) < 1e-2


def test_static_shape_is_the_catenary_and_converges_in_segments():
    """The static line's force on the fairlead: (-H, 0, -V) of the catenary, within 0.5 % at 20
    segments, and the error falls as the segments are refined."""
    H, V, _ = oc3_catenary()
    errs = []
    for n in (10, 20, 40):
        F = static_force(oc3_line(n), F0)
        err = max(abs(-F[0] / H - 1), abs(-F[2] / V - 1))
        assert abs(F[1]) < 1e-6 * H
        errs.append(err)
    assert errs[1] < 5e-3
    assert errs[0] > errs[1] > errs[2], errs
    assert errs[2] < 1e-3


@pytest.mark.parametrize("dx", [-8.0, 12.0])
def test_static_offset_fairlead(dx):
    """Offsets change the touchdown and the tension by tens of percent: still the catenary within 0.5 %."""
    H, V, _ = oc3_catenary(dx)
    F = static_force(oc3_line(20), F0 + jnp.array([dx, 0.0, 0.0]))
    assert abs(-F[0] / H - 1) < 5e-3 and abs(-F[2] / V - 1) < 5e-3


def surge_run(line, period, amp, h, n, ramp=0.0):
    """The line from rest under a fairlead surge amp sin(w t) (ramp > 0: the offset amp (1 - cos)/2
    over `ramp` s, then held): fairlead tensions (n,) at the steps' ends."""
    r0, _ = lm.static_shape(line, F0)
    w = 2 * np.pi / period if period else 0.0

    def motion(t):
        if ramp:
            tau = jnp.clip(t / ramp, 0.0, 1.0)
            x = amp * 0.5 * (1 - jnp.cos(jnp.pi * tau))
            v = jnp.where(t < ramp, amp * 0.5 * jnp.pi / ramp * jnp.sin(jnp.pi * tau), 0.0)
        else:
            x, v = amp * jnp.sin(w * t), amp * w * jnp.cos(w * t)
        return F0 + jnp.array([1.0, 0.0, 0.0]) * x, jnp.array([1.0, 0.0, 0.0]) * v

    def body(s, t):
        p0, v0 = motion(t)
        p1, v1 = motion(t + h)
        s = lm.advance(line, s, p0, v0, p1, v1, h)
        return s, jnp.linalg.norm(lm.fairlead_force(line, s.r, s.v, p1, v1))

    _, T = jax.jit(lambda s: jax.lax.scan(body, s, jnp.arange(n) * h))(lm.LineState(r0, jnp.zeros_like(r0)))
    return np.asarray(T)


def test_slowly_moved_fairlead_gives_the_catenary_tension():
    """A fairlead moved 10 m over 150 s and held: the catenary's tension there within 0.5 %."""
    T = surge_run(oc3_line(20), None, 10.0, 0.1, 1700, ramp=150.0)
    H, V, _ = oc3_catenary(10.0)
    assert abs(T[-1] / np.hypot(H, V) - 1) < 5e-3
    assert np.all(np.isfinite(T))


def test_wave_period_tension_exceeds_quasi_static():
    """At a 10 s period the tension's range exceeds the quasi-static range between the catenary's
    tensions at the motion's extremes (drag and inertia), by more than half again."""
    amp = 4.0
    T = surge_run(oc3_line(20), 10.0, amp, 0.1, 400)
    dyn = T[200:].max() - T[200:].min()
    qs = np.hypot(*oc3_catenary(amp)[:2]) - np.hypot(*oc3_catenary(-amp)[:2])
    assert dyn > 1.5 * qs, (dyn, qs)


@pytest.mark.parametrize("h", [0.05, 0.1])
def test_undamped_line_keeps_its_energy_at_a_ship_step(h):
    """No drag, internal or seabed damping, the fairlead held: a line set swinging sideways keeps its
    energy (kinetic + elastic + weight + seabed) to 0.5 % of its initial kinetic energy over 60 s of
    20 segments stepped at the ship's h (the sub-steps chosen by the line)."""
    n = 20
    line = oc3_line(n, cd=(0.0, 0.0), internal_damping=0.0, seabed_damping=0.0)
    r, _ = lm.static_shape(line, F0)
    v = jnp.zeros_like(r).at[:, 1].set(jnp.sin(jnp.pi * jnp.arange(1, n) / n))
    s0 = lm.LineState(r, v)

    def energy(s):
        return lm.kinetic(line, s.r, s.v, F0) + lm.potential(line, s.r, F0)

    def body(s, _):
        s = lm.advance(line, s, F0, ZERO, F0, ZERO, h)
        return s, energy(s)

    _, E = jax.jit(lambda s: jax.lax.scan(body, s, None, length=int(round(60.0 / h))))(s0)
    E0, K0 = energy(s0), lm.kinetic(line, r, v, F0)
    assert float(jnp.max(jnp.abs(E - E0))) < 5e-3 * float(K0)


def test_damped_line_loses_energy():
    """With drag, internal and seabed damping the same swing dies out: energy falls below 20 % of
    the initial kinetic energy above the static minimum, and never rises above its start."""
    n = 20
    line = oc3_line(n)
    r, _ = lm.static_shape(line, F0)
    v = jnp.zeros_like(r).at[:, 1].set(jnp.sin(jnp.pi * jnp.arange(1, n) / n))

    def energy(s):
        return lm.kinetic(line, s.r, s.v, F0) + lm.potential(line, s.r, F0)

    def body(s, _):
        s = lm.advance(line, s, F0, ZERO, F0, ZERO, 0.1)
        return s, energy(s)

    s0 = lm.LineState(r, v)
    _, E = jax.jit(lambda s: jax.lax.scan(body, s, None, length=600))(s0)
    Emin, K0 = lm.potential(line, r, F0), lm.kinetic(line, r, v, F0)
    assert float(E[-1] - Emin) < 0.2 * float(K0)
    assert float(jnp.max(E)) <= float(energy(s0)) + 1e-3 * float(K0)


def test_substep_from_the_axial_frequency():
    """The sub-step is below the symplectic Euler's limit 2 / omega of the axial mode
    omega = 2 (N / L) sqrt(EA / m), and halves as the segments double (seabed held out)."""
    a = oc3_line(20, seabed_z=-np.inf, internal_damping=0.0)
    b = oc3_line(40, seabed_z=-np.inf, internal_damping=0.0)
    w = 2 * 20 / OC3["length"] * np.sqrt(OC3["ea"] / OC3["mass"])
    assert a.substep_max == pytest.approx(lm.SAFETY * 2 / w, rel=1e-12)
    assert b.substep_max == pytest.approx(a.substep_max / 2, rel=1e-12)


def test_advance_gradient_matches_finite_differences():
    """d(fairlead tension after a step)/d(fairlead's end position), through the sub-steps' scan."""
    line = oc3_line(10)
    r, _ = lm.static_shape(line, F0)
    s = lm.LineState(r, jnp.zeros_like(r))

    def tension(x):
        p1 = F0 + jnp.array([x, 0.0, 0.0])
        v1 = jnp.array([x / 0.1, 0.0, 0.0])
        s1 = lm.advance(line, s, F0, ZERO, p1, v1, 0.1)
        return jnp.linalg.norm(lm.fairlead_force(line, s1.r, s1.v, p1, v1))

    g = jax.jit(jax.grad(tension))(0.05)
    e = 1e-4
    jtension = jax.jit(tension)         # one compiled program for both ends (not operation by operation)
    fd = (jtension(0.05 + e) - jtension(0.05 - e)) / (2 * e)
    assert float(g) == pytest.approx(float(fd), rel=1e-5)
