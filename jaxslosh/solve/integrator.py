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

Each step solves R(Delta) = 0 by Newton iterations (newton.py) wrapped in `lax.custom_root`, so
gradients use the implicit function theorem instead of running back through the iterations.
"""
from __future__ import annotations

from typing import Any, NamedTuple, Optional

import jax
import jax.numpy as jnp

from ..physics import structures as mb
from ..physics.kinematics import rotation_matrix
from ..physics.system import System, advance_config, advance_config_parts
from ..physics.terms import Config
from .linear import Solver, empty_pre
from .newton import solve_root, solve_root_carried


class State(NamedTuple):
    c: Config
    v: jax.Array      # (n,) V0 (inertial), omega (body), d_dot
    acc: jax.Array    # (n,) accelerations satisfying the equations of motion
    a: jax.Array      # (n,) generalized-alpha pseudo-accelerations
    t: jax.Array
    pre: Any = None   # the Newton preconditioner carried to the next step (Solver.reuse), else None
    alg: Optional[jax.Array] = None   # interface frame positions and multipliers (multibody.py), if any
    z: tuple = ()   # the terms' integrator states (System.states_init: zero-size for a term without)
    e0: Optional[jax.Array] = None  # the initial total energy, held by the energy projection (Solver.project)


class StepInfo(NamedTuple):
    iterations: jax.Array
    residual: jax.Array   # max scaled residual at the end of the step: an acceleration error (m/s^2, rad/s^2)
    ok: jax.Array         # converged and finite


def _advance(system, c, delta):
    if system.flex is not None:
        return mb.advance(system, c, delta)
    return advance_config(c, delta)


def _split(v):
    return v[:3], v[3:6], v[6:]


def initial_state(system: System, solver: Solver, c0: Config, v0, alg0=None) -> tuple[State, StepInfo]:
    """Accelerations consistent with the initial configuration and velocities (with structures:
    their static equilibrium first, then the accelerations and multipliers from the constraints
    differentiated twice in time)."""
    if system.flex is not None:
        return _flex_initial_state(system, solver, c0, v0, alg0)
    scale = system.scales()

    z0 = system.states_init()
    V0, om, dd = _split(v0)

    def parts(a6, d_acc):
        return system.residual_parts(c0, V0, om, dd, a6, d_acc, jnp.zeros(()), z0)

    def R(acc):
        return jnp.concatenate(parts(acc[:6], acc[6:]))

    exact = system.liquid.nonlinear    # every unknown in the exact block: R's parts are not needed
    acc0, (it, err, ok) = solve_root(R, jnp.zeros_like(v0), solver.Cinv_mass, scale, solver.tol, solver.max_iter,
                                     ns=solver.ns, implicit=solver.implicit, parts=None if exact else parts)
    pre = empty_pre(system) if solver.reuse else None
    e0 = total_energy(system, c0, v0) if solver.project else None
    return State(c0, v0, acc0, acc0, jnp.zeros(()), pre=pre, z=z0, e0=e0), StepInfo(it, err, ok)


def initial_state_like(system: System, solver: Solver, c0: Config, v0, alg0=None) -> tuple[State, StepInfo]:
    """What initial_state returns, of the same trees, shapes and types, without solving anything:
    the shapes the time loop is lowered for while the initial state's own program is still being
    traced (cache/compiled.compile_run; a test keeps the two in step)."""
    zeros = jnp.zeros_like(v0)
    z0 = system.states_init()
    pre = empty_pre(system) if solver.reuse else None
    info = StepInfo(jnp.zeros((), jnp.int32), jnp.zeros(()), jnp.array(True))
    if system.flex is not None:
        return State(c0, v0, zeros, zeros, jnp.zeros(()), pre, alg0, z0), info
    e0 = jnp.zeros(()) if solver.project else None
    return State(c0, v0, zeros, zeros, jnp.zeros(()), pre=pre, z=z0, e0=e0), info


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


def states_next(system: System, solver: Solver, s: State, v_new):
    """The terms' integrator states at t_{n+1} (the radiation memory's: exact for a rigid velocity
    linear over the step, so they are a linear function of the step's unknown new velocity)."""
    return system.states_advance(s.z, s.v[:6], v_new[:6], system.states_coefficients(solver.h))


def step_equations(system: System, solver: Solver, s: State):
    """The equations of one step t_n -> t_{n+1} in the increment Delta = (dX0, Theta, dd):
    returns (R, unpack, x0, parts): the residual R(Delta) (with structures, of their dynamic
    unknowns, without the multipliers), the map Delta -> (config, v, acc, a) of the scheme, the
    predictor (a_{n+1} = a_n), and the residual in parts for the Newton
    preconditioner, parts(Delta[:r], Delta[r:]) = (rigid rows, the others) with r the rigid
    unknowns (System.residual_parts; with structures their inertia rows, without the multipliers:
    structures.inertia_rows_parts)."""
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
        return (_advance(system, s.c, delta),) + rates(delta, slice(None))

    coef = system.states_coefficients(h)
    r = mb.layout(system).n_rigid

    def parts(y, z):
        vy, ay, _ = rates(y, slice(0, r))
        vz, az, _ = rates(z, slice(r, None))
        states = system.states_advance(s.z, s.v[:6], vy[:6], coef)
        if system.flex is not None:
            return mb.inertia_rows_parts(system, mb.advance_parts(system, s.c, y, z), vy, vz, ay, az, s.t + h, states)
        return system.residual_parts(advance_config_parts(s.c, y, z), vy[:3], vy[3:], vz, ay, az, s.t + h, states)

    def R(delta):
        return jnp.concatenate(parts(delta[:r], delta[r:]))

    return R, unpack, base + h * h * beta * s.a, parts


def static_structures(system, solver: Solver, c0: Config, v0, alg0):
    """The structures in static equilibrium under gravity, the vessel and the liquid held where they
    are (the counterpart of the liquid's hydrostatic start, PHYSICS.md item 6: a mast that starts
    undeformed would ring with its own weight). Returns the configuration, velocities in which every
    structure moves rigidly with the vessel, and the frames and multipliers of the equilibrium."""
    L = mb.layout(system)
    r, nf = L.n_rigid, L.nf
    held = jnp.zeros(L.n_dyn, dtype=bool).at[:6].set(True).at[r:r + nf].set(True)
    held_x = L.to_x(held, jnp.zeros(L.n_alg, dtype=bool))
    f = solver.scheme.c_d(solver.h)
    gsc, alg_sc = mb.alg_scales(system, f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
    scale = L.to_x(mb.scales(system), alg_sc)
    z = jnp.zeros(L.n_dyn)
    w2 = jax.lax.stop_gradient(jnp.concatenate([b.omega2 for b in system.flex.bodies]))
    Cinv = jnp.zeros((nf + L.m, nf + L.m)).at[:nf, :nf].set(jnp.eye(nf)).at[nf:, nf:].set(jnp.diag(1.0 / w2))

    held_y, held_z = held[:r], held[r:]
    zy, zz = jnp.zeros(r), jnp.zeros(L.n_dyn - r)

    # the vessel's and the liquid's rows are held: their terms are left out, not computed and dropped
    def Rm_parts(y, w):
        ry, rw = mb.inertia_rows_parts(system, mb.advance_parts(system, c0, y, w), zy, zz, zy, zz, jnp.zeros(()),
                                       core=False)
        return jnp.where(held_y, y * scale[:r], ry), jnp.where(held_z, w * scale[L.n_small:], rw)

    def Rm(x):
        return mb.in_x(L, *Rm_parts(x[:r], x[L.n_small:]))

    def Rc(x):
        dyn, alg = L.from_x(x)
        c = mb.advance(system, c0, dyn)
        return jnp.where(held_x, 0.0, mb.constraint_rows(system, c, alg, mb.constraint(system, c, alg), gsc))

    x, (it, err, ok) = solve_root(lambda x: Rm(x) + Rc(x), L.to_x(z, alg0), Cinv, scale, solver.tol,
                                  solver.max_iter, L.n_small, split=(Rm, Rc, L.n_rigid, Rm_parts),
                                  implicit=solver.implicit)
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
    L = mb.layout(system)
    c0, v0, alg0, info0 = static_structures(system, solver, c0, v0, alg0)
    gsc, alg_sc = mb.alg_scales(system, 1.0, lambda itf: 1.0)       # rows m_ref d2g/dt2: forces
    scale = L.to_x(mb.scales(system), alg_sc)
    z0 = system.states_init()
    Rm, Rc, Rm_parts = mb.initial_residuals(system, c0, v0, alg0, jnp.zeros(()), gsc, z0)
    x, (it, err, ok) = solve_root(lambda x: Rm(x) + Rc(x), jnp.zeros(L.n), solver.Cinv_mass, scale, solver.tol,
                                  solver.max_iter, L.n_small, split=(Rm, Rc, L.n_rigid, Rm_parts),
                                  implicit=solver.implicit)
    acc0, alg_a = L.from_x(x)
    alg = jnp.where(mb.position_mask(system.flex), alg0, alg_a)
    info = StepInfo(it + info0.iterations, jnp.maximum(err, info0.residual), ok & info0.ok)
    pre = empty_pre(system) if solver.reuse else None
    return State(c0, v0, acc0, acc0, jnp.zeros(()), pre, alg, z0), info


def _flex_step(system, solver: Solver, s: State, fresh=None) -> tuple[State, StepInfo]:
    """The step with structures: unknowns [Delta_y, (X_f, lambda), Delta_z]; the constraint rows
    are g(q_{n+1}) m_ref / (beta h^2) (forces), converged when g / (beta h^2) is below the tolerance
    like the acceleration errors of the other rows, or |g| below 1e-13 of the interface's size
    (round-off), whichever is larger."""
    L = mb.layout(system)
    f = solver.scheme.c_d(solver.h)
    gsc, alg_sc = mb.alg_scales(system, f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
    scale = L.to_x(mb.scales(system), alg_sc)
    _, unpack, pred, Rm_parts = step_equations(system, solver, s)
    r = L.n_rigid

    def Rm(x):
        return mb.in_x(L, *Rm_parts(x[:r], x[L.n_small:]))

    def Rc(x):
        dyn, alg = L.from_x(x)
        c = unpack(dyn)[0]
        return mb.constraint_rows(system, c, alg, mb.constraint(system, c, alg), gsc)

    floor = solver.noise * jnp.max(jnp.abs(s.c.d), initial=0.0)
    pre = s.pre if solver.reuse else None
    x, (it, err, ok), pre_new = solve_root_carried(lambda x: Rm(x) + Rc(x), L.to_x(pred, s.alg), solver.Cinv_step,
                                                   scale, solver.tol, solver.max_iter, pre, floor, solver.adaptive,
                                                   L.n_small, (Rm, Rc, L.n_rigid, Rm_parts), fresh, solver.implicit)
    dyn, alg = L.from_x(x)
    c, v, acc, a = unpack(dyn)
    ok = ok & jnp.all(jnp.isfinite(x))
    return (State(c, v, acc, a, s.t + solver.h, pre_new if solver.reuse else s.pre, alg,
                  states_next(system, solver, s, v)),
            StepInfo(it, err, ok))


def step(system: System, solver: Solver, s: State, fresh=None) -> tuple[State, StepInfo]:
    """One implicit step t_n -> t_{n+1}; the unknown is the increment Delta = (dX0, Theta, dd).
    `fresh`: batch mode with a carried preconditioner, whether this step forms it anew (see _newton)."""
    if system.flex is not None:
        return _flex_step(system, solver, s, fresh)
    with jax.named_scope("predictor"):
        scale = system.scales()            # residual rows / scale: accelerations (m/s^2, rad/s^2)
        R, unpack, x0, parts = step_equations(system, solver, s)
        floor = solver.noise * jnp.max(jnp.abs(s.c.d), initial=0.0)
    pre = s.pre if solver.reuse else None
    with jax.named_scope("newton"):
        exact = system.liquid.nonlinear    # every unknown in the exact block: R's parts are not needed
        delta, (it, err, ok), pre_new = solve_root_carried(R, x0, solver.Cinv_step, scale, solver.tol,
                                                           solver.max_iter, pre, floor, solver.adaptive, ns=solver.ns,
                                                           fresh=fresh, implicit=solver.implicit,
                                                           parts=None if exact else parts)
    with jax.named_scope("update"):
        c, v, acc, a = unpack(delta)
        ok = ok & jnp.all(jnp.isfinite(delta))
        z = states_next(system, solver, s, v)
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
