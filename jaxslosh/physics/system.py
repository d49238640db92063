"""The assembled model: a rigid vessel (floating frame at its COG) carrying liquid, as the sum of the
terms its scene has (terms.py).

Static model, dynamic state (docs/design.md, the step): `System` holds everything that is constant in the
body frame; `terms.Config` and the velocity vector are the dynamic unknowns. Generalised
coordinates: X0 (inertial position of the vessel COG), q (Euler parameters), d (the deformable
block: liquid displacement relative to the tank on the dofs the slip walls leave free, or its modal
coordinates). Generalised velocities: V0 = dX0/dt (inertial), omega (body frame), d_dot. The
residual is the virtual work of inertia minus applied forces (eq. 26), the sum of the terms' rows;
the energy is the sum of the terms' energies; tangents come from JAX. A term with unknowns of its
own (unknowns.py: the flexible structures in their own frames, structures.py) adds unknowns,
multipliers and constraints around this core through its hooks; the System's `layout`, `advance`,
`step_rows_parts`, `constraint_rows` and the rest are what the step calls, the same for every system.
A term that prescribes the vessel's motion (`[vessel.forced]`, vessel.AbstractPrescribedMotion)
gives the vessel's rows of the whole step in place of the others' (`hold`); a free vessel has no
such term.
"""
from __future__ import annotations

from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp

from .floating import AbstractFloating, frame_kin, gravity_in
from .kinematics import G_matrix, quat_exp, quat_multiply
from .terms import Config, Kin, Unknowns
from .unknowns import Layout
from .vessel import RigidBody


class System(AbstractFloating):
    body: RigidBody                  # the hull's inertia (always a term)
    terms: tuple                     # the other terms the scene has (buoyancy, weight, waves, penalties, ...)
    # the owner of the deformable unknowns: a jaxslosh/liquid AbstractLiquid (NoLiquid without tanks);
    # the liquid sits above this module and the solver pieces (it owns its constant block's inverse)
    liquid: Any
    gravity: jax.Array               # m/s^2, along -Z
    q_ref: jax.Array                 # the initial attitude
    # terms summed after the liquid's rows (its modal damping, [tanks.damping]): the sums' order is
    # the residual's rounding
    tail: tuple = ()
    gravity_turning: bool = eqx.field(static=True, default=True)   # off: g_b stays as at the start
    balanced: bool = eqx.field(static=True, default=True)          # weight balanced by static buoyancy

    def __check_init__(self):
        if len(self.owners()) > 1:      # the layout places one owner's unknowns (physics/unknowns.py)
            raise ValueError("a System holds at most one term that owns unknowns (the structures' term "
                             "holds every structure and interface)")
        if len(self.prescribing()) > 1:  # the vessel's rows are one term's constraint (hold)
            raise ValueError("a System holds at most one term that prescribes the vessel's motion")

    @property
    def nf(self) -> int:
        return self.liquid.nf

    @property
    def n(self) -> int:
        return 6 + self.nf

    def all_terms(self) -> tuple:
        return (self.body, *self.terms, self.liquid, *self.tail)

    def frame_terms(self) -> tuple:
        """The vessel's terms (a floating body's, floating.AbstractFloating): all of them."""
        return self.all_terms()

    # ---------------------------------------------------------------- the terms' own unknowns
    def owners(self) -> tuple:
        """The terms with unknowns of their own (unknowns.AbstractOwner): static, from their sizes."""
        return tuple(t for t in self.all_terms() if t.unknowns() != Unknowns())

    def prescribing(self) -> tuple:
        """The term that prescribes the vessel's motion, if any (AbstractTerm.prescribes): static."""
        return tuple(t for t in self.all_terms() if t.prescribes())

    def hold(self, ry, a6, t):
        """The rigid rows ry (the vessel's six first) with the vessel's replaced by the constraint of
        the term that prescribes its motion: unchanged without one (a branch on static model data)."""
        for term in self.prescribing():
            with jax.named_scope(type(term).__name__):
                ry = jnp.concatenate([term.prescribed_rows(a6, jnp.asarray(t), lambda: self.scales()[:6]), ry[6:]])
        return ry

    def hold_forces(self, rows):
        """Rows in Newton order [y, alg, z] of forces beside the terms' (the multipliers'), none on
        the vessel's rows where its motion is prescribed: its rows are the constraint alone."""
        return rows.at[:6].set(0.0) if self.prescribing() else rows

    def exact_block(self) -> int:
        """How many of the Newton unknowns (x = [y, alg, z]: physics/unknowns.py) form its exact block,
        linearised at every preconditioner: the rigid and algebraic ones; a nonlinear liquid's too (the
        vessel's multimodal); and the owners' deformable ones where an owner asks (a body's multimodal
        tank), which then needs the vessel's liquid in the exact block too (it lies between)."""
        L = self.layout()
        ns = L.n_small + (L.nf if self.liquid.nonlinear else 0)
        if any(o.exact() for o in self.owners()):
            if ns != L.n_small + L.nf:
                raise ValueError("a body's nonlinear liquid beside a linear liquid on the vessel: the exact block "
                                 "is the Newton unknowns' first ones")
            ns = L.n
        return ns

    def layout(self) -> Layout:
        u = [t.unknowns() for t in self.owners()]
        return Layout(sum(x.frames for x in u), self.nf, sum(x.deformable for x in u), sum(x.alg for x in u))

    def start(self, c0: Config, v0):
        """(c, v, alg) at t = 0 with the owners' unknowns (alg empty without)."""
        alg = jnp.zeros(0)
        for o in self.owners():
            c0, v0, alg = o.start(self, c0, v0)
        return c0, v0, alg

    def carried_velocities(self, c: Config, v):
        """v with the owners' rates those of moving rigidly with the vessel."""
        for o in self.owners():
            v = o.carried_velocities(self, c, v)
        return v

    def advance(self, c: Config, delta) -> Config:
        """Apply a dynamic increment: translations added, rotations on the group (q exp(Theta))."""
        r = self.layout().n_rigid
        return self.advance_parts(c, delta[:r], delta[r:])

    def advance_parts(self, c: Config, y, z) -> Config:
        """`advance` for the rigid increments y (vessel, frames) and the others z (liquid, the
        owners' deformable) apart (see step_rows_parts)."""
        nf = self.nf
        out = Config(c.X0 + y[:3], quat_multiply(c.q, quat_exp(y[3:6])), c.d + z[:nf])
        for o in self.owners():
            out = o.advance(c, out, y[6:], z[nf:])
        return out

    def step_rows(self, c: Config, v, acc, t, z=None):
        """The dynamic rows (every term's, the owners' with theirs; without the multipliers)."""
        r = self.layout().n_rigid
        return jnp.concatenate(self.step_rows_parts(c, v[:r], v[r:], acc[:r], acc[r:], t, z))

    def step_rows_parts(self, c: Config, vy, vz, ay, az, t, z=None, core=True):
        """`step_rows` as (rigid rows (n_rigid,), the others), with the rates of the rigid unknowns
        (y) and of the others (z) passed apart, as residual_parts. `core=False`: without the
        vessel-and-liquid terms (zero on the liquid's rows, the owners' balance alone on the
        vessel's)."""
        nf = self.nf
        if core:
            ry, rz, frames = self.terms_rows(c, vy[:3], vy[3:6], vz[:nf], ay[:6], az[:nf], t, z,
                                             vy[6:] if vy.shape[0] > 6 else None)
        else:
            ry, rz, frames = jnp.zeros(6), jnp.zeros(nf), None
        states = self.states_init() if z is None else z
        for o in self.owners():
            own = next(zi for term, zi in zip(self.all_terms(), states) if term is o)
            ry, rz = o.add_rows(self, c, ry, rz, vy, vz, ay, az, t, own)
        if frames is not None:       # a term's rows on the bodies' frames (their owner has put them after the vessel's)
            ry = ry.at[6:6 + frames.shape[0]].add(frames)
        return self.hold(ry, ay[:6], t), rz

    def constraint(self, c: Config, alg):
        """The owners' constraints g (empty without)."""
        return jnp.concatenate([jnp.zeros(0)] + [o.constraint(self, c, alg) for o in self.owners()])

    def constraint_rows(self, c: Config, alg, g_rows, gscale):
        """The constraints' rows in Newton order [y, alg, z] (zero without owners)."""
        rows = [o.constraint_rows(self, c, alg, g_rows, gscale) for o in self.owners()]
        return self.hold_forces(sum(rows[1:], rows[0])) if rows else jnp.zeros(self.layout().n)

    def constraint_residual(self, x, config, gscale):
        """The constraints' part Rc of the step's residual at x = [y, alg, z] in Newton order,
        `config(dyn)` the configuration of the dynamic unknowns: zero without owners, where not
        even the configuration is formed (a dead update in every Newton iteration is not always
        removed by XLA: it doubled the paper example's step)."""
        if not self.owners():
            return jnp.zeros_like(x)
        dyn, alg = self.layout().from_x(x)
        c = config(dyn)
        return self.constraint_rows(c, alg, self.constraint(c, alg), gscale)

    def initial_constraint_rows(self, c: Config, v, alg0, mscale):
        """x -> the constraints' rows of the initial accelerations (d^2 g / dt^2 = 0)."""
        fs = [o.initial_constraint_rows(self, c, v, alg0, mscale) for o in self.owners()]
        return lambda x: self.hold_forces(sum((f(x) for f in fs[1:]), fs[0](x))) if fs else jnp.zeros_like(x)

    def initial_alg(self, alg0, alg_a):
        for o in self.owners():
            alg_a = o.initial_alg(alg0, alg_a)
        return alg_a

    def unknown_scales(self):
        """Characteristic mass of each dynamic unknown (dyn order): the vessel-and-liquid scales
        and the owners' (so that every row over its scale is an acceleration)."""
        base = self.scales()
        if not self.owners():
            return base
        y, z = base[:6], base[6:]
        for o in self.owners():
            y, z = o.add_scales(y, z)
        return jnp.concatenate([y, z])

    def alg_scales(self, row_factor, err_factor):
        """(gscale, the alg part of the error scale): the owners' (empty without)."""
        gsc, sc = [], [jnp.zeros(0)]
        for o in self.owners():
            g, a = o.alg_scales(row_factor, err_factor)
            gsc, sc = gsc + list(g), sc + [a]
        return gsc, jnp.concatenate(sc)

    def block_diagonal(self, c_m, c_k):
        """The diagonal of the owners' deformable block of c_m M + c_k K (empty without)."""
        return jnp.concatenate([jnp.zeros(0)] + [o.block_diagonal(c_m, c_k) for o in self.owners()])

    def deformable_block(self, c_m, c_k):
        """The owner's deformable block of c_m M + c_k K (unknowns.AbstractOwner.deformable_block: a
        diagonal (m,) or a block (m, m)); empty without."""
        owner = self.owners()
        return owner[0].deformable_block(c_m, c_k) if owner else jnp.zeros(0)

    def total_mass(self):
        return self.body.mass + self.liquid.total_mass()

    def start_attitude(self):
        return self.q_ref

    def gravity_body(self, A):
        """Gravity in the body frame at rotation A: turning with the body (the load of eq. 32), or frozen at the start."""
        frozen = self.gravity_attitude()
        return gravity_in(A if frozen is None else frozen, self.gravity)

    def kin(self, c: Config, V0, omega, d_dot, a6=None, d_acc=None, t=0.0, vs=None) -> Kin:
        """The vessel's Kin (floating.frame_kin), its gravity frozen at the start where it does not turn;
        `vs` the other frames' rigid velocities (Kin.vs)."""
        return frame_kin(c, V0, omega, d_dot, a6, d_acc, t, self.gravity, self.gravity_attitude())._replace(vs=vs)

    def at_time(self, t) -> "System":
        """The System for the evaluations of one step at time t: each term's `at_time` (what
        depends on the time alone formed once per step, not in every Newton iteration)."""
        terms = tuple(term.at_time(t) for term in self.terms)
        tail = tuple(term.at_time(t) for term in self.tail)
        if all(a is b for a, b in zip(terms + tail, self.terms + self.tail)):
            return self
        return eqx.tree_at(lambda s: (s.terms, s.tail), self, (terms, tail))

    # ---------------------------------------------------------------- the terms' integrator states
    def states_init(self) -> tuple:
        """Every term's integrator states at t = 0 (AbstractTerm.state_init), in all_terms' order."""
        return tuple(term.state_init() for term in self.all_terms())

    def states_coefficients(self, h) -> tuple:
        return tuple(term.state_coefficients(h) for term in self.all_terms())

    def states_advance(self, z: tuple, v_old, v_new, coef: tuple, c_old=None, c_new=None) -> tuple:
        """The terms' states at t_{n+1} (rigid velocities (6, or 6 per floating frame) at t_n and t_{n+1}; the configurations
        at both ends for the terms that follow them, AbstractTerm.state_advance_config)."""
        return tuple(term.state_advance_config(zi, c_old, v_old, c_new, v_new, ci)
                     for term, zi, ci in zip(self.all_terms(), z, coef, strict=True))

    def states_settle(self, z: tuple, c: Config, start: bool = False) -> tuple:
        """The terms' states at the end of a converged step at configuration c, or at the run's
        initial configuration where `start` (AbstractTerm.state_settle)."""
        return tuple(term.state_settle(zi, c, start) for term, zi in zip(self.all_terms(), z, strict=True))

    # ---------------------------------------------------------------- equations of motion
    def residual(self, c: Config, V0, omega, d_dot, acc, t=0.0, z=None):
        """Virtual work of inertia minus applied forces (eq. 26) for the unknown accelerations
        acc = (dV0/dt (3, inertial), d omega/dt (3, body), d2 d/dt2 (nf)): the sum of the terms' rows.
        Rows: translation (inertial, N), rotation (body, N m), the deformable block's (N).
        `z`: the terms' integrator states at t (states_init's tree; None: those of t = 0)."""
        return jnp.concatenate(self.residual_parts(c, V0, omega, d_dot, acc[:6], acc[6:], t, z))

    def residual_parts(self, c: Config, V0, omega, d_dot, a6, d_acc, t=0.0, z=None):
        """`residual` as (rigid rows (6,), deformable rows (nf,)), with the rigid and the deformable
        unknowns passed apart. Kept apart, JAX sees which rows and unknowns do not touch: the Newton
        preconditioner's rigid rows over the liquid's unknowns (solve/newton.py) are then a
        transpose of the liquid's rigid rows alone, where through one stacked vector every term's
        rows would be linearised and transposed with zero tangents. The vessel's rows are those of
        a prescribed motion where the System has one (`hold`)."""
        rigid, d, _ = self.terms_rows(c, V0, omega, d_dot, a6, d_acc, t, z)
        return self.hold(rigid, a6, t), d

    def terms_rows(self, c: Config, V0, omega, d_dot, a6, d_acc, t=0.0, z=None, vs=None):
        """`residual_parts` before `hold`: the sum of the terms' rows (vessel, deformable, the bodies'
        frames: None where no term has rows there); `vs` the other frames' rigid velocities (Kin.vs)."""
        return self.frame_rows(self.kin(c, V0, omega, d_dot, a6, d_acc, t, vs), z)

    # ---------------------------------------------------------------- energies
    def kinetic_energy(self, c: Config, v):
        """The kinetic energy for the velocity vector v (vessel, [structures,] liquid, [modal])."""
        ves, _, d_dot, _ = self.layout().split(v)
        T = self.frame_kinetic(self.kin(c, ves[:3], ves[3:6], d_dot))
        for o in self.owners():
            T = T + o.extra_kinetic(self, c, v)
        return T

    def potential_energy(self, c: Config):
        z = jnp.zeros(3)
        V = self.frame_potential(self.kin(c, z, z, jnp.zeros(self.nf)))
        for o in self.owners():
            V = V + o.extra_potential(self, c)
        return V

    def energy(self, c: Config, v):
        """(kinetic, potential): the one energy of the whole system."""
        return self.kinetic_energy(c, v), self.potential_energy(c)

    # ---------------------------------------------------------------- scales
    def scales(self):
        """Characteristic mass (kg or kg m^2) of each unknown, to scale residual rows to O(1)."""
        return jnp.concatenate([self.frame_mass_scale(), self.liquid.d_scale()])


def advance_config(c: Config, delta) -> Config:
    """Apply an increment (dX0, Theta, dd): rotations on the group, q_{n+1} = q_n exp(Theta)."""
    return advance_config_parts(c, delta[:6], delta[6:])


def advance_config_parts(c: Config, y, z) -> Config:
    """`advance_config` for the rigid increment y = (dX0, Theta) and the deformable one z apart."""
    return Config(c.X0 + y[:3], quat_multiply(c.q, quat_exp(y[3:6])), c.d + z)


def omega_from_qdot(q, q_dot):
    """omega = 2 G(q) q_dot (body frame)."""
    return 2.0 * G_matrix(q) @ q_dot
