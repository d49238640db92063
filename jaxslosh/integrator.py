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

import dataclasses
from typing import Any, NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .kinematics import rotation_matrix
from .model import Config, System, advance_config
from .reduction import is_reduced


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
    pre: Any = None   # the Newton preconditioner carried to the next step (Solver.reuse), else None
    alg: Optional[jax.Array] = None   # interface frame positions and multipliers (multibody.py), if any
    z: Optional[jax.Array] = None   # radiation memory states (hydrodynamics.Memory), None without them
    e0: Optional[jax.Array] = None  # the initial total energy, held by the energy projection (Solver.project)


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
    # Speed (none changes what a converged step is):
    # the round-off floor of the scaled residual per metre of liquid displacement, eps max_i
    # sum_j |K_ij| / scale_i: a tolerance below eps |K| |d| cannot be met, so the iterations stop there
    noise: Any = 0.0
    # carry the preconditioner from step to step, formed again only when convergence slows (single
    # runs); False: formed once at the start of every step
    reuse: bool = eqx.field(static=True, default=False)
    # refresh the preconditioner inside the iterations when convergence slows (a lax.cond); False
    # for vmapped batches, where a cond computes both branches
    adaptive: bool = eqx.field(static=True, default=True)
    # unknowns of the exact (Schur) block: the 6 rigid ones, and with flexible structures their rigid
    # unknowns and the interface frames and multipliers (multibody.Layout.n_small)
    ns: int = eqx.field(static=True, default=6)
    # after each step, scale the velocities so that the total energy is the initial one (the
    # `simulation.energy_projection` key: trapezoidal rule, conservative scenes only; see project_energy)
    project: bool = eqx.field(static=True, default=False)
    # with reuse and not adaptive (vmapped batches): the carried preconditioner is formed afresh at
    # every this-many-th step (the step counter is the same for every run of a batch, so the cond
    # stays a branch under vmap); 0: at every step
    refresh_every: int = eqx.field(static=True, default=0)
    # the Newton solves are differentiable (lax.custom_root: gradients by the implicit function
    # theorem). False where nothing a run depends on is traced for differentiation (run.prepare):
    # custom_root traces the linearisation and both tangent solves of every root even when no
    # gradient is taken, a fifth of a scene's tracing; the iterations and their result are the same
    implicit: bool = eqx.field(static=True, default=True)

    def sub_solver(self) -> "Solver":
        return Solver(self.Cinv_sub, self.Cinv_mass, self.h / self.substeps, self.scheme, self.tol, self.max_iter,
                      noise=self.noise, adaptive=self.adaptive, ns=self.ns, project=self.project,
                      implicit=self.implicit)

    @property
    def c_a(self):
        s = self.scheme
        return (1.0 - s.alpha_m) / ((1.0 - s.alpha_f) * s.beta * self.h ** 2)


def make_solver(system: System, h: float, scheme: Scheme, tol: float, max_iter: int, substeps: int = 0,
                reuse: bool = False, adaptive: bool = True) -> Solver:
    """Factor the constant liquid blocks once (float64): NumPy for concrete matrices, JAX when the
    liquid was built from traced values (under jit).

    The inverses only precondition the Newton iterations and the tangent solves, whose solutions do
    not depend on them (`lax.custom_root` drops their tangents), so they are formed from
    `stop_gradient` values: under `jax.grad` outside jit the matrices are then concrete again."""
    nf = system.nf
    substeps = int(substeps) if substeps and substeps > 1 else 0
    if getattr(system, "flex", None) is not None:
        return _flex_solver(system, h, scheme, tol, max_iter, substeps, reuse, adaptive)
    if nf == 0:
        z = jnp.zeros((0, 0))
        return Solver(z, z, jnp.asarray(h, dtype=float), scheme, tol, max_iter, substeps, z if substeps else None,
                      reuse=reuse, adaptive=adaptive)
    L = system.liquid
    from .sparse import is_sparse
    if is_sparse(L):         # large mesh (sparse.py): host-side sparse LU factors
        from .sparse import sparse_solver_blocks
        c_a = lambda hh: (1.0 - scheme.alpha_m) / ((1.0 - scheme.alpha_f) * scheme.beta * hh ** 2)  # noqa: E731
        step_inv, mass_inv, sub_inv, K = sparse_solver_blocks(L, c_a(h), c_a(h / substeps) if substeps else None)
        scale = np.asarray(jax.lax.stop_gradient(system.scales()[6:]))
        noise = np.finfo(np.float64).eps * np.max(np.asarray(abs(K).sum(axis=1)).reshape(-1) / scale)
        return Solver(step_inv, mass_inv, jnp.asarray(h, dtype=float), scheme, tol, max_iter, substeps, sub_inv,
                      noise=noise, reuse=reuse, adaptive=adaptive)
    if is_reduced(L):        # modal liquid (reduction.py): small dense blocks
        M_ff, K_ff = jax.lax.stop_gradient(L.Mr), jax.lax.stop_gradient(L.Kr)
        traced = isinstance(M_ff, jax.core.Tracer) or isinstance(K_ff, jax.core.Tracer)
        if not traced:
            M_ff, K_ff = np.asarray(M_ff), np.asarray(K_ff)
    else:
        Ms, K_ff = jax.lax.stop_gradient(L.Ms), jax.lax.stop_gradient(L.K)
        free = np.asarray(L.free)
        traced = isinstance(Ms, jax.core.Tracer) or isinstance(K_ff, jax.core.Tracer)
        xp = jnp if traced else np
        if not traced:
            Ms, K_ff = np.asarray(Ms), np.asarray(K_ff)
        M_ff = xp.kron(Ms, xp.eye(3))[np.ix_(free, free)]
        if getattr(L, "dof_map", None) is not None:     # elastic tank walls: T^T kron(Ms, I3) T
            dmap = np.asarray(L.dof_map)
            T = np.zeros((dmap.size, free.size + 1))
            T[np.arange(dmap.size), dmap] = 1.0
            T = T[:, :-1]
            M_ff = T.T @ np.kron(np.asarray(Ms), np.eye(3)) @ T

    def inverse(A):
        return jnp.linalg.inv(A) if traced else jnp.asarray(np.linalg.inv(A))

    def step_block_inverse(hh):
        c_a = (1.0 - scheme.alpha_m) / ((1.0 - scheme.alpha_f) * scheme.beta * hh ** 2)
        Cs = c_a * M_ff + K_ff
        return inverse(0.5 * (Cs + Cs.T))

    scale = jax.lax.stop_gradient(system.scales()[6:])
    noise = jnp.finfo(jnp.float64).eps * jnp.max(jnp.sum(jnp.abs(jnp.asarray(K_ff)), axis=1) / scale)
    return Solver(step_block_inverse(h), inverse(M_ff), jnp.asarray(h, dtype=float), scheme, tol,
                  max_iter, substeps, step_block_inverse(h / substeps) if substeps else None,
                  noise=noise, reuse=reuse, adaptive=adaptive)


class BlockInverse(eqx.Module):
    """The constant-block inverse with flexible structures: the liquid's (a dense matrix, or the
    sparse factors of sparse.py) and the structures' modal block, which is diagonal."""
    liquid: Any           # (nf, nf)
    modal: jax.Array      # (m,)

    @property
    def shape(self):
        n = self.liquid.shape[0] + self.modal.shape[0]
        return (n, n)

    def __matmul__(self, x):
        nf = self.liquid.shape[0]
        bottom = self.modal[:, None] * x[nf:] if x.ndim == 2 else self.modal * x[nf:]
        return jnp.concatenate([self.liquid @ x[:nf], bottom])


def _flex_solver(system: System, h, scheme: Scheme, tol, max_iter, substeps, reuse, adaptive) -> Solver:
    """With flexible structures: the liquid block inverses as without them, and the structures'
    modal block, which is diagonal (Phi^T M Phi = I, Phi^T K Phi = omega^2): 1 / (c_a + omega^2)."""
    from .multibody import layout
    base = make_solver(dataclasses.replace(system, flex=None), h, scheme, tol, max_iter, substeps, reuse, adaptive)
    w2 = jax.lax.stop_gradient(jnp.concatenate([b.omega2 for b in system.flex.bodies]))

    def c_a(hh):
        return (1.0 - scheme.alpha_m) / ((1.0 - scheme.alpha_f) * scheme.beta * hh ** 2)

    sub = BlockInverse(base.Cinv_sub, 1.0 / (c_a(h / substeps) + w2)) if substeps else None
    return Solver(BlockInverse(base.Cinv_step, 1.0 / (c_a(h) + w2)), BlockInverse(base.Cinv_mass, jnp.ones_like(w2)),
                  jnp.asarray(h, dtype=float), scheme, tol, max_iter, substeps, sub, noise=base.noise, reuse=reuse,
                  adaptive=adaptive, ns=layout(system).n_small)


def _precond_data_split(A, Ac, like, Cinv, nr, ns):
    """As _precond_data, when unknowns nr..ns (interface frames and multipliers) enter the residual
    only through a cheap part Ac of A (the constraints), whose rows nr..ns are all of A's there: their
    columns and rows are taken from Ac, and the expensive A is applied only nr times each way."""
    n = like.shape[0]
    I = jnp.eye(n, ns, dtype=like.dtype)
    cols = jnp.concatenate([jax.vmap(A, in_axes=1, out_axes=1)(I[:, :nr]),
                            jax.vmap(Ac, in_axes=1, out_axes=1)(I[:, nr:])], axis=1)
    AT = jax.linear_transpose(A, like)
    AcT = jax.linear_transpose(Ac, like)
    rows = jnp.concatenate([jax.vmap(lambda e: AT(e)[0])(I[:, :nr].T), jax.vmap(lambda e: AcT(e)[0])(I[:, nr:].T)])
    Ayz = rows[:, ns:]
    Wz = Cinv @ cols[ns:]
    return jnp.linalg.inv(cols[:ns] - Ayz @ Wz), Ayz, Wz


def _precond_data(A, like, Cinv, ns=6):
    """The factors of P^-1 for a linear map A with the Newton matrix's structure: the first ns rows
    and columns exact (ns products with A, ns with its transpose: the rigid unknowns, and the
    interface frames and multipliers when there are flexible structures), the rest (liquid and
    elastic modal coordinates) replaced by the constant C (inverse Cinv); a Schur complement on the
    ns unknowns. Exact without liquid and structures."""
    n = like.shape[0]
    E6 = jnp.eye(n, ns, dtype=like.dtype)
    cols = jax.vmap(A, in_axes=1, out_axes=1)(E6)                   # [A_yy; A_zy]
    if n == ns:
        return (jnp.linalg.inv(cols),)
    AT = jax.linear_transpose(A, like)
    Ayz = jax.vmap(lambda e: AT(e)[0])(E6.T)[:, ns:]                 # (ns, nz)
    Wz = Cinv @ cols[ns:]
    return jnp.linalg.inv(cols[:ns] - Ayz @ Wz), Ayz, Wz


def _precond_apply(data, Cinv, r, ns=6):
    if len(data) == 1:
        return data[0] @ r
    S_inv, Ayz, Wz = data
    wz = Cinv @ r[ns:]
    xy = S_inv @ (r[:ns] - Ayz @ wz)
    return jnp.concatenate([xy, wz - Wz @ xy])


def _preconditioner(A, like, Cinv, ns=6):
    data = _precond_data(A, like, Cinv, ns)
    return lambda r: _precond_apply(data, Cinv, r, ns)


#: a carried preconditioner is formed again when an iteration reduces the residual by less than this
#: factor (a fresh one converges 1e-3 to 1e-4 per iteration on the paper example)
SLOW = 0.01


def _newton(R, x0, Cinv, scale, tol, max_iter, pre=None, floor=0.0, adaptive=True, ns=6, split=None, fresh=None):
    """Quasi-Newton iterations on R(x) = 0 (x: ns rigid and algebraic unknowns, then the liquid's and
    the structures' modal ones) with the
    structured approximate inverse of the Jacobian, formed at the first iteration of the step and
    formed again only when the residual stops falling fast (a rotation that changed a lot).

    `pre` = (data, valid): a preconditioner carried from the previous step, used while it keeps the
    convergence fast (and formed afresh when not valid); the one used last is returned with the
    aux. `floor`: the round-off floor of the scaled residual; the iterations stop below
    max(tol, floor). `adaptive=False`: formed once before the iterations, never inside (vmapped
    batches, where a lax.cond computes both branches); then, with `pre` carried, `fresh` (a boolean
    that is the same for every run of a batch) says whether to form it anew or use the carried one
    through this step. `split` = (Rc, nr): unknowns nr..ns enter R only through the cheap part Rc
    (see _precond_data_split)."""
    tol = jnp.maximum(tol, floor)

    def err_of(r):
        return jnp.max(jnp.abs(r / scale))

    def refresh(x):
        _, jvp = jax.linearize(R, x)
        if split is not None:
            Rc, nr = split
            _, jvp_c = jax.linearize(Rc, x)
            return _precond_data_split(jvp, jvp_c, x, Cinv, nr, ns)
        return _precond_data(jvp, x, Cinv, ns)

    def body(carry):
        x, r, it, err_prev, _, need, data = carry
        if adaptive:
            data = jax.lax.cond(need, refresh, lambda _: data, x)
        x = x + _precond_apply(data, Cinv, -r, ns)
        r = R(x)
        err = err_of(r)
        fresh = need | (not adaptive)
        # a stale preconditioner that slows down is formed again; a fresh one that cannot is a stall
        slow = err > jnp.where(fresh, 0.1, SLOW) * err_prev
        return x, r, it + 1, err, fresh & (err > 0.5 * err_prev), slow, data

    def cond(carry):
        _, _, it, err, stalled, _, _ = carry
        return (err > tol) & (it < max_iter) & jnp.isfinite(err) & ~stalled

    r0 = R(x0)
    if not adaptive:
        if pre is not None and fresh is not None:
            # `fresh` only, never the carried validity flag, which is per run: the predicate stays
            # unbatched and the cond a branch (the first step of a run is always fresh)
            data0 = jax.lax.cond(fresh, refresh, lambda _: pre[0], x0)
        else:
            data0 = refresh(x0)
        need0 = jnp.array(False)
    elif pre is not None:
        data0, need0 = pre[0], ~(pre[1] > 0.5)
    else:
        data0 = jax.tree_util.tree_map(jnp.zeros_like, jax.eval_shape(refresh, x0))
        need0 = jnp.array(True)
    init = (x0, r0, jnp.array(0), err_of(r0), jnp.array(False), need0, data0)
    x, r, it, err, stalled, _, data = jax.lax.while_loop(cond, body, init)
    # Converged: below the tolerance, or stalled at round-off within a factor 100 of it.
    ok = jnp.isfinite(err) & ((err <= tol) | (stalled & (err <= 100.0 * tol)))
    # aux leaves are floats: custom_root's JVP rule cannot carry integer or boolean aux tangents
    aux = (it.astype(float), err, ok.astype(float))
    if pre is not None:
        aux = aux + ((data, jnp.ones(())),)
    return x, aux


def _structured_linear_solve(A, b, Cinv, rtol=1e-13, max_sweeps=30, ns=6):
    """Solve A x = b to full precision: the structured preconditioner, then Richardson sweeps.
    The same code solves the transposed system (pass A^T), which reverse mode needs."""
    P_inv = _preconditioner(A, b, Cinv, ns)
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


def _tangent_solver(Cinv, ns=6):
    def tangent_solve(g, y):
        return jax.lax.custom_linear_solve(
            g, y, solve=lambda A, b: _structured_linear_solve(A, b, Cinv, ns=ns),
            transpose_solve=lambda AT, b: _structured_linear_solve(AT, b, Cinv, ns=ns))
    return tangent_solve


def _root(R, x0, newton, Cinv, ns, implicit):
    """newton(R, x0), differentiable by the implicit function theorem when `implicit`."""
    if not implicit:
        return newton(R, x0)
    return jax.lax.custom_root(R, x0, newton, _tangent_solver(Cinv, ns), has_aux=True)


def solve_root(R, x0, Cinv, scale, tol, max_iter, ns=6, split=None, implicit=True):
    """Root of R near x0; differentiable by the implicit function theorem (lax.custom_root), the
    tangent systems solved with the same structure as the Newton iterations (`implicit=False`: the
    iterations alone, for runs that no gradient goes through)."""
    x, (it, err, ok) = _root(R, x0, lambda f, x: _newton(f, x, Cinv, scale, tol, max_iter, ns=ns, split=split),
                             Cinv, ns, implicit)
    it, err, ok = jax.lax.stop_gradient((it, err, ok))
    return x, (it.astype(jnp.int32), err, ok > 0.5)


def solve_root_carried(R, x0, Cinv, scale, tol, max_iter, pre=None, floor=0.0, adaptive=True, ns=6, split=None,
                       fresh=None, implicit=True):
    """`solve_root` with a preconditioner carried in and out (`pre`, see `_newton`; None: formed
    here and not returned), a round-off floor and the batch mode. Returns x, (it, err, ok), pre."""
    out = _root(R, x0, lambda f, x: _newton(f, x, Cinv, scale, tol, max_iter, pre, floor, adaptive, ns, split, fresh),
                Cinv, ns, implicit)
    x, aux = out
    it, err, ok = jax.lax.stop_gradient(aux[:3])
    new_pre = jax.lax.stop_gradient(aux[3]) if pre is not None else None
    return x, (it.astype(jnp.int32), err, ok > 0.5), new_pre


def empty_pre(system: System):
    """A carried preconditioner of the right shapes, marked not valid (formed at the first step)."""
    ns, nz = 6, system.nf
    if _has_flex(system):
        from .multibody import layout
        L = layout(system)
        ns, nz = L.n_small, L.nf + L.m
    data = (jnp.zeros((ns, ns)),) if nz == 0 else (jnp.zeros((ns, ns)), jnp.zeros((ns, nz)), jnp.zeros((nz, ns)))
    return data, jnp.zeros(())


def _advance(system, c, delta):
    if _has_flex(system):
        from .multibody import advance
        return advance(system, c, delta)
    return advance_config(c, delta)


def _has_flex(system) -> bool:
    return getattr(system, "flex", None) is not None


def _split(v):
    return v[:3], v[3:6], v[6:]


def initial_state(system: System, solver: Solver, c0: Config, v0, alg0=None) -> tuple[State, StepInfo]:
    """Accelerations consistent with the initial configuration and velocities (with structures:
    their static equilibrium first, then the accelerations and multipliers from the constraints
    differentiated twice in time)."""
    if _has_flex(system):
        return _flex_initial_state(system, solver, c0, v0, alg0)
    scale = system.scales()

    memory = _memory(system)
    z0 = None if memory is None else memory.init()
    mu0 = None if memory is None else memory.force(z0)

    def R(acc):
        V0, om, dd = _split(v0)
        return system.residual(c0, V0, om, dd, acc, jnp.zeros(()), mu0)

    acc0, (it, err, ok) = solve_root(R, jnp.zeros_like(v0), solver.Cinv_mass, scale, solver.tol, solver.max_iter,
                                     implicit=solver.implicit)
    pre = empty_pre(system) if solver.reuse else None
    e0 = total_energy(system, c0, v0) if solver.project else None
    return State(c0, v0, acc0, acc0, jnp.zeros(()), pre=pre, z=z0, e0=e0), StepInfo(it, err, ok)


def total_energy(system: System, c: Config, v):
    V0, om, dd = _split(v)
    return system.kinetic_energy(c, V0, om, dd) + system.potential_energy(c)


def project_energy(system: System, c: Config, v, e0):
    """Scale the velocities so that T(c, s v) + V(c) = e0 (the standard projection onto the energy
    surface, Hairer, Lubich & Wanner, Geometric Numerical Integration, sec. IV.4, along the velocity).

    The kinetic energy is a quadratic form in the velocities at fixed configuration, so the scale is
    s = sqrt((e0 - V) / T) in closed form; it leaves the configuration, |q| = 1 and every homogeneous
    linear velocity constraint as they are. After a trapezoidal step s - 1 is of the order of the
    step's local energy error (dt^3), so the scheme stays second order. Where there is no kinetic
    energy to scale (T = 0) or the potential is above e0, the velocities are left as they are."""
    V0, om, dd = _split(v)
    T = system.kinetic_energy(c, V0, om, dd)
    room = e0 - system.potential_energy(c)
    ok = (T > 0.0) & (room > 0.0)
    return v * jnp.sqrt(jnp.where(ok, room / jnp.where(ok, T, 1.0), 1.0))


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
        return _advance(system, s.c, delta), v_new, acc_new, a_new

    memory = _memory(system)
    coef = None if memory is None else memory.coefficients(h)

    def R(delta):
        c, v, acc, _ = unpack(delta)
        V0, om, dd = _split(v)
        mu = None if memory is None else memory.force(memory.advance(s.z, s.v[:6], v[:6], coef))
        return system.residual(c, V0, om, dd, acc, s.t + h, mu)

    return R, unpack, base + h * h * beta * s.a


def static_structures(system, solver: Solver, c0: Config, v0, alg0):
    """The structures in static equilibrium under gravity, the vessel and the liquid held where they
    are (the counterpart of the liquid's hydrostatic start, PHYSICS.md item 6: a mast that starts
    undeformed would ring with its own weight). Returns the configuration, velocities in which every
    structure moves rigidly with the vessel, and the frames and multipliers of the equilibrium."""
    from . import multibody as mb
    L = mb.layout(system)
    r, nf = L.n_rigid, L.nf
    held = jnp.zeros(L.n_dyn, dtype=bool).at[:6].set(True).at[r:r + nf].set(True)
    held_x = L.to_x(held, jnp.zeros(L.n_alg, dtype=bool))
    f = 1.0 / (solver.scheme.beta * solver.h ** 2)
    gsc, alg_sc = mb.alg_scales(system, f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
    scale = L.to_x(mb.scales(system), alg_sc)
    z = jnp.zeros(L.n_dyn)
    w2 = jax.lax.stop_gradient(jnp.concatenate([b.omega2 for b in system.flex.bodies]))
    Cinv = jnp.zeros((nf + L.m, nf + L.m)).at[:nf, :nf].set(jnp.eye(nf)).at[nf:, nf:].set(jnp.diag(1.0 / w2))

    def Rm(x):
        dyn, _ = L.from_x(x)
        rows = L.to_x(mb.inertia_rows(system, mb.advance(system, c0, dyn), z, z, jnp.zeros(())), jnp.zeros(L.n_alg))
        return jnp.where(held_x, x * scale, rows)

    def Rc(x):
        dyn, alg = L.from_x(x)
        c = mb.advance(system, c0, dyn)
        return jnp.where(held_x, 0.0, mb.constraint_rows(system, c, alg, mb.constraint(system, c, alg), gsc))

    x, (it, err, ok) = solve_root(lambda x: Rm(x) + Rc(x), L.to_x(z, alg0), Cinv, scale, solver.tol,
                                  solver.max_iter, L.n_small, split=(Rc, L.n_rigid), implicit=solver.implicit)
    dyn, alg = L.from_x(x)
    c = mb.advance(system, c0, dyn)
    # every structure moves rigidly with the vessel: V_s = V + (A omega) x (X_s - X0), omega_s = A_s^T A omega
    ves, _, d_v, _ = L.split(v0)
    w = rotation_matrix(c.q) @ ves[3:]
    rig = jnp.concatenate([jnp.concatenate([ves[:3] + jnp.cross(w, c.Xs[k] - c.X0), rotation_matrix(c.qs[k]).T @ w])
                           for k in range(L.S)])
    v = jnp.concatenate([ves, rig, d_v, jnp.zeros(L.m)])
    return c, v, alg, StepInfo(it, err, ok)


def _flex_initial_state(system, solver: Solver, c0: Config, v0, alg0):
    from . import multibody as mb
    L = mb.layout(system)
    c0, v0, alg0, info0 = static_structures(system, solver, c0, v0, alg0)
    gsc, alg_sc = mb.alg_scales(system, 1.0, lambda itf: 1.0)       # rows m_ref d2g/dt2: forces
    scale = L.to_x(mb.scales(system), alg_sc)
    memory = _memory(system)
    z0 = None if memory is None else memory.init()
    Rm, Rc = mb.initial_residuals(system, c0, v0, alg0, jnp.zeros(()), gsc, None if memory is None else memory.force(z0))
    x, (it, err, ok) = solve_root(lambda x: Rm(x) + Rc(x), jnp.zeros(L.n), solver.Cinv_mass, scale, solver.tol,
                                  solver.max_iter, L.n_small, split=(Rc, L.n_rigid), implicit=solver.implicit)
    acc0, alg_a = L.from_x(x)
    alg = jnp.where(mb._position_mask(system.flex), alg0, alg_a)
    info = StepInfo(it + info0.iterations, jnp.maximum(err, info0.residual), ok & info0.ok)
    pre = empty_pre(system) if solver.reuse else None
    return State(c0, v0, acc0, acc0, jnp.zeros(()), pre, alg, z0), info


def _flex_step(system, solver: Solver, s: State, fresh=None) -> tuple[State, StepInfo]:
    """The step with structures: unknowns [Delta_y, (X_f, lambda), Delta_z]; the constraint rows
    are g(q_{n+1}) m_ref / (beta h^2) (forces), converged when g / (beta h^2) is below the tolerance
    like the acceleration errors of the other rows, or |g| below 1e-13 of the interface's size
    (round-off), whichever is larger."""
    from . import multibody as mb
    L = mb.layout(system)
    h, beta = solver.h, solver.scheme.beta
    f = 1.0 / (beta * h * h)
    gsc, alg_sc = mb.alg_scales(system, f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
    scale = L.to_x(mb.scales(system), alg_sc)
    _, unpack, pred = step_equations(system, solver, s)

    memory = _memory(system)
    coef = None if memory is None else memory.coefficients(h)

    def Rm(x):
        dyn, _ = L.from_x(x)
        c, v, acc, _ = unpack(dyn)
        mu = None if memory is None else memory.force(memory.advance(s.z, s.v[:6], v[:6], coef))
        return L.to_x(mb.inertia_rows(system, c, v, acc, s.t + h, mu), jnp.zeros(L.n_alg))

    def Rc(x):
        dyn, alg = L.from_x(x)
        c = unpack(dyn)[0]
        return mb.constraint_rows(system, c, alg, mb.constraint(system, c, alg), gsc)

    floor = solver.noise * jnp.max(jnp.abs(s.c.d), initial=0.0)
    pre = s.pre if solver.reuse else None
    x, (it, err, ok), pre_new = solve_root_carried(lambda x: Rm(x) + Rc(x), L.to_x(pred, s.alg), solver.Cinv_step,
                                                   scale, solver.tol, solver.max_iter, pre, floor, solver.adaptive,
                                                   L.n_small, (Rc, L.n_rigid), fresh, solver.implicit)
    dyn, alg = L.from_x(x)
    c, v, acc, a = unpack(dyn)
    ok = ok & jnp.all(jnp.isfinite(x))
    return (State(c, v, acc, a, s.t + h, pre_new if solver.reuse else s.pre, alg, memory_next(system, solver, s, v)),
            StepInfo(it, err, ok))


def step(system: System, solver: Solver, s: State, fresh=None) -> tuple[State, StepInfo]:
    """One implicit step t_n -> t_{n+1}; the unknown is the increment Delta = (dX0, Theta, dd).
    `fresh`: batch mode with a carried preconditioner, whether this step forms it anew (see _newton)."""
    if _has_flex(system):
        return _flex_step(system, solver, s, fresh)
    scale = system.scales()            # residual rows / scale: accelerations (m/s^2, rad/s^2)
    R, unpack, x0 = step_equations(system, solver, s)
    floor = solver.noise * jnp.max(jnp.abs(s.c.d), initial=0.0)
    pre = s.pre if solver.reuse else None
    delta, (it, err, ok), pre_new = solve_root_carried(R, x0, solver.Cinv_step, scale, solver.tol, solver.max_iter,
                                                       pre, floor, solver.adaptive, fresh=fresh,
                                                       implicit=solver.implicit)
    c, v, acc, a = unpack(delta)
    ok = ok & jnp.all(jnp.isfinite(delta))
    z = memory_next(system, solver, s, v)
    if solver.project:
        v = project_energy(system, c, v, s.e0)
    return (State(c, v, acc, a, s.t + solver.h, pre=pre_new if solver.reuse else s.pre, z=z, e0=s.e0),
            StepInfo(it, err, ok))


def step_or_retry(system: System, solver: Solver, s: State, n=None) -> tuple[State, StepInfo]:
    """One step; when it fails and `solver.substeps` > 1, the step is redone as that many sub-steps
    (the iterations of every attempt are counted). `n`: the steps attempted so far (the same for every
    run of a batch), which times the preconditioner's refresh in batch mode (Solver.refresh_every)."""
    fresh = None
    if solver.refresh_every and n is not None:
        fresh = n % solver.refresh_every == 0
    s1, info = step(system, solver, s, fresh)
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
