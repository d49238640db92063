"""Rigid floating vessel: small-oscillation periods, the torque-free body, buoyancy derivatives."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jaxslosh as js
from jaxslosh.physics.kinematics import G_matrix, quat_from_rpy, rotation_matrix, rpy_from_quat, skew
from jaxslosh.physics.vessel import A_PHI, A_THETA, ConservativeRestoring as Hydro

from helpers import vessel_scene, zero_crossing_period

RHO, G, V, AW, GMT, GML, M = 1025.0, 9.81, 390.0, 200.0, 1.5, 15.0, 4.0e5
IXX, IYY = 5.0e6, 1.5e7


@pytest.mark.parametrize("axis,expected", [
    (0, 2 * np.pi * np.sqrt(IXX / (RHO * G * V * GMT))),
    (1, 2 * np.pi * np.sqrt(IYY / (RHO * G * V * GML))),
])
def test_small_roll_and_pitch_periods(axis, expected):
    omega = [0.0, 0.0, 0.0]
    omega[axis] = 1e-3
    r = js.simulate(vessel_scene(duration=6 * expected, dt=0.01, scheme="newmark", alpha=0.0, omega=omega))
    T = zero_crossing_period(r.time, r.vessel.roll_pitch_yaw[:, axis])
    assert abs(T / expected - 1) < 5e-3, (T, expected)


def test_small_heave_period():
    expected = 2 * np.pi * np.sqrt(M / (RHO * G * AW))
    r = js.simulate(vessel_scene(duration=6 * expected, dt=0.01, position=(0.0, 0.0, 0.05)))
    T = zero_crossing_period(r.time, r.vessel.position[:, 2])
    assert abs(T / expected - 1) < 5e-3, (T, expected)


FREE = """
title = "torque-free body"
[environment]
gravity = 0.0
[simulation]
duration = 400.0
dt = 0.05
scheme = "newmark"
[vessel]
mass = 1.0
inertia = [1.0, 2.0, 3.0]
[vessel.initial]
angular_velocity = [0.1, 0.05, 0.0]
"""


def _euler_reference(t_eval):
    I = np.array([1.0, 2.0, 3.0])

    def f(t, w):
        return -np.cross(w, I * w) / I

    sol = solve_ivp(f, (0, t_eval[-1]), [0.1, 0.05, 0.0], t_eval=t_eval, rtol=1e-12, atol=1e-14, method="DOP853")
    return sol.y.T


@pytest.fixture(scope="module")
def free_runs():
    scene = js.load_scene(FREE)
    return {dt: js.simulate(scene, dt=dt) for dt in (0.05, 0.002)}


@pytest.mark.parametrize("dt", [0.05, 0.002])
def test_torque_free_body_follows_euler_equations(free_runs, dt):
    r = free_runs[dt]
    t = np.asarray(r.time)
    w = np.asarray(r.vessel.angular_velocity)
    ref = _euler_reference(t)
    err = np.max(np.linalg.norm(w - ref, axis=1)) / np.linalg.norm([0.1, 0.05, 0.0])
    assert err < 2e-3, err
    I = np.array([1.0, 2.0, 3.0])
    E = 0.5 * np.sum(I * w * w, axis=1)
    L = np.linalg.norm(I * w, axis=1)
    assert np.max(np.abs(E / E[0] - 1)) < 1e-5
    assert np.max(np.abs(L / L[0] - 1)) < 1e-5
    # no drift: the second half is no further off than the first half allows
    half = len(E) // 2
    assert abs(E[-1] / E[0] - 1) <= 2 * np.max(np.abs(E[:half] / E[0] - 1)) + 1e-12
    # the unit norm of the Euler parameters holds to round-off
    assert np.max(np.abs(np.linalg.norm(np.asarray(r.vessel.quaternion), axis=1) - 1)) < 1e-12


def test_smaller_step_is_never_worse(free_runs):
    """A direct transcription (Newmark on the four Euler parameters with a norm multiplier) gets worse
    as the step shrinks (PHYSICS.md item 8); the Lie-group scheme converges at second order."""
    errs = {}
    for dt, r in free_runs.items():
        ref = _euler_reference(np.asarray(r.time))
        errs[dt] = np.max(np.linalg.norm(np.asarray(r.vessel.angular_velocity) - ref, axis=1))
    assert errs[0.002] < errs[0.05]
    # second order: (0.05 / 0.002)^2 = 625; allow a generous margin for the reference's own error
    assert errs[0.002] < errs[0.05] / 100, errs


def _hydro():
    f = lambda x: jnp.asarray(x, dtype=float)  # noqa: E731
    return Hydro(rho_w=f(RHO), gravity=f(G), waterplane_area=f(AW), displaced_volume=f(V), gm_t=f(GMT), gm_l=f(GML))


def _random_states(n, seed=0):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = rng.normal(size=4)
        yield jnp.asarray(rng.normal(size=3)), jnp.asarray(q / np.linalg.norm(q))


def test_buoyancy_moment_derivative_is_eq_38():
    h = _hydro()
    k = RHO * G * V
    jac = jax.jit(jax.jacfwd(h.moment_paper))       # one program (eager: each operation its own)
    for _, q in _random_states(10):
        J = jac(q)
        q = np.asarray(q)
        eq38 = -2 * k * (np.outer([GMT, 0, 0], q @ np.asarray(A_PHI)) + np.outer([0, GML, 0], q @ np.asarray(A_THETA)))
        np.testing.assert_allclose(J, eq38, rtol=1e-12, atol=1e-12 * k)


def test_buoyancy_force_derivative_is_eq_37():
    """Eq. (35) in the body frame, f_h = -rho g A_w A^T A_Z (X0 - X0^0); its derivative, eq. (37):
    df = -rho g A_w A^T A_Z dX0 + 2 f~_h G dq on unit-norm variations (dq . q = 0). The printed
    eq. (37) writes the second term -rho g A_w f~_h G dq: with omega = 2 G q_dot, the derivative of
    A^T is A^T-rotation by -2 G dq, so the factor is 2 f~_h, not -rho g A_w f~_h (a misprint)."""
    h = _hydro()
    AZ = jnp.diag(jnp.array([0.0, 0.0, 1.0]))

    def f_body(X0, q):
        return rotation_matrix(q).T @ h.force(X0)

    # the derivatives and the rotation in one program (eager, each operation compiles on its own)
    parts = jax.jit(lambda X0, q: (jax.jacfwd(f_body, 0)(X0, q), jax.jacfwd(f_body, 1)(X0, q), f_body(X0, q),
                                   rotation_matrix(q), G_matrix(q)))
    rng = np.random.default_rng(1)
    for X0, q in _random_states(10):
        JX, Jq, f, A, Gq = (np.asarray(x) for x in parts(X0, q))
        np.testing.assert_allclose(JX, -RHO * G * AW * A.T @ np.asarray(AZ), rtol=1e-12, atol=1e-6)
        dq = rng.normal(size=4)
        dq = dq - (dq @ np.asarray(q)) * np.asarray(q)                 # tangent to |q| = 1
        np.testing.assert_allclose(Jq @ dq, 2 * np.asarray(skew(f)) @ Gq @ dq, rtol=1e-10, atol=1e-6)


def test_paper_moment_is_the_restoring_moment_for_pure_roll_and_pitch():
    h = _hydro()
    k = RHO * G * V
    for phi in (0.05, 0.4, 1.2):
        m = h.moment_paper(quat_from_rpy(jnp.array([phi, 0.0, 0.0])))
        np.testing.assert_allclose(m, [-k * GMT * np.sin(phi), 0, 0], rtol=1e-12, atol=1e-6)
        m = h.moment_paper(quat_from_rpy(jnp.array([0.0, phi, 0.0])))
        np.testing.assert_allclose(m, [0, -k * GML * np.sin(phi), 0], rtol=1e-12, atol=1e-6)


def test_conservative_moment_is_minus_gradient_of_potential_and_matches_paper_when_gm_equal():
    f = lambda x: jnp.asarray(x, dtype=float)  # noqa: E731
    h = Hydro(rho_w=f(RHO), gravity=f(G), waterplane_area=f(AW), displaced_volume=f(V), gm_t=f(2.0), gm_l=f(2.0))
    for _, q in _random_states(5, seed=3):
        if rotation_matrix(q)[2, 2] < -0.5:
            continue    # far past capsize the potential's (1 + g_z) denominator is near zero
        np.testing.assert_allclose(h.moment(q), h.moment_paper(q), rtol=1e-9, atol=1e-6)


def test_rotation_helpers_agree():
    for _, q in _random_states(5, seed=4):
        A = rotation_matrix(q)
        np.testing.assert_allclose(A @ A.T, np.eye(3), atol=1e-14)
        np.testing.assert_allclose(rotation_matrix(quat_from_rpy(rpy_from_quat(q))), A, atol=1e-12)
        np.testing.assert_allclose(G_matrix(q) @ q, 0.0, atol=1e-15)


def test_conservative_hydrostatic_rows_are_the_gradient_of_the_restoring_potential():
    """The hand-written rows of the buoyancy term (force and conservative moment) equal the gradient of
    its potential along the step's increments (translations, body-frame rotations on the group)."""
    from jaxslosh.physics.terms import Config, potential_rows
    h = _hydro()
    # the rows and their reference in one program (eager, each operation compiles on its own)
    both = jax.jit(lambda c: (jnp.concatenate([-h.force(c.X0), -h.moment(c.q)]),
                              potential_rows(lambda cc: h.restoring_potential(cc.X0, cc.q), c)))
    for X0, q in _random_states(6, seed=5):
        if rotation_matrix(q)[2, 2] < -0.5:
            continue
        rows, ref = both(Config(X0, q, jnp.zeros(0)))
        np.testing.assert_allclose(rows, ref, rtol=1e-10, atol=1e-9 * float(jnp.max(jnp.abs(ref))))
