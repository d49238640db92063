"""Implicit time integration: Newmark, HHT-alpha and generalized-alpha on the Lie group.

One family covers the three schemes of the scene file: the generalized-alpha method in the form of
Arnold & Bruls (2007) and Bruls, Cardona & Arnold (2012), where the equations of motion hold exactly
at t_{n+1} and a pseudo-acceleration `a` carries the numerical dissipation:

    (1 - alpha_m) a_{n+1} + alpha_m a_n = (1 - alpha_f) acc_{n+1} + alpha_f acc_n
    Delta   = h v_n + h^2 (1/2 - beta) a_n + h^2 beta a_{n+1}
    v_{n+1} = v_n + h (1 - gamma) a_n + h gamma a_{n+1}

For linear systems this is exactly Chung & Hulbert's generalized-alpha (and HHT when alpha_m = 0),
so the spectral radius and period error follow their theory. Rotations are advanced on the group,
q_{n+1} = q_n exp(Theta) with Theta the rotational part of Delta in the body frame: |q| = 1 by
construction and the free rigid body reduces to the trapezoidal rule on Euler's equations
(PHYSICS.md section 2, item 8), stable as the step shrinks.

Each step solves R(Delta) = 0 by Newton iterations (`lax.while_loop`) wrapped in
`lax.custom_root`, so gradients use the implicit function theorem instead of running back through
the iterations. The liquid block of the Newton matrix is constant in the body frame: it is
factored once per run (`Solver.Cinv`) and only the rigid rows and columns, where the rotation
enters, are re-linearised with JAX in each iteration (a Schur complement on the 6 rigid unknowns).
"""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .model import Config, System, advance_config


class Scheme(NamedTuple):
    alpha_m: float
    alpha_f: float
    beta: float
    gamma: float


def make_scheme(name: str, alpha: float = 0.0, rho_inf: float = 1.0) -> Scheme:
    """Newmark (trapezoidal), HHT-alpha (gamma = 1/2 + alpha, beta = (1 + alpha)^2 / 4, PHYSICS.md
    item 7) or generalized-alpha (Chung & Hulbert 1993, by its high-frequency radius rho_inf)."""
    if name == "newmark":
        return Scheme(0.0, 0.0, 0.25, 0.5)
    if name == "hht":
        return Scheme(0.0, alpha, 0.25 * (1.0 + alpha) ** 2, 0.5 + alpha)
    if name == "generalized-alpha":
        am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
        af = rho_inf / (rho_inf + 1.0)
        return Scheme(am, af, 0.25 * (1.0 - am + af) ** 2, 0.5 - am + af)
    raise ValueError(f"unknown scheme {name!r}")


class State(NamedTuple):
    c: Config
    v: jax.Array      # (n,) V0 (inertial), omega (body), d_dot
    acc: jax.Array    # (n,) accelerations satisfying the equations of motion
    a: jax.Array      # (n,) generalized-alpha pseudo-accelerations
    t: jax.Array


class StepInfo(NamedTuple):
    iterations: jax.Array
    residual: jax.Array   # max scaled residual at the end of the step: an acceleration error (m/s^2, rad/s^2)
    ok: jax.Array         # converged and finite


class Solver(eqx.Module):
    """What the Newton iterations need besides the system: constant liquid-block inverses."""
    Cinv_step: jax.Array   # (nf, nf) inverse of c_a M_ff + K_ff (liquid block of the step matrix)
    Cinv_mass: jax.Array   # (nf, nf) inverse of M_ff (liquid block of the initial-acceleration matrix)
    h: jax.Array                     # step (traced: one compilation serves every step size)
    scheme: Scheme = eqx.field(static=True)
    tol: float = eqx.field(static=True)
    max_iter: int = eqx.field(static=True)

    @property
    def c_a(self):
        s = self.scheme
        return (1.0 - s.alpha_m) / ((1.0 - s.alpha_f) * s.beta * self.h ** 2)


def make_solver(system: System, h: float, scheme: Scheme, tol: float, max_iter: int) -> Solver:
    """Factor the constant liquid blocks once (NumPy, float64)."""
    nf = system.nf
    if nf == 0:
        z = jnp.zeros((0, 0))
        return Solver(z, z, jnp.asarray(h, dtype=float), scheme, tol, max_iter)
    L = system.liquid
    Ms = np.asarray(L.Ms)
    free = np.asarray(L.free)
    M_ff = np.kron(Ms, np.eye(3))[np.ix_(free, free)]
    K_ff = np.asarray(L.K)
    c_a = (1.0 - scheme.alpha_m) / ((1.0 - scheme.alpha_f) * scheme.beta * h ** 2)
    Cs = c_a * M_ff + K_ff
    return Solver(jnp.asarray(np.linalg.inv(0.5 * (Cs + Cs.T))), jnp.asarray(np.linalg.inv(M_ff)),
                  jnp.asarray(h, dtype=float), scheme, tol, max_iter)


def _newton(R, x0, Cinv, scale, tol, max_iter):
    """Newton iterations on R(x) = 0, x = (y: 6 rigid unknowns, z: liquid), with the exact rigid
    rows/columns from JAX and the constant liquid block inverse Cinv (a Schur complement on y)."""
    n = x0.shape[0]
    nf = n - 6
    E6 = jnp.eye(n, 6)

    def err_of(r):
        return jnp.max(jnp.abs(r / scale))

    def body(carry):
        x, _, it, err_prev, _ = carry
        r, jvp = jax.linearize(R, x)
        Jy = jax.vmap(jvp, in_axes=1, out_axes=1)(E6)               # (n, 6) = [J_yy; J_zy]
        if nf == 0:
            dx = jnp.linalg.solve(Jy, -r)
        else:
            vjp = jax.linear_transpose(jvp, x)
            Jyz = jax.vmap(lambda e: vjp(e)[0])(E6.T)[:, 6:]           # (6, nf) = dr_y / dz
            W = Cinv @ jnp.concatenate([r[6:, None], Jy[6:]], axis=1)  # C^-1 [r_z, J_zy]
            S = Jy[:6] - Jyz @ W[:, 1:]
            dy = jnp.linalg.solve(S, -r[:6] + Jyz @ W[:, 0])
            dz = -W[:, 0] - W[:, 1:] @ dy
            dx = jnp.concatenate([dy, dz])
        x = x + dx
        r = R(x)
        err = err_of(r)
        return x, r, it + 1, err, err > 0.5 * err_prev

    def cond(carry):
        _, _, it, err, stalled = carry
        return (err > tol) & (it < max_iter) & jnp.isfinite(err) & ~stalled

    r0 = R(x0)
    x, r, it, err, stalled = jax.lax.while_loop(cond, body, (x0, r0, jnp.array(0), err_of(r0), jnp.array(False)))
    # Converged: below the tolerance, or stalled at round-off within a factor 100 of it.
    ok = jnp.isfinite(err) & ((err <= tol) | (stalled & (err <= 100.0 * tol)))
    # aux leaves are floats: custom_root's JVP rule cannot carry integer or boolean aux tangents
    return x, (it.astype(float), err, ok.astype(float))


def _dense_tangent_solve(g, y):
    return jnp.linalg.solve(jax.jacfwd(g)(y), y)


def solve_root(R, x0, Cinv, scale, tol, max_iter):
    """Root of R near x0; differentiable by the implicit function theorem (lax.custom_root)."""
    x, (it, err, ok) = jax.lax.custom_root(
        R, x0, lambda f, x: _newton(f, x, Cinv, scale, tol, max_iter), _dense_tangent_solve, has_aux=True)
    it, err, ok = jax.lax.stop_gradient((it, err, ok))
    return x, (it.astype(jnp.int32), err, ok > 0.5)


def _split(v):
    return v[:3], v[3:6], v[6:]


def initial_state(system: System, solver: Solver, c0: Config, v0) -> tuple[State, StepInfo]:
    """Accelerations consistent with the initial configuration and velocities."""
    scale = system.scales()

    def R(acc):
        V0, om, dd = _split(v0)
        return system.residual(c0, V0, om, dd, acc, jnp.zeros(()))

    acc0, (it, err, ok) = solve_root(R, jnp.zeros_like(v0), solver.Cinv_mass, scale, solver.tol, solver.max_iter)
    return State(c0, v0, acc0, acc0, jnp.zeros(())), StepInfo(it, err, ok)


def step(system: System, solver: Solver, s: State) -> tuple[State, StepInfo]:
    """One implicit step t_n -> t_{n+1}; the unknown is the increment Delta = (dX0, Theta, dd)."""
    h, (am, af, beta, gamma) = solver.h, solver.scheme
    scale = system.scales()            # residual rows / scale: accelerations (m/s^2, rad/s^2)

    base = h * s.v + h * h * (0.5 - beta) * s.a

    def unpack(delta):
        a_new = (delta - base) / (beta * h * h)
        v_new = s.v + h * ((1.0 - gamma) * s.a + gamma * a_new)
        acc_new = ((1.0 - am) * a_new + am * s.a - af * s.acc) / (1.0 - af)
        return advance_config(s.c, delta), v_new, acc_new, a_new

    def R(delta):
        c, v, acc, _ = unpack(delta)
        V0, om, dd = _split(v)
        return system.residual(c, V0, om, dd, acc, s.t + h)

    x0 = base + h * h * beta * s.a
    delta, (it, err, ok) = solve_root(R, x0, solver.Cinv_step, scale, solver.tol, solver.max_iter)
    c, v, acc, a = unpack(delta)
    ok = ok & jnp.all(jnp.isfinite(delta))
    return State(c, v, acc, a, s.t + h), StepInfo(it, err, ok)
