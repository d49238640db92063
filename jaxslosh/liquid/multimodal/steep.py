"""Past the multimodal method's range: the steep-wave damping (docs/guide/nonlinear-sloshing.md,
"Past the method's range").

The N potential modes cos(k_n x) cosh(k_n u) / cosh(k_n h) grow under a crest as exp(k_n zeta). When
the crests are high for the highest one, its surface values under the crest outweigh those elsewhere
and the modal kinetic energy degenerates: one combination of the modal rates, made of the highest
modes and moving the surface away from the crest, carries almost no kinetic energy (the smallest
eigenvalue of the modal mass matrix, over the modal masses at rest, falls to 0.05 and below). Its
acceleration under any load then grows without bound and the Newton iterations fail (the same crests
defeat a higher-order spectral solution with as many modes). The measure of it, the same for every N
(1 x 1 m tank, h = 0.5 m, 6 and 16 modes: the eigenvalue is 0.1, 0.05 and 0.02 at a = 1.6, 2.05 and
2.6 in both), is the crest index

    a = ln( mean over the surface of exp(k_N zeta) ),

a smooth maximum of k_N zeta (0 at rest, k_N^2 <zeta^2> / 2 for small waves). Past a = STEEP_ON the
tank adds an eddy viscosity nu to its modes, each damped as a viscous free-surface wave (Lamb:
2 nu k_n^2 per unit amplitude, a force 4 nu k_n^2 m_n beta_dot_n with m_n the modal mass at rest),
switched on smoothly,

    nu = s(a) STEEP_RATIO omega_N / (2 k_N^2),   s = 0 below STEEP_ON, 1 above STEEP_FULL,
    s(x) = x^3 (10 - 15 x + 6 x^2) between, x = (a - STEEP_ON) / (STEEP_FULL - STEEP_ON),

so that the highest mode's damping ratio is STEEP_RATIO when the switch is full and mode n's is
STEEP_RATIO (k_n / k_N)^2 (omega_N / omega_n): the damping of the higher modes that the multimodal
literature adds for breaking waves and roof impacts (Faltinsen & Timokha, Sloshing, 2009, chapter 8),
with the weights of an eddy viscosity. It bounds the degenerate combination's rate (a damped
first-order motion in place of an unbounded acceleration) and takes energy from the steep waves.
s and its first two derivatives vanish at STEEP_ON: below it the rows are those of the inviscid
method exactly; Newton's Jacobian and gradients through a run stay continuous.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

#: the crest index where the damping starts and where it is full (the modal mass's smallest
#: eigenvalue over its value at rest about 0.05 and 0.01)
STEEP_ON, STEEP_FULL = 2.0, 3.0
#: the highest mode's damping ratio with the switch full
STEEP_RATIO = 0.5


def surface_table(tank):
    """(table (Q, N), weights (Q,)): the elevation per unit beta at the tank's quadrature points on
    its surface, and their weights (a 2-D tank's along its length, a 3-D one's over its base)."""
    t = getattr(tank, "exact", tank)           # the third-order system: its exact tank's tables
    return (t.cx, t.wq) if hasattr(t, "cx") else (t.F, t.wq)


def crest_index(tank, beta):
    """a = ln(mean of exp(k_N zeta) over the surface), k_N the highest mode's wavenumber."""
    table, w = surface_table(tank)
    t = getattr(tank, "exact", tank)
    kN = jnp.max(t.k)
    return jax.nn.logsumexp(kN * (table @ beta), b=w / jnp.sum(w))


def steep_switch(a):
    """0 below STEEP_ON, 1 above STEEP_FULL, C^2 between (zero slope and curvature at both ends)."""
    x = jnp.clip((a - STEEP_ON) / (STEEP_FULL - STEEP_ON), 0.0, 1.0)
    return x ** 3 * (10.0 - 15.0 * x + 6.0 * x * x)


def steep_damping(tank, beta, beta_dot, g):
    """(N,) the damping force on the tank's modal rows (module docstring): zero while a < STEEP_ON."""
    t = getattr(tank, "exact", tank)
    om = t.omega_linear(g)
    kN = jnp.max(t.k)
    omN = jnp.max(om)
    ratio = steep_switch(crest_index(tank, beta)) * STEEP_RATIO * (t.k / kN) ** 2 * (omN / om)
    return 2.0 * ratio * om * t.modal_mass() * beta_dot


def roundoff_floor(tank, beta, g):
    """The round-off level of the tank's scaled modal rows (accelerations, m/s^2) at beta: eps
    omega_N^2 max|beta| exp(2 k_N zeta_max), zeta_max the highest surface at the quadrature points.
    The rows' integrals hold products of cosh(k_n H) / cosh(k_n h) that grow under the crest as
    exp(2 k_N zeta) and cancel: a 1 m tank with 0.5 m of water on 10 modes stalls at 1.2e-8 with a
    0.24 m crest (the estimate 4e-8) and at 1.4e-6 with 0.32 m (9e-6). Below crest index 2 it is under
    3e-11 there, below the default tolerance."""
    table, _ = surface_table(tank)
    t = getattr(tank, "exact", tank)
    kN = jnp.max(t.k)
    omN2 = g * kN * jnp.tanh(kN * t.h)
    eps = jnp.finfo(beta.dtype).eps
    return eps * omN2 * jnp.max(jnp.abs(beta)) * jnp.exp(2.0 * kN * jnp.max(table @ beta))
