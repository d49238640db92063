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

Two stages go further (`steep_rows`). A two-dimensional tank on more than STEEP_MODES modes loses its
rows to round-off before the damping can hold it (the integrals' terms grow as exp(2 k_N zeta) and
cancel: 16 modes of a 1 m tank stall at 1e-7 with a 0.13 m crest); with the same switch s(a) its
rows pass to its first STEEP_MODES modes' (nonlinear, with their own damping) and the modes above
become linear oscillators about rest with the damping full. The third-order system's polynomial
mass matrix loses positive definiteness at moderate crests; as its margin falls its rows pass to
its exact tank's.
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

#: the crest index where the damping starts and where it is full (the modal mass's smallest
#: eigenvalue over its value at rest about 0.05 and 0.01)
STEEP_ON, STEEP_FULL = 2.0, 3.0
#: the highest mode's damping ratio with the switch full
STEEP_RATIO = 0.5
#: a two-dimensional tank on more modes keeps this many nonlinear past its range; those above are
#: handed over to damped linear oscillators (`steep_rows`): 10 modes of the 1 m tank run the resonant
#: case's 12 s with crests of 0.36 m, 16 lose their rows to round-off at 0.13 m
STEEP_MODES = 10
#: the third-order system's margin of positive definiteness (the smallest eigenvalue of its modal mass
#: matrix over the modal masses at rest, a soft minimum) where its rows start to be blended into the
#: exact integrals' and where they are the exact ones (`steep_rows`)
DEFINITE_ON, DEFINITE_FULL = 0.25, 0.1
#: the soft minimum's width
DEFINITE_SOFT = 0.01


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
    return smooth_step((a - STEEP_ON) / (STEEP_FULL - STEEP_ON))


def smooth_step(x):
    """0 below 0, 1 above 1, x^3 (10 - 15 x + 6 x^2) between."""
    x = jnp.clip(x, 0.0, 1.0)
    return x ** 3 * (10.0 - 15.0 * x + 6.0 * x * x)


def steep_damping(tank, beta, beta_dot, g):
    """(N,) the damping force on the tank's modal rows (module docstring): zero while a < STEEP_ON."""
    t = getattr(tank, "exact", tank)
    om = t.omega_linear(g)
    ratio = steep_switch(crest_index(tank, beta)) * _damping_ratio(t, g)
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
    eps = jnp.finfo(beta.dtype).eps

    def floor(kN):
        return eps * g * kN * jnp.tanh(kN * t.h) * jnp.max(jnp.abs(beta)) * jnp.exp(2.0 * kN * jnp.max(table @ beta))
    if hasattr(t, "cx") and t.n > STEEP_MODES:
        # past STEEP_FULL the rows are the first STEEP_MODES modes' (`steep_rows`): their floor
        return jnp.where(crest_index(t, beta) < STEEP_FULL, floor(t.k[-1]), floor(t.k[STEEP_MODES - 1]))
    return floor(jnp.max(t.k))


def low_tank(tank, n):
    """The first n modes of a two-dimensional tank (its quadrature, tables and rest values, sliced:
    each mode's entries are its own)."""
    Bw0, *rest = tank.vort0
    return eqx.tree_at(lambda m: (m.k, m.cx, m.sx, m.cj, m.vort0), tank,
                       (tank.k[:n], tank.cx[:, :n], tank.sx[:, :n], tank.cj[:, :2 * n + 1], (Bw0[:n], *rest)))


def _damping_ratio(t, g):
    """(N,) the damping ratios of the switch full: STEEP_RATIO (k_n / k_N)^2 (omega_N / omega_n)."""
    om = t.omega_linear(g)
    return STEEP_RATIO * (t.k / jnp.max(t.k)) ** 2 * (jnp.max(om) / om)


def truncated_rows(tank, Vb, omega, beta, beta_dot, Vb_dot, alpha, beta_dd, g_b, g):
    """Past the range of a two-dimensional tank on N > STEEP_MODES modes: its first STEEP_MODES modes
    as that tank (nonlinear, with its own steep-wave damping) and the modes above as damped linear
    oscillators, coupled with the vessel through the mass matrix at rest (module docstring of
    `steep_rows`). The first moment is separable in the modes (cosines orthogonal over the length):
    the oscillators' weight and moment are theirs exactly."""
    nc = STEEP_MODES
    lo = low_tank(tank, nc)
    bl, bh = beta[:nc], beta[nc:]
    f, m, rl = lo.rows(Vb, omega, bl, beta_dot[:nc], Vb_dot, alpha, beta_dd[:nc], g_b)
    rl = rl + steep_damping(lo, bl, beta_dot[:nc], g)
    # at rest: the high modes' columns, and their share of the rigid block (the vortical flow's
    # projection on them: a tank on fewer modes has a larger pitch inertia)
    Mf = tank.mass_matrix(jnp.zeros(tank.n))
    M0, dM = Mf[:, 6 + nc:], Mf[:6, :6] - lo.mass_matrix(jnp.zeros(nc))[:6, :6]
    acc = jnp.concatenate([Vb_dot, alpha])
    ph = M0[:6] @ beta_dot[nc:] + dM @ jnp.concatenate([Vb, omega])
    dph = M0[:6] @ beta_dd[nc:] + dM @ acc
    full = jnp.concatenate([jnp.zeros(nc), bh])
    dSh = tank.first_moment(full) - tank.S0
    Ph = jax.jacfwd(tank.first_moment)(full)[:, nc:]                     # dS/dbeta of the high modes
    f = f + dph[:3] + jnp.cross(omega, ph[:3])
    m = m + dph[3:] + jnp.cross(omega, ph[3:]) + jnp.cross(Vb, ph[:3]) - jnp.cross(dSh, g_b)
    mh = tank.modal_mass()[nc:]
    c = 2.0 * _damping_ratio(tank, g)[nc:] * tank.omega_linear(g)[nc:] * mh
    rh = M0[:6].T @ acc + M0[6 + nc:].T @ beta_dd[nc:] - g_b @ Ph + c * beta_dot[nc:]
    return f, m, jnp.concatenate([rl, rh])


def definiteness(tank, beta):
    """The third-order system's margin: a soft minimum (width DEFINITE_SOFT) of the eigenvalues of
    its modal mass matrix scaled by the modal masses at rest (1 at rest)."""
    M = tank.mass_matrix(beta)[6:, 6:]
    d = 1.0 / jnp.sqrt(tank.modal_mass())
    lam = jnp.linalg.eigvalsh(d[:, None] * M * d[None, :])
    return -DEFINITE_SOFT * jax.nn.logsumexp(-lam / DEFINITE_SOFT)


def _blend(s, a, b):
    return jax.tree_util.tree_map(lambda x, y: (1.0 - s) * x + s * y, a, b)


def steep_rows(tank, Vb, omega, beta, beta_dot, Vb_dot, alpha, beta_dd, g_b, g):
    """A tank's rows (f, m, modal rows) with what carries it past its range (docs/guide/
    nonlinear-sloshing.md, "Past the method's range"): the steep-wave damping (`steep_damping`), and

    - a two-dimensional tank on more than STEEP_MODES modes: switched by the same s(a) as the damping,
      its rows blend into `truncated_rows` (the first STEEP_MODES modes nonlinear, those above damped
      linear oscillators): their integrals' terms grow as exp(2 k_N zeta) and cancel, so that past
      a = STEEP_FULL the N-mode rows are round-off (16 modes of a 1 m tank: 1e-7 at a = 4);
    - the third-order system: its rows blend into its exact tank's (with what carries that one past
      its range) as its modal mass matrix's margin (`definiteness`) falls from DEFINITE_ON to
      DEFINITE_FULL (the same C^2 switch): past it the polynomial's inertia loses positive
      definiteness and no damping holds it.

    Each stage is a branch of lax.switch: the rows within the range are computed alone (those of the
    method, unchanged) and a stage's costly rows only where it acts."""
    args = (Vb, omega, beta, beta_dot, Vb_dot, alpha, beta_dd, g_b)

    def own(_):
        f, m, r = tank.rows(*args)
        return f, m, r + steep_damping(tank, beta, beta_dot, g)

    if hasattr(tank, "exact"):
        mu = definiteness(tank, beta)
        x = jnp.clip((DEFINITE_ON - jax.lax.stop_gradient(mu)) / (DEFINITE_ON - DEFINITE_FULL), 0.0, 1.0)
        other = lambda _: steep_rows(tank.exact, *args, g)  # noqa: E731

        def mix(_):
            return _blend(smooth_step((DEFINITE_ON - mu) / (DEFINITE_ON - DEFINITE_FULL)), own(None), other(None))
    elif hasattr(tank, "cx") and tank.n > STEEP_MODES:
        a = crest_index(tank, beta)
        x = jnp.clip((jax.lax.stop_gradient(a) - STEEP_ON) / (STEEP_FULL - STEEP_ON), 0.0, 1.0)
        other = lambda _: truncated_rows(tank, *args, g)  # noqa: E731

        def mix(_):
            return _blend(steep_switch(a), own(None), other(None))
    else:
        return own(None)
    stage = (x > 0.0).astype(jnp.int32) + (x >= 1.0).astype(jnp.int32)
    return jax.lax.switch(stage, (own, mix, other), None)
