"""The multimodal liquid's term (the contract of liquid/base.py): every tank's liquid as a
multimodal tank (term.py ModalTank, or tank3d.py's), their modal coordinates stacked; past the
method's range the rows of steep.py carry each tank on."""
from __future__ import annotations

import dataclasses
from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp

from ...physics.about import About
from ...physics.kinematics import mv3, tv3
from ...physics.terms import Kin, Rows
from ..base import AbstractLiquid, dense_step_inverse
from .steep import roundoff_floor, steep_rows
from .tank_modes import multimodal_sloshing_modes, multimodal_unknowns
from ..words import TankWords
from ..cost import nodal_bytes
from .watch import SurfaceTable, multimodal_words, surface_table


class MultimodalLiquid(AbstractLiquid):
    """Every tank's liquid as a multimodal tank (ModalTank), the modal coordinates stacked."""
    tanks: tuple                      # ModalTank per tank
    sizes: tuple = eqx.field(static=True)     # modes per tank
    samples: jax.Array                # (Ns, nf) surface elevation at sample points of every tank (validity)
    gravity: jax.Array                # m/s^2, for the rest stiffness
    about: About = eqx.field(static=True, default=About())     # its tanks
    # (N, nf): the vertical displacement of the nodes of the tanks' surface meshes per modal coordinate
    # (liquid/multimodal/build.py surface_meshes: what a result keeps to draw and export); None: no fields
    fields: Optional[jax.Array] = None
    sparse = False

    nonlinear = True

    def describe(self) -> tuple:
        return self.about.lines

    def with_effects(self, coriolis: bool, centrifugal: bool, about: About) -> "MultimodalLiquid":
        # its inertial loads are the modal Lagrangian's, not switched by [effects]
        return dataclasses.replace(self, about=about)

    def step_inverse(self, c_a, c_a_sub=None):
        return dense_step_inverse(self, c_a, c_a_sub)

    @classmethod
    def tank_unknowns(cls, tank) -> int:
        return multimodal_unknowns(tank)

    @classmethod
    def sloshing_modes(cls, tank, g: float, n: int = 10):
        return multimodal_sloshing_modes(tank, g, n)

    # counted as a nodal tank on its `mesh` would be: an upper bound of its few modal blocks
    @classmethod
    def tank_bytes(cls, tank, sparse: bool, host_lu: bool = False, rt_dense: bool = False) -> float:
        return nodal_bytes(tank, cls.tank_unknowns(tank), sparse, host_lu)

    @classmethod
    def describe_tank(cls, tank) -> TankWords:
        return multimodal_words(tank)

    @classmethod
    def surface_table(cls, tank, g: float) -> SurfaceTable:
        return surface_table(tank, g)

    @property
    def n_nodes(self) -> int:
        return 0 if self.fields is None else int(self.fields.shape[0])

    @property
    def nf(self) -> int:
        return int(sum(self.sizes))

    def _split(self, v):
        out, i = [], 0
        for n in self.sizes:
            out.append(v[i:i + n])
            i += n
        return out

    def rows(self, k: Kin) -> Rows:
        A, omega = k.A, k.omega
        Vb = tv3(A, k.V0)
        Vb_dot = tv3(A, k.a6[:3]) - jnp.cross(omega, Vb)
        f, m, rd = jnp.zeros(3), jnp.zeros(3), []
        for t, be, bd, bdd in zip(self.tanks, self._split(k.c.d), self._split(k.d_dot), self._split(k.d_acc)):
            # past the method's range, what carries the tank on (multimodal_steep.py); within it, its rows
            ft, mt, rt = steep_rows(t, Vb, omega, be, bd, Vb_dot, k.a6[3:6], bdd, k.g_b, self.gravity)
            f, m = f + ft, m + mt
            rd.append(rt)
        return Rows(jnp.concatenate([mv3(A, f), m]), jnp.concatenate(rd))

    def kinetic(self, k: Kin):
        Vb = tv3(k.A, k.V0)
        return sum((t.kinetic(Vb, k.omega, be, bd) for t, be, bd in
                    zip(self.tanks, self._split(k.c.d), self._split(k.d_dot))), jnp.zeros(()))

    def potential(self, k: Kin):
        return self._potential(k.c.d, k.g_b)

    def _potential(self, d, g_b):
        return sum((t.potential(be, g_b) for t, be in zip(self.tanks, self._split(d))), jnp.zeros(()))

    def mass_scale(self):
        m = sum(t.mass for t in self.tanks)
        I = jnp.zeros(3)
        for t in self.tanks:
            J = t.moments(t.integrals(jnp.zeros(t.n)))[1]
            I = I + jnp.trace(J) - jnp.diag(J)
        return jnp.concatenate([jnp.full(3, m), I])

    def d_scale(self):
        return jnp.concatenate([t.modal_mass() for t in self.tanks])

    def total_mass(self):
        return sum((t.mass for t in self.tanks), jnp.zeros(()))

    def rigid_first_moment(self):
        return sum((t.rest_moment() for t in self.tanks), jnp.zeros(3))

    def constant_blocks(self):
        """The modal rows' mass and stiffness at rest (they precondition Newton; the rows are exact)."""
        M = jnp.diag(self.d_scale())
        Kd = jnp.concatenate([t.modal_mass() * t.omega_linear(self.gravity) ** 2 for t in self.tanks])
        return M, jnp.diag(Kd)

    def frame_field(self, d):
        return d

    def roundoff(self, d):
        """The rows' round-off floor, m/s^2 (`roundoff_floor`, multimodal_steep.py: their terms grow as
        exp(2 k_N zeta_max) under the highest crest and cancel)."""
        return sum((roundoff_floor(t, be, self.gravity) for t, be in zip(self.tanks, self._split(d))), jnp.zeros(()))

    def nodal_fields(self, D):
        """Modal coordinates (..., nf) -> the surface meshes' nodal displacements (..., N, 3), vertical."""
        if self.fields is None:
            return D
        z = D @ self.fields.T
        return jnp.stack([jnp.zeros_like(z), jnp.zeros_like(z), z], axis=-1)

    def probe_displacements(self, weights, modal, d):
        return jnp.einsum("pkc,k->pc", modal, d)

    def surface_heave(self, d, nodes):
        return (self.samples @ d)[nodes]

    def probe_modal(self, weights):
        return None       # its probes' rows come from the scene (build.py probe_modal: the block's probe_rows)

    def for_batch(self) -> "MultimodalLiquid":
        return self

    def static_start(self, g_b):
        """The level surface under the initial gravity direction: the minimum of the potential (Newton)."""
        beta = jnp.zeros(self.nf)
        grad = jax.grad(self._potential)
        for _ in range(4):
            beta = beta - jnp.linalg.solve(jax.jacfwd(grad)(beta, g_b), grad(beta, g_b))
        return beta
