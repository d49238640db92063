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
(docs/theory.md item 8), stable as the step shrinks.

Each step solves R(Delta) = 0 by Newton iterations (newton.py) wrapped in `lax.custom_root`, so
gradients use the implicit function theorem instead of running back through the iterations.

One step and one initial state serve every system: the unknowns are those of the System's layout
(physics/unknowns.py), R = Rm + Rc with Rc the constraints of the terms that own unknowns (an
empty set without them), the terms' integrator states advanced with the step (the radiation
memory) and the constant blocks' inverses extended by the terms' hooks (linear.py).
"""
from __future__ import annotations

from typing import Any, NamedTuple, Optional

import jax
import jax.numpy as jnp

from ..physics.system import System
from ..physics.terms import Config
from .linear import Solver, empty_pre
from .newton import solve_root, solve_root_carried


class State(NamedTuple):
    c: Config
    v: jax.Array      # (n,) V0 (inertial), omega (body), d_dot [, the owners' rates: physics/unknowns.py]
    acc: jax.Array    # (n,) accelerations satisfying the equations of motion
    a: jax.Array      # (n,) generalized-alpha pseudo-accelerations
    t: jax.Array
    alg: jax.Array    # algebraic unknowns (interface frames, multipliers; physics/unknowns.py): empty without
    z: tuple          # the terms' integrator states (System.states_init: zero-size for a term without)
    pre: Any = None   # the Newton preconditioner carried to the next step (Solver.reuse), else None
    e0: Optional[jax.Array] = None  # the initial total energy, held by the energy projection (Solver.project)
    a1: Optional[jax.Array] = None  # the previous step's pseudo-accelerations a_{n-1} (the predictor's slope)


class StepInfo(NamedTuple):
    iterations: jax.Array
    residual: jax.Array   # max scaled residual at the end of the step: an acceleration error (m/s^2, rad/s^2)
    ok: jax.Array         # converged and finite


def _split_newton(system: System, Rm_parts, Rc, r):
    """(R, the split of R = Rm + Rc the Newton preconditioner takes, or None): every unknown in
    the exact block for a nonlinear liquid, the vessel's or a body's (its few unknowns linearised
    exactly: System.exact_block)."""
    L = system.layout()

    def Rm(x):
        return L.in_x(*Rm_parts(x[:r], x[L.n_small:]))

    def R(x):
        return Rm(x) + Rc(x)

    return R, None if system.exact_block() > L.n_small else (Rm, Rc, r, Rm_parts)


def initial_state(system: System, solver: Solver, c0: Config, v0, alg0=None) -> tuple[State, StepInfo]:
    """Accelerations consistent with the initial configuration and velocities (with terms that own
    unknowns: their static equilibrium first, then the accelerations and multipliers from the
    constraints differentiated twice in time)."""
    alg0 = jnp.zeros(0) if alg0 is None else alg0
    c0, v0, alg0, info0 = static_equilibrium(system, solver, c0, v0, alg0)
    L = system.layout()
    gsc, alg_sc = system.alg_scales(1.0, lambda itf: 1.0)       # rows m_ref d2g/dt2: forces
    scale = L.to_x(system.unknown_scales(), alg_sc)
    # the states settled at the initial configuration (the catenary lines' solution at the initial
    # pose, which the step's own chord steps start from: mooring/term.py)
    z0 = system.states_settle(system.states_init(), c0, start=True)
    r, t0 = L.n_rigid, jnp.zeros(())

    def Rm_parts(ay, az):
        return system.step_rows_parts(c0, v0[:r], v0[r:], ay, az, t0, z0)

    R, split = _split_newton(system, Rm_parts, system.initial_constraint_rows(c0, v0, alg0, gsc), r)
    x, (it, err, ok) = solve_root(R, jnp.zeros(L.n, dtype=v0.dtype), solver.Cinv_mass, scale, solver.tol,
                                  solver.max_iter, solver.ns, split=split, implicit=solver.implicit)
    acc0, alg_a = L.from_x(x)
    alg = system.initial_alg(alg0, alg_a)
    info = StepInfo(it + info0.iterations, jnp.maximum(err, info0.residual), ok & info0.ok)
    pre = empty_pre(system) if solver.reuse else None
    e0 = total_energy(system, c0, v0) if solver.project else None
    return State(c0, v0, acc0, acc0, jnp.zeros(()), alg, z0, pre, e0, acc0), info


def initial_state_like(system: System, solver: Solver, c0: Config, v0, alg0=None) -> tuple[State, StepInfo]:
    """What initial_state returns, of the same trees, shapes and types, without solving anything:
    the shapes the time loop is lowered for while the initial state's own program is still being
    traced (run/compiled.compile_run; a test keeps the two in step)."""
    zeros = jnp.zeros_like(v0)
    pre = empty_pre(system) if solver.reuse else None
    info = StepInfo(jnp.zeros((), jnp.int32), jnp.zeros(()), jnp.array(True))
    e0 = jnp.zeros(()) if solver.project else None
    alg = jnp.zeros(0) if alg0 is None else alg0
    return State(c0, v0, zeros, zeros, jnp.zeros(()), alg, system.states_init(), pre, e0, zeros), info


def total_energy(system: System, c: Config, v):
    T, V = system.energy(c, v)
    return T + V


def project_energy(system: System, c: Config, v, e0):
    """Scale the velocities so that T(c, s v) + V(c) = e0 (the standard projection onto the energy
    surface, Hairer, Lubich & Wanner, Geometric Numerical Integration, sec. IV.4, along the velocity).

    The kinetic energy is a quadratic form in the velocities at fixed configuration, so the scale is
    s = sqrt((e0 - V) / T) in closed form; it leaves the configuration, |q| = 1 and every homogeneous
    linear velocity constraint as they are. After a trapezoidal step s - 1 is of the order of the
    step's local energy error (dt^3), so the scheme stays second order. Where there is no kinetic
    energy to scale (T = 0) or the potential is above e0, the velocities are left as they are."""
    T = system.kinetic_energy(c, v)
    room = e0 - system.potential_energy(c)
    ok = (T > 0.0) & (room > 0.0)
    return v * jnp.sqrt(jnp.where(ok, room / jnp.where(ok, T, 1.0), 1.0))


def states_next(system: System, solver: Solver, s: State, v_new, c_new=None):
    """The terms' integrator states at t_{n+1} (the radiation memory's: exact for a rigid velocity
    linear over the step, so they are a linear function of the step's unknown new velocity; a
    lumped mooring line's also follow the configuration c_new), settled at c_new (the catenary lines'
    solution there, the start of the next step's)."""
    r = system.layout().n_rigid          # every floating frame's velocities (the bodies' coupled memory)
    z = system.states_advance(s.z, s.v[:r], v_new[:r], system.states_coefficients(solver.h), s.c, c_new)
    return z if c_new is None else system.states_settle(z, c_new)


def step_equations(system: System, solver: Solver, s: State):
    """The equations of one step t_n -> t_{n+1} in the increment Delta = (dX0, Theta, dd):
    returns (R, unpack, x0, parts): the residual R(Delta) of the dynamic unknowns (without the
    multipliers), the map Delta -> (config, v, acc, a) of the scheme, the predictor
    (a_{n+1} = 2 a_n - a_{n-1}), and the residual in parts for the Newton preconditioner,
    parts(Delta[:r], Delta[r:]) = (rigid rows, the others) with r the rigid unknowns
    (System.step_rows_parts)."""
    h, sc = solver.h, solver.scheme
    am, af, beta, gamma = sc.alpha_m, sc.alpha_f, sc.beta, sc.gamma
    base = h * s.v + h * h * (0.5 - beta) * s.a

    def rates(delta, i):
        """(v, acc, a) at t_{n+1} of the unknowns i (a slice) for their increments delta."""
        a_new = (delta - base[i]) / (beta * h * h)
        v_new = s.v[i] + h * ((1.0 - gamma) * s.a[i] + gamma * a_new)
        acc_new = ((1.0 - am) * a_new + am * s.a[i] - af * s.acc[i]) / (1.0 - af)
        return v_new, acc_new, a_new

    def unpack(delta):
        return (system.advance(s.c, delta),) + rates(delta, slice(None))

    coef = system.states_coefficients(h)
    r = system.layout().n_rigid
    # the terms' parts that depend on the time alone (the wave excitation's components), formed
    # once per step: the residual below is evaluated in every Newton iteration
    at_t = system.at_time(s.t + h)

    def parts(y, z):
        vy, ay, _ = rates(y, slice(0, r))
        vz, az, _ = rates(z, slice(r, None))
        c_new = system.advance_parts(s.c, y, z)
        states = system.states_advance(s.z, s.v[:r], vy, coef, s.c, c_new)
        return at_t.step_rows_parts(c_new, vy, vz, ay, az, s.t + h, states)

    def R(delta):
        return jnp.concatenate(parts(delta[:r], delta[r:]))

    # the predictor: a_{n+1} extrapolated linearly from a_n and a_{n-1} (a_n itself at the first
    # step, where a1 = a): its residual is 3 to 10 times smaller than a_{n+1} = a_n's, which saves
    # one Newton iteration in many steps (docs/benchmarks.md, campaigns)
    a1 = s.a if s.a1 is None else s.a1
    return R, unpack, base + h * h * beta * (2.0 * s.a - a1), parts


def static_equilibrium(system: System, solver: Solver, c0: Config, v0, alg0):
    """The owners' unknowns (the structures) in static equilibrium under gravity, the vessel and
    the liquid held where they are (the counterpart of the liquid's hydrostatic start, docs/theory.md
    item 6: a mast that starts undeformed would ring with its own weight). Returns the
    configuration, velocities in which every structure moves rigidly with the vessel, and the
    frames and multipliers of the equilibrium. Nothing to solve without owners: the static layout
    says so (a Python branch on static model data, as MJX's stages skip what a model lacks)."""
    L = system.layout()
    if not any(o.settles() for o in system.owners()):
        return c0, v0, alg0, StepInfo(jnp.zeros((), jnp.int32), jnp.zeros(()), jnp.array(True))
    r, nf = L.n_rigid, L.nf
    held = jnp.zeros(L.n_dyn, dtype=bool).at[:6].set(True).at[r:r + nf].set(True)
    held_x = L.to_x(held, jnp.zeros(L.n_alg, dtype=bool))
    f = solver.scheme.c_d(solver.h)
    gsc, alg_sc = system.alg_scales(f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
    scale = L.to_x(system.unknown_scales(), alg_sc)
    z = jnp.zeros(L.n_dyn)
    Cinv = jnp.zeros((nf + L.m, nf + L.m)).at[:nf, :nf].set(jnp.eye(nf)).at[nf:, nf:].set(
        jnp.diag(1.0 / system.block_diagonal(0.0, 1.0)))
    held_y, held_z = held[:r], held[r:]
    zy, zz = jnp.zeros(r), jnp.zeros(L.n_dyn - r)

    # the vessel's and the liquid's rows are held: their terms are left out, not computed and dropped
    def Rm_parts(y, w):
        ry, rw = system.step_rows_parts(system.advance_parts(c0, y, w), zy, zz, zy, zz, jnp.zeros(()), core=False)
        return jnp.where(held_y, y * scale[:r], ry), jnp.where(held_z, w * scale[L.n_small:], rw)

    def Rm(x):
        return L.in_x(*Rm_parts(x[:r], x[L.n_small:]))

    def Rc(x):
        dyn, alg = L.from_x(x)
        c = system.advance(c0, dyn)
        return jnp.where(held_x, 0.0, system.constraint_rows(c, alg, system.constraint(c, alg), gsc))

    x, (it, err, ok) = solve_root(lambda x: Rm(x) + Rc(x), L.to_x(z, alg0), Cinv, scale, solver.tol,
                                  solver.max_iter, L.n_small, split=(Rm, Rc, L.n_rigid, Rm_parts),
                                  implicit=solver.implicit)
    dyn, alg = L.from_x(x)
    c = system.advance(c0, dyn)
    return c, system.carried_velocities(c, v0), alg, StepInfo(it, err, ok)


def step(system: System, solver: Solver, s: State, fresh=None) -> tuple[State, StepInfo]:
    """One implicit step t_n -> t_{n+1}; the unknowns x = [Delta_y, alg, Delta_z] (the System's
    layout: Delta = (dX0, Theta, dd) without terms that own unknowns). With constraints their rows
    are g(q_{n+1}) m_ref / (beta h^2) (forces), converged when g / (beta h^2) is below the tolerance
    like the acceleration errors of the other rows, or |g| below 1e-13 of the interface's size
    (round-off), whichever is larger. `fresh`: batch mode with a carried preconditioner, whether
    this step forms it anew (see newton.StructuredNewton.init)."""
    with jax.named_scope("predictor"):
        L = system.layout()
        f = solver.scheme.c_d(solver.h)
        gsc, alg_sc = system.alg_scales(f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
        scale = L.to_x(system.unknown_scales(), alg_sc)   # rows / scale: accelerations (m/s^2, rad/s^2)
        _, unpack, pred, Rm_parts = step_equations(system, solver, s)

        def Rc(x):
            return system.constraint_residual(x, lambda dyn: unpack(dyn)[0], gsc)

        R, split = _split_newton(system, Rm_parts, Rc, L.n_rigid)
        # the liquid's own floor: a multimodal tank's rows lose digits as exp(2 k_N zeta) under high crests
        floor = jnp.maximum(solver.noise * jnp.max(jnp.abs(s.c.d), initial=0.0),
                            jax.lax.stop_gradient(system.liquid.roundoff(s.c.d)))
    pre = s.pre if solver.reuse else None
    with jax.named_scope("newton"):
        x, (it, err, ok), pre_new = solve_root_carried(R, L.to_x(pred, s.alg), solver.Cinv_step, scale, solver.tol,
                                                       solver.max_iter, pre, floor, solver.adaptive, solver.ns, split,
                                                       fresh, solver.implicit)
    with jax.named_scope("update"):
        dyn, alg = L.from_x(x)
        c, v, acc, a = unpack(dyn)
        ok = ok & jnp.all(jnp.isfinite(x))
        z = states_next(system, solver, s, v, c)
        if solver.project:
            v = project_energy(system, c, v, s.e0)
    return (State(c, v, acc, a, s.t + solver.h, alg, z, pre_new if solver.reuse else s.pre, s.e0, s.a),
            StepInfo(it, err, ok))


def step_or_retry(system: System, solver: Solver, s: State, n=None, live=None) -> tuple[State, StepInfo]:
    """One step; when it fails and `solver.substeps` > 1, the step is redone as that many sub-steps
    (the iterations of every attempt are counted). `n`: the steps attempted so far (the same for every
    run of a batch), which times the preconditioner's refresh in batch mode (Solver.refresh_every).
    `live`: whether this run has not failed before (batches: only live runs ask for a redo)."""
    fresh = None
    if solver.refresh_every and n is not None:
        fresh = n % solver.refresh_every == 0
    if fresh is not None and solver.batch_axis is not None:
        s1, info = _step_or_redo(system, solver, s, fresh, live)
    else:
        s1, info = step(system, solver, s, fresh)
    if not solver.substeps:
        return s1, info
    sub = solver.sub_solver()

    def retry(_):
        def one(carry, _):
            st, it, err, ok = carry
            st2, inf = step(system, sub, st)
            return (st2, it + inf.iterations, jnp.maximum(err, inf.residual), ok & inf.ok), None

        # the sub-steps' first predictor is a_n itself (the step's slope a_n - a_{n-1} spans h, not h / substeps)
        init = (s._replace(a1=s.a), info.iterations, jnp.zeros_like(info.residual), jnp.array(True))
        (st, it, err, ok), _ = jax.lax.scan(one, init, None, length=solver.substeps)
        return st, StepInfo(it, err, ok)

    return jax.lax.cond(info.ok, lambda _: (s1, info), retry, None)


def _step_or_redo(system: System, solver: Solver, s: State, fresh, live):
    """Batches: `step`, and a step that failed with the carried preconditioner is redone with one
    formed for it. Formed some steps before, the carried one can contract by only about half per
    iteration where the Jacobian moves fast (a multimodal liquid's rows near resonance, whose high
    modes' integrals go as exp(k_n zeta)), and then runs out of iterations above the tolerance; a
    fresh one converges in a few. The redo is decided for the whole batch, by a sum over the vmapped
    runs' axis, so that the loop's test is not batched (the redo runs only when some live run
    failed; the step appears once in the program), and only the failed runs take its result (the
    iterations of both attempts counted). A step that fails again fails as before."""
    live = jnp.asarray(True) if live is None else live

    def attempt(c):
        k, s1, info = c
        s2, info2 = step(system, solver, s, fresh | (k > 0))
        take = (k == 0) | ~info.ok
        pick = lambda a, b: jnp.where(take, a, b)  # noqa: E731
        return (k + 1, jax.tree_util.tree_map(pick, s2, s1),
                StepInfo(jnp.where(take, info.iterations + info2.iterations, info.iterations),
                         pick(info2.residual, info.residual), pick(info2.ok, info.ok)))

    def again(c):
        k, _, info = c
        bad = jax.lax.psum((~info.ok & live).astype(jnp.int32), solver.batch_axis) > 0
        return (k == 0) | ((k == 1) & ~fresh & bad)

    info0 = StepInfo(jnp.zeros((), jnp.int32), jnp.zeros(()), jnp.array(True))
    _, s1, info = jax.lax.while_loop(again, attempt, (jnp.zeros((), jnp.int32), s, info0))
    return s1, info
