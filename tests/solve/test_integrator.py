"""Spectral radius and period error of the three schemes on a linear oscillator (the vessel's heave),
measured from the integrator's own step map and compared with the theory of Newmark, HHT and
Chung & Hulbert's generalized-alpha."""
import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest

import equinox as eqx

from jaxslosh.assemble.system import build
from jaxslosh.solve.integrator import State, step
from jaxslosh.solve.schemes import make_scheme
from jaxslosh.solve.linear import make_solver
from jaxslosh.physics.terms import Config

from helpers import vessel_scene

SCENE = vessel_scene()
SYSTEM = build(SCENE).system
STEP = eqx.filter_jit(step)
OMEGA = float(np.sqrt(1025.0 * 9.81 * 200.0 / 4.0e5))   # heave, rad/s


def measured_amplification(scheme, Om):
    """The 3x3 map (z, h v, h^2 a)_n -> (z, h v, h^2 a)_{n+1} of one step, by probing unit states."""
    h = Om / OMEGA
    solver = make_solver(SYSTEM, h, scheme, tol=1e-12, max_iter=20)
    cols = []
    eps = min(1.0, h * h)     # probe amplitude: keep accelerations O(1) (the map is linear)
    for e in np.eye(3) * eps:
        z, v, a = e[0], e[1] / h, e[2] / h ** 2
        c = Config(jnp.array([0.0, 0.0, z]), jnp.array([1.0, 0, 0, 0]), jnp.zeros(0))
        vel = jnp.array([0, 0, v, 0, 0, 0.0])
        acc = jnp.array([0, 0, -OMEGA ** 2 * z, 0, 0, 0.0])
        pa = jnp.array([0, 0, a, 0, 0, 0.0])
        s1, info = STEP(SYSTEM, solver, State(c, vel, acc, pa, jnp.zeros(()), jnp.zeros(0), SYSTEM.states_init()))
        assert bool(info.ok)
        cols.append(np.array([float(s1.c.X0[2]), float(s1.v[2]) * h, float(s1.a[2]) * h ** 2]) / eps)
    return np.array(cols).T


def theory_amplification(sch, Om):
    """Chung & Hulbert (1993): (1-am) a1 + am a0 = -w^2 ((1-af) z1 + af z0) with Newmark's updates;
    written in the scaled state (z, h v, h^2 a)."""
    am, af, beta, gamma = sch.alpha_m, sch.alpha_f, sch.beta, sch.gamma
    w2 = Om ** 2
    D = (1 - am) + w2 * (1 - af) * beta
    # a1 h^2 = (-w2 z0 - w2 (1-af) (h v0) - (am + w2 (1-af) (0.5 - beta)) h^2 a0) / D
    ra = np.array([-w2, -w2 * (1 - af), -(am + w2 * (1 - af) * (0.5 - beta))]) / D
    rz = np.array([1.0, 1.0, 0.5 - beta]) + beta * ra
    rv = np.array([0.0, 1.0, 1 - gamma]) + gamma * ra
    return np.array([rz, rv, ra])


def spectral_radius(A):
    return np.max(np.abs(np.linalg.eigvals(A)))


def principal_phase(A):
    lam = np.linalg.eigvals(A)
    lam = lam[np.argmax(np.abs(lam.imag))]
    return abs(np.angle(lam))


SCHEMES = {"newmark": make_scheme("newmark"), "hht": make_scheme("hht", alpha=0.01),
           "hht-0.1": make_scheme("hht", alpha=0.1), "generalized-alpha": make_scheme("generalized-alpha", rho_inf=0.8)}


@pytest.mark.parametrize("name", list(SCHEMES))
@pytest.mark.parametrize("Om", [0.05, 0.3, 1.0, 3.0, 30.0])
def test_step_map_matches_theory(name, Om):
    sch = SCHEMES[name]
    A = measured_amplification(sch, Om)
    B = theory_amplification(sch, Om)
    np.testing.assert_allclose(A, B, rtol=1e-9, atol=1e-9)


def test_high_frequency_limits():
    Om = 1e6
    assert abs(spectral_radius(measured_amplification(SCHEMES["newmark"], Om)) - 1.0) < 1e-6
    for alpha in (0.01, 0.1):
        rho = spectral_radius(measured_amplification(make_scheme("hht", alpha=alpha), Om))
        assert abs(rho - (1 - alpha) / (1 + alpha)) < 1e-3, (alpha, rho)
    rho = spectral_radius(measured_amplification(SCHEMES["generalized-alpha"], Om))
    assert abs(rho - 0.8) < 1e-3, rho


def test_trapezoidal_period_error_is_exact_closed_form():
    """Trapezoidal rule: |lambda| = 1 and arg(lambda) = 2 atan(Om / 2) exactly."""
    for Om in (0.05, 0.2, 0.8, 2.0):
        A = measured_amplification(SCHEMES["newmark"], Om)
        lam = np.linalg.eigvals(A)
        top = lam[np.argsort(-np.abs(lam))[:2]]
        np.testing.assert_allclose(np.abs(top), 1.0, atol=1e-10)
        assert abs(principal_phase(A) - 2 * np.arctan(Om / 2)) < 1e-10


@pytest.mark.parametrize("name", ["hht", "generalized-alpha"])
def test_second_order_period_error(name):
    """Relative period error (Om / phase - 1) is O(Om^2) at low frequency: the fitted slope is 2."""
    Oms = np.array([0.02, 0.04, 0.08])
    errs = [Om / principal_phase(measured_amplification(SCHEMES[name], Om)) - 1 for Om in Oms]
    slope = np.polyfit(np.log(Oms), np.log(errs), 1)[0]
    assert abs(slope - 2) < 0.1, (slope, errs)


def test_hht_with_alpha_001_never_amplifies():
    for Om in np.logspace(-3, 4, 36):
        assert spectral_radius(measured_amplification(SCHEMES["hht"], Om)) <= 1 + 1e-9, Om


def test_literal_paper_parameters_amplify():
    """gamma = 1/2, beta = 1/4 with alpha = 0.01 (a literal reading of the paper) amplifies; this is
    why the loader refuses alpha != 0 with scheme = "newmark" (PHYSICS.md item 7)."""
    sch = dataclasses.replace(make_scheme("newmark"), alpha_f=0.01)
    radii = [spectral_radius(theory_amplification(sch, Om)) for Om in np.logspace(-1, 3, 30)]
    assert max(radii) > 1.004
