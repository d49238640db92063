"""The one interface of the physics: a term of the virtual work (eq. 26) and what every term reads.

A System (system.py) is the sum of its terms: each is an equinox module, abstract or final (STYLE.md),
built once from the scene with only what the scene has (assemble/), and evaluated inside the jitted
step. A term gives

* `rows(k)`: its share of the residual, inertia minus applied forces, for the unknown accelerations
  of `k` (rigid rows: translation in the inertial frame (N), rotation in the body frame (N m); and
  the deformable block's rows for the term that owns it);
* `kinetic(k)` and `potential(k)`: its energies where it has them (0 otherwise);
* `mass_scale()`: its characteristic mass on each rigid row (kg, kg m^2), so that a row over the
  summed scale is an acceleration error.

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
    unknown accelerations (None for energies), the time, the radiation memory force, and what the
    System computes once for all terms: the rotation A(q) and gravity in the body frame."""
    c: Config
    V0: jax.Array           # (3,) inertial
    omega: jax.Array        # (3,) body frame
    d_dot: jax.Array        # (nf,)
    a6: Optional[jax.Array]    # (6,) rigid accelerations: dV0/dt (inertial), d omega/dt (body); None for energies
    d_acc: Optional[jax.Array]  # (nf,) d2 d/dt2 (kept apart from a6: see System.residual_parts)
    t: jax.Array
    mu: Optional[jax.Array]    # (6,) radiation memory force at t, from the integrator's states
    A: jax.Array            # (3, 3) rotation matrix of q
    g_b: jax.Array          # (3,) gravity acceleration in the body frame

    @property
    def acc(self):
        """(6 + nf,) all the unknown accelerations."""
        return jnp.concatenate([self.a6, self.d_acc])

    @property
    def v6(self):
        return jnp.concatenate([self.V0, self.omega])


class Rows(NamedTuple):
    rigid: jax.Array                 # (6,)
    d: Optional[jax.Array] = None    # (nf,) the deformable block's rows (its owner only)


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


def potential_rows(potential, c: Config):
    """The rigid rows of a conservative term: the gradient of its potential V(c) along the step's
    increments, translations (dX0) and body-frame rotations on the group (q exp(Theta))."""
    def along(x):
        return potential(c._replace(X0=c.X0 + x[:3], q=quat_multiply(c.q, quat_exp(x[3:]))))
    return jax.grad(along)(jnp.zeros(6, dtype=c.X0.dtype))
