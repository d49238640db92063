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

from typing import NamedTuple, Optional

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
    z: Optional[jax.Array] = None   # radiation memory states (hydrodynamics.Memory), None without them


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
    substeps: int = eqx.field(static=True, default=0)   # retry a failed step as this many sub-steps
    Cinv_sub: Optional[jax.Array] = None                # liquid block inverse for the sub-step

    def sub_solver(self) -> "Solver":
        return Solver(self.Cinv_sub, self.Cinv_mass, self.h / self.substeps, self.scheme, self.tol, self.max_iter)

    @property
    def c_a(self):
        s = self.scheme
        return (1.0 - s.alpha_m) / ((1.0 - s.alpha_f) * s.beta * self.h ** 2)


def make_solver(system: System, h: float, scheme: Scheme, tol: float, max_iter: int, substeps: int = 0) -> Solver:
    """Factor the constant liquid blocks once (float64): NumPy for concrete matrices, JAX when the
    liquid was built from traced values (under jit).

    The inverses only precondition the Newton iterations and the tangent solves, whose solutions do
    not depend on them (`lax.custom_root` drops their tangents), so they are formed from
    `stop_gradient` values: under `jax.grad` outside jit the matrices are then concrete again."""
    nf = system.nf
    substeps = int(substeps) if substeps and substeps > 1 else 0
    if nf == 0:
        z = jnp.zeros((0, 0))
        return Solver(z, z, jnp.asarray(h, dtype=float), scheme, tol, max_iter, substeps, z if substeps else None)
    L = system.liquid
    Ms, K_ff = jax.lax.stop_gradient(L.Ms), jax.lax.stop_gradient(L.K)
    free = np.asarray(L.free)
    traced = isinstance(Ms, jax.core.Tracer) or isinstance(K_ff, jax.core.Tracer)
    xp = jnp if traced else np
    if not traced:
        Ms, K_ff = np.asarray(Ms), np.asarray(K_ff)
    M_ff = xp.kron(Ms, xp.eye(3))[np.ix_(free, free)]

    def inverse(A):
        return jnp.linalg.inv(A) if traced else jnp.asarray(np.linalg.inv(A))

    def step_block_inverse(hh):
        c_a = (1.0 - scheme.alpha_m) / ((1.0 - scheme.alpha_f) * scheme.beta * hh ** 2)
        Cs = c_a * M_ff + K_ff
        return inverse(0.5 * (Cs + Cs.T))

    return Solver(step_block_inverse(h), inverse(M_ff), jnp.asarray(h, dtype=float), scheme, tol,
                  max_iter, substeps, step_block_inverse(h / substeps) if substeps else None)


def _precond_data(A, like, Cinv):
    """The factors of P^-1 for a linear map A with the Newton matrix's structure: the rigid rows and
    columns exact (6 products with A, 6 with its transpose), the liquid block replaced by the
    constant C (inverse Cinv); a Schur complement on the 6 rigid unknowns. Exact without liquid."""
    n = like.shape[0]
    E6 = jnp.eye(n, 6, dtype=like.dtype)
    cols = jax.vmap(A, in_axes=1, out_axes=1)(E6)                   # [A_yy; A_zy]
    if n == 6:
        return (jnp.linalg.inv(cols),)
    AT = jax.linear_transpose(A, like)
    Ayz = jax.vmap(lambda e: AT(e)[0])(E6.T)[:, 6:]                  # (6, nf)
    Wz = Cinv @ cols[6:]
    return jnp.linalg.inv(cols[:6] - Ayz @ Wz), Ayz, Wz


def _precond_apply(data, Cinv, r):
    if len(data) == 1:
        return data[0] @ r
    S_inv, Ayz, Wz = data
    wz = Cinv @ r[6:]
    xy = S_inv @ (r[:6] - Ayz @ wz)
    return jnp.concatenate([xy, wz - Wz @ xy])


def _preconditioner(A, like, Cinv):
    data = _precond_data(A, like, Cinv)
    return lambda r: _precond_apply(data, Cinv, r)


def _newton(R, x0, Cinv, scale, tol, max_iter):
    """Quasi-Newton iterations on R(x) = 0 (x: 6 rigid unknowns, then the liquid's) with the
    structured approximate inverse of the Jacobian, formed at the first iteration of the step and
    formed again only when the residual stops falling fast (a rotation that changed a lot)."""

    def err_of(r):
        return jnp.max(jnp.abs(r / scale))

    def refresh(x):
        _, jvp = jax.linearize(R, x)
        return _precond_data(jvp, x, Cinv)

    def body(carry):
        x, r, it, err_prev, _, need, data = carry
        data = jax.lax.cond(need, refresh, lambda _: data, x)
        x = x + _precond_apply(data, Cinv, -r)
        r = R(x)
        err = err_of(r)
        return x, r, it + 1, err, err > 0.5 * err_prev, err > 0.1 * err_prev, data

    def cond(carry):
        _, _, it, err, stalled, _, _ = carry
        return (err > tol) & (it < max_iter) & jnp.isfinite(err) & ~stalled

    r0 = R(x0)
    data0 = jax.tree_util.tree_map(jnp.zeros_like, jax.eval_shape(refresh, x0))
    init = (x0, r0, jnp.array(0), err_of(r0), jnp.array(False), jnp.array(True), data0)
    x, r, it, err, stalled, _, _ = jax.lax.while_loop(cond, body, init)
    # Converged: below the tolerance, or stalled at round-off within a factor 100 of it.
    ok = jnp.isfinite(err) & ((err <= tol) | (stalled & (err <= 100.0 * tol)))
    # aux leaves are floats: custom_root's JVP rule cannot carry integer or boolean aux tangents
    return x, (it.astype(float), err, ok.astype(float))


def _structured_linear_solve(A, b, Cinv, rtol=1e-13, max_sweeps=30):
    """Solve A x = b to full precision: the structured preconditioner, then Richardson sweeps.
    The same code solves the transposed system (pass A^T), which reverse mode needs."""
    P_inv = _preconditioner(A, b, Cinv)
    bnorm = jnp.max(jnp.abs(b)) + 1e-300

    def cond(c):
        _, res, k = c
        return (jnp.max(jnp.abs(res)) > rtol * bnorm) & (k < max_sweeps)

    def body(c):
        x, res, k = c
        x = x + P_inv(res)
        return x, b - A(x), k + 1

    x0 = P_inv(b)
    x, _, _ = jax.lax.while_loop(cond, body, (x0, b - A(x0), 0))
    return x


def _tangent_solver(Cinv):
    def tangent_solve(g, y):
        return jax.lax.custom_linear_solve(
            g, y, solve=lambda A, b: _structured_linear_solve(A, b, Cinv),
            transpose_solve=lambda AT, b: _structured_linear_solve(AT, b, Cinv))
    return tangent_solve


def solve_root(R, x0, Cinv, scale, tol, max_iter):
    """Root of R near x0; differentiable by the implicit function theorem (lax.custom_root), the
    tangent systems solved with the same structure as the Newton iterations."""
    x, (it, err, ok) = jax.lax.custom_root(
        R, x0, lambda f, x: _newton(f, x, Cinv, scale, tol, max_iter), _tangent_solver(Cinv), has_aux=True)
    it, err, ok = jax.lax.stop_gradient((it, err, ok))
    return x, (it.astype(jnp.int32), err, ok > 0.5)


def _split(v):
    return v[:3], v[3:6], v[6:]


def initial_state(system: System, solver: Solver, c0: Config, v0) -> tuple[State, StepInfo]:
    """Accelerations consistent with the initial configuration and velocities."""
    scale = system.scales()

    memory = _memory(system)
    z0 = None if memory is None else memory.init()
    mu0 = None if memory is None else memory.force(z0)

    def R(acc):
        V0, om, dd = _split(v0)
        return system.residual(c0, V0, om, dd, acc, jnp.zeros(()), mu0)

    acc0, (it, err, ok) = solve_root(R, jnp.zeros_like(v0), solver.Cinv_mass, scale, solver.tol, solver.max_iter)
    return State(c0, v0, acc0, acc0, jnp.zeros(()), z0), StepInfo(it, err, ok)


def _memory(system: System):
    """The radiation memory of the system's hydrodynamics, or None (hydrodynamics.py)."""
    sea = getattr(system, "sea", None)
    return None if sea is None else sea.memory


def memory_next(system: System, solver: Solver, s: State, v_new):
    """Radiation states at t_{n+1}: exact for a rigid velocity linear over the step, so they are a
    linear function of the step's unknown new velocity (None without radiation)."""
    memory = _memory(system)
    if memory is None:
        return None
    return memory.advance(s.z, s.v[:6], v_new[:6], memory.coefficients(solver.h))


def step_equations(system: System, solver: Solver, s: State):
    """The equations of one step t_n -> t_{n+1} in the increment Delta = (dX0, Theta, dd):
    returns (R, unpack, x0): the residual R(Delta), the map Delta -> (config, v, acc, a) of the
    scheme, and the predictor (a_{n+1} = a_n)."""
    h, (am, af, beta, gamma) = solver.h, solver.scheme
    base = h * s.v + h * h * (0.5 - beta) * s.a

    def unpack(delta):
        a_new = (delta - base) / (beta * h * h)
        v_new = s.v + h * ((1.0 - gamma) * s.a + gamma * a_new)
        acc_new = ((1.0 - am) * a_new + am * s.a - af * s.acc) / (1.0 - af)
        return advance_config(s.c, delta), v_new, acc_new, a_new

    memory = _memory(system)
    coef = None if memory is None else memory.coefficients(h)

    def R(delta):
        c, v, acc, _ = unpack(delta)
        V0, om, dd = _split(v)
        mu = None if memory is None else memory.force(memory.advance(s.z, s.v[:6], v[:6], coef))
        return system.residual(c, V0, om, dd, acc, s.t + h, mu)

    return R, unpack, base + h * h * beta * s.a


def step(system: System, solver: Solver, s: State) -> tuple[State, StepInfo]:
    """One implicit step t_n -> t_{n+1}; the unknown is the increment Delta = (dX0, Theta, dd)."""
    scale = system.scales()            # residual rows / scale: accelerations (m/s^2, rad/s^2)
    R, unpack, x0 = step_equations(system, solver, s)
    delta, (it, err, ok) = solve_root(R, x0, solver.Cinv_step, scale, solver.tol, solver.max_iter)
    c, v, acc, a = unpack(delta)
    ok = ok & jnp.all(jnp.isfinite(delta))
    return State(c, v, acc, a, s.t + solver.h, memory_next(system, solver, s, v)), StepInfo(it, err, ok)


def step_or_retry(system: System, solver: Solver, s: State) -> tuple[State, StepInfo]:
    """One step; when it fails and `solver.substeps` > 1, the step is redone as that many sub-steps
    (the iterations of every attempt are counted)."""
    s1, info = step(system, solver, s)
    if not solver.substeps:
        return s1, info
    sub = solver.sub_solver()

    def retry(_):
        def one(carry, _):
            st, it, err, ok = carry
            st2, inf = step(system, sub, st)
            return (st2, it + inf.iterations, jnp.maximum(err, inf.residual), ok & inf.ok), None

        init = (s, info.iterations, jnp.zeros_like(info.residual), jnp.array(True))
        (st, it, err, ok), _ = jax.lax.scan(one, init, None, length=solver.substeps)
        return st, StepInfo(it, err, ok)

    return jax.lax.cond(info.ok, lambda _: (s1, info), retry, None)
