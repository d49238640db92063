"""The one interface of the physics: a term of the virtual work (eq. 26) and what every term reads.

A System (system.py) is the sum of its terms: each is an equinox module, abstract or final (docs/design.md),
built once from the scene with only what the scene has (assemble/), and evaluated inside the jitted
step. A term gives

* `rows(k)`: its share of the residual, inertia minus applied forces, for the unknown accelerations
  of `k` (rigid rows: translation in the inertial frame (N), rotation in the body frame (N m); and
  the deformable block's rows for the term that owns it);
* `kinetic(k)` and `potential(k)`: its energies where it has them (0 otherwise);
* `mass_scale()`: its characteristic mass on each rigid row (kg, kg m^2), so that a row over the
  summed scale is an acceleration error.

Optional hooks of the step, whose defaults are a term without them (the integrator calls them
for every term and never asks which term has what):

* integrator states (`state_init`, `state_coefficients`, `state_advance`): states of the term's
  own that the step advances from t_n to t_{n+1} (the radiation memory); the default is none, a
  zero-size array. A term reads its states at the evaluation's time as `k.z`. The step calls
  `state_advance_config`, which also has the configurations at both ends (a lumped mooring line's
  nodes follow its fairlead) and by default calls `state_advance`; `state_settle` refreshes them once
  the step has converged (by default it leaves them as advanced);
* `update_inverse(inv, c_v)`: the inverse of the deformable block of the step matrix with this
  term's constant velocity tangent added (the modal damping's low-rank update); the default
  leaves it as it is;
* `unknowns()`: unknowns of the term's own beside the vessel's and the deformable block's
  (floating frames, algebraic unknowns with their constraints, deformable coordinates); the
  default is none. A term with unknowns implements the interface of `unknowns.AbstractOwner`
  (the flexible structures, physics/structures.py);
* a constraint on the vessel's rigid unknowns (`prescribes`, `prescribed_rows`): a term that
  prescribes the vessel's motion gives the vessel's six rows of the step itself, in place of every
  term's and owner's share of them (the prescribed motion of `[vessel.forced]`,
  vessel.AbstractPrescribedMotion); the default prescribes nothing.

A term's rows are written out. Where the term has a potential, a test checks its rows against
the potential's gradient along the step's increments (`potential_rows`, by JAX): a gradient inside
the residual would be linearised and transposed again in every Newton preconditioner, which
lengthens compilation; the liquid's rows must also stay linear and sparse for large meshes
(tests/physics/test_model.py checks them against the gradient and the Hessian of its energies).
"""
from __future__ import annotations

import abc
from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp

from .kinematics import quat_exp, quat_multiply


class Config(NamedTuple):
    X0: jax.Array      # (3,) inertial position of the vessel COG
    q: jax.Array       # (4,) Euler parameters, scalar first
    d: jax.Array       # (nf,) the deformable block: liquid displacement on free dofs (tank frame), or modal
    Xs: Optional[jax.Array] = None    # (S, 3) origins of the structures' floating frames (their COG), inertial
    qs: Optional[jax.Array] = None    # (S, 4) their Euler parameters
    eta: Optional[jax.Array] = None   # (m,) their elastic modal coordinates, stacked (structures.py)


class Kin(NamedTuple):
    """What the terms read at one evaluation: the configuration, the rigid and deformable rates, the
    unknown accelerations (None for energies), the time, the evaluated term's own integrator states
    at that time (`AbstractTerm.state_init`; zero-size for a term without), and what the System
    computes once for all terms: the rotation A(q) and gravity in the body frame."""
    c: Config
    V0: jax.Array           # (3,) inertial
    omega: jax.Array        # (3,) body frame
    d_dot: jax.Array        # (nf,)
    a6: Optional[jax.Array]    # (6,) rigid accelerations: dV0/dt (inertial), d omega/dt (body); None for energies
    d_acc: Optional[jax.Array]  # (nf,) d2 d/dt2 (kept apart from a6: see System.residual_parts)
    t: jax.Array
    z: jax.Array            # this term's integrator states at t (zero-size for a term without)
    A: jax.Array            # (3, 3) rotation matrix of q
    g_b: jax.Array          # (3,) gravity acceleration in the body frame
    # (6 S,) the other floating frames' rigid velocities (V inertial, omega body; the [[bodies]]'), for
    # a term with rows on them that reads their rates (a lumped mooring line on a body); None without
    vs: Optional[jax.Array] = None

    @property
    def acc(self):
        """(6 + nf,) all the unknown accelerations."""
        return jnp.concatenate([self.a6, self.d_acc])

    @property
    def v6(self):
        return jnp.concatenate([self.V0, self.omega])


class Unknowns(NamedTuple):
    """A term's own unknowns (static sizes): `frames` floating frames of 6 rigid unknowns each
    (solved with the vessel's), `alg` algebraic ones (multipliers, interface frames: no inertia,
    solved at t_{n+1}) and `deformable` ones (with a constant block, beside the liquid's)."""
    frames: int = 0
    alg: int = 0
    deformable: int = 0


class Rows(NamedTuple):
    rigid: jax.Array                 # (6,)
    d: Optional[jax.Array] = None    # (nf,) the deformable block's rows (its owner only)
    frames: Optional[jax.Array] = None   # (6 S,) rows on the bodies' floating frames (mooring lines on bodies)


class AbstractTerm(eqx.Module):
    """A term of the virtual work."""

    @abc.abstractmethod
    def rows(self, k: Kin) -> Rows:
        """This term's share of the residual."""

    def kinetic(self, k: Kin):
        return jnp.zeros(())

    def potential(self, k: Kin):
        return jnp.zeros(())

    def mass_scale(self):
        return jnp.zeros(6)

    def describe(self) -> tuple:
        """(effect, text) lines: what this term adds to the model, as `jaxslosh check` lists it
        (`- effect: text`); a final term says it from its own fields and its static `About`."""
        return ()

    # ---------------------------------------------------------------- optional hooks of the step
    def state_init(self) -> jax.Array:
        """Its integrator states at t = 0: none (a zero-size array)."""
        return jnp.zeros((0,))

    def state_coefficients(self, h):
        """What advancing its states over a step h needs, formed once per step (outside the iterations)."""
        return ()

    def at_time(self, t) -> "AbstractTerm":
        """This term for the evaluations of one step at time t: what depends on the time alone
        formed once, outside the step's Newton iterations (the residual is evaluated in every
        iteration and every column of its linearisation). The default has nothing of the kind."""
        return self

    def state_advance(self, z, v_old, v_new, coef):
        """Its states at t_{n+1} from those at t_n and the rigid velocities (6,) at both ends (v_new
        is the step's unknown: the states enter the residual through it)."""
        return z

    def state_advance_config(self, z, c_old, v_old, c_new, v_new, coef):
        """`state_advance` for a term whose states follow the vessel's configuration as well as its
        velocities (a lumped mooring line's nodes follow the fairlead's positions at t_n and
        t_{n+1}): the configurations (Config) at both ends are given too, c_new the step's unknown.
        The default ignores them."""
        return self.state_advance(z, v_old, v_new, coef)

    def state_settle(self, z, c: Config, start: bool = False):
        """Its states at t_{n+1} once the step has converged at the configuration c, from those the
        step advanced them to, or (`start`) at the run's initial configuration c, from state_init's:
        unchanged (the default). A term whose states only start iterations
        of its own (the catenary lines' last solution, mooring/term.py) refreshes them here, once a
        step, not in every evaluation of the residual."""
        return z

    def unknowns(self) -> Unknowns:
        """Its own unknowns: none (see unknowns.AbstractOwner for a term that has some)."""
        return Unknowns()

    def prescribes(self) -> bool:
        """Whether it prescribes the vessel's rigid motion (static). Such a term also defines
        `prescribed_rows(a6, t, scale)`: the vessel's six rows of the step, the constraint on its rigid
        accelerations a6 at time t (`scale()`: the rows' masses), which System.hold puts in place of
        the vessel's rows; a System holds at most one such term (vessel.AbstractPrescribedMotion)."""
        return False

    def update_inverse(self, inv, c_v):
        """The inverse of the step matrix's deformable block with this term's c_v dR/d(d_dot) added
        (`inv`: the block's inverse without it, a matrix or an object with `@`): unchanged."""
        return inv


def potential_rows(potential, c: Config):
    """The rigid rows of a conservative term: the gradient of its potential V(c) along the step's
    increments, translations (dX0) and body-frame rotations on the group (q exp(Theta))."""
    def along(x):
        return potential(c._replace(X0=c.X0 + x[:3], q=quat_multiply(c.q, quat_exp(x[3:]))))
    return jax.grad(along)(jnp.zeros(6, dtype=c.X0.dtype))
