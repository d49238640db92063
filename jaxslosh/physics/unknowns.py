"""Terms with unknowns of their own: the interface the step sees, and the layout of the unknowns.

Unknowns, in the order the Newton iterations see them (x):

    y   = vessel (dX0, Theta) | the owners' floating frames (dX_s, Theta_s)      "rigid", nonlinear
    alg = the owners' algebraic unknowns (interface frames, multipliers)         solved at t_{n+1}
    z   = the deformable block (liquid) | the owners' deformable unknowns          constant blocks

The dynamic vectors (velocities, accelerations) are [y, z]. Without an owner, alg is empty and
x = [vessel, liquid]: one step serves every system (solve/integrator.py), the owners' constraints
entering it as the cheap part Rc of R = Rm + Rc (an empty set of constraints without them).
The layout holds one owner's unknowns after the vessel's and the liquid's (the flexible
structures, physics/structures.py, which tie any number of bodies through one term; or the rigid
floating bodies and their connections, physics/bodies.py, whose deformable unknowns are the liquid
of the bodies' tanks).
"""
from __future__ import annotations

import abc
from typing import NamedTuple

import jax.numpy as jnp

from .terms import AbstractTerm, Config


class Layout(NamedTuple):
    """Sizes of the blocks of a system's unknowns (static)."""
    S: int          # floating frames beside the vessel's (structures)
    nf: int         # the deformable block's unknowns (liquid)
    m: int          # the owners' deformable unknowns (structures' modal coordinates)
    n_alg: int      # algebraic unknowns (interface frame positions and multipliers)

    @property
    def n_rigid(self) -> int:
        return 6 + 6 * self.S

    @property
    def n_small(self) -> int:
        return self.n_rigid + self.n_alg

    @property
    def n_dyn(self) -> int:
        return self.n_rigid + self.nf + self.m

    @property
    def n(self) -> int:
        return self.n_dyn + self.n_alg

    # without algebraic unknowns x is the dynamic vector itself: no copies in the step (a few small
    # concatenations cost the vessel alone's step a fifth of its time)
    def to_x(self, dyn, alg):
        if not self.n_alg:
            return dyn
        return jnp.concatenate([dyn[:self.n_rigid], alg, dyn[self.n_rigid:]])

    def from_x(self, x):
        """(dyn, alg) of a Newton vector."""
        r, s = self.n_rigid, self.n_small
        if not self.n_alg:
            return x, x[r:s]
        return jnp.concatenate([x[:r], x[s:]]), x[r:s]

    def in_x(self, rows_y, rows_z):
        """Rigid and other dynamic rows in Newton order [y, alg, z], zero on the alg rows."""
        return jnp.concatenate([rows_y, jnp.zeros(self.n_alg, rows_y.dtype), rows_z])

    def split(self, dyn):
        """vessel (6,), frames (S, 6), liquid (nf,), the owners' deformable (m,) of a dynamic vector."""
        r = self.n_rigid
        return dyn[:6], dyn[6:r].reshape(self.S, 6), dyn[r:r + self.nf], dyn[r + self.nf:]


class AbstractOwner(AbstractTerm):
    """A term with unknowns of its own (`unknowns()` not empty): what the System asks of it to
    extend the step's unknowns, rows, constraints, scales, constant blocks and start. Every method
    takes and returns the whole system's vectors in the Layout's order."""

    @abc.abstractmethod
    def start(self, system, c0: Config, v0):
        """(c, v, alg) at t = 0 from the vessel-and-liquid c0, v0 (before any equilibrium)."""

    def settles(self) -> bool:
        """Whether its unknowns start at their static equilibrium (the vessel and the liquid held):
        the structures' do (a mast that starts undeformed would ring with its own weight); the
        floating bodies' start where the scene puts them (physics/bodies.py)."""
        return True

    @abc.abstractmethod
    def carried_velocities(self, system, c: Config, v):
        """v with its unknowns' rates those of moving rigidly with the vessel (after its static start)."""

    @abc.abstractmethod
    def advance(self, c: Config, out: Config, y, z) -> Config:
        """`out` with its unknowns advanced from c by its rigid (y) and deformable (z) increments."""

    @abc.abstractmethod
    def add_rows(self, system, c: Config, core_y, core_z, vy, vz, ay, az, t=0.0, z=None):
        """The rows (y, z) from the vessel-and-liquid ones: its own appended, its forces added (at
        time t, with its own integrator states z: AbstractTerm.state_init)."""

    @abc.abstractmethod
    def extra_kinetic(self, system, c: Config, v):
        """Its kinetic energy for the dynamic velocity vector v."""

    @abc.abstractmethod
    def extra_potential(self, system, c: Config):
        """Its potential energy."""

    @abc.abstractmethod
    def add_scales(self, y, z):
        """The rigid and deformable scales (characteristic masses) with its own appended."""

    @abc.abstractmethod
    def constraint(self, system, c: Config, alg):
        """Its constraints g (positions), concatenated."""

    @abc.abstractmethod
    def constraint_rows(self, system, c: Config, alg, g_rows, gscale):
        """Its constraints' rows in Newton order (x-sized): forces of the multipliers and `g_rows`
        (g, or its second time derivative at the start) times `gscale`."""

    @abc.abstractmethod
    def alg_scales(self, row_factor, err_factor):
        """(gscale, the alg part of the error scale)."""

    @abc.abstractmethod
    def block_diagonal(self, c_m, c_k):
        """The diagonal of its deformable unknowns' block of c_m M + c_k K (constant)."""

    def exact(self) -> bool:
        """Whether its deformable unknowns join the exact block of the Newton matrix, linearised at
        every preconditioner as the rigid ones are (a nonlinear liquid's few coordinates: a body's
        multimodal tank, physics/bodies.py), instead of the constant block (static)."""
        return False

    def deformable_block(self, c_m, c_k):
        """Its deformable unknowns' block of c_m M + c_k K (constant): its diagonal (m,) where the
        block is diagonal (the structures' modal one), else the block (m, m) (the bodies' tank liquid)."""
        return self.block_diagonal(c_m, c_k)

    @abc.abstractmethod
    def initial_constraint_rows(self, system, c: Config, v, alg0, mscale):
        """x -> its constraint rows of the initial accelerations (x: accelerations and alg)."""

    @abc.abstractmethod
    def initial_alg(self, alg0, alg_a):
        """The algebraic unknowns at t = 0 from alg0 and the solved ones."""
