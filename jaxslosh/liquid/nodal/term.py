"""The nodal liquid's term: all tank liquid of the vessel at full order as one block (tanks
stacked block-diagonally), its displacement d relative to the tank on the dofs the slip walls leave
free (docs/theory.md, eqs. 28-32); with elastic tank walls and structures in the vessel's frame, their
nodes too."""
from __future__ import annotations

from typing import Any, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...fem.linalg import solve
from ...fem.slip import rotate_matrix
from ...physics.about import About
from ...physics.terms import Kin, Rows
from ..words import TankWords, element_words
from ..cost import nodal_bytes
from ..base import (AbstractLiquid, StepInverse, dense_step_inverse, inertial_lines, switch_inertial, nodal_product, particle_rows,
                    point_mass_scale)
from .sparse import hydrostatic_start, sparse_solver_blocks
from .tank_modes import nodal_sloshing_modes, nodal_unknowns


class NodalLiquid(AbstractLiquid):
    """All tank liquid of the vessel, full order, as one block (tanks stacked block-diagonally);
    with elastic tank walls and structures in the vessel's frame, their nodes too."""
    r: jax.Array          # (N, 3) node positions in the vessel frame (COG origin)
    Ms: Any               # (N, N) scalar mass matrix (3N mass = kron(Ms, I3)); liquid/nodal/sparse.HostSparse on large meshes
    K: Any                # (nf, nf) stiffness on the free dofs; HostSparse on large meshes
    free: jax.Array       # (nf,) indices of the free dofs in the node-major 3N vector
    n_nodes: int = eqx.field(static=True)
    coriolis: bool = eqx.field(static=True, default=True)
    centrifugal: bool = eqx.field(static=True, default=True)
    # elastic tank walls (liquid/walls.py): (3N,) the unknown of each nodal dof (nf: held at zero); a
    # liquid's wall-normal dof shares the wall's unknown. None: `free` lists the free dofs
    dof_map: Optional[jax.Array] = None
    # large meshes (liquid/nodal/sparse.py): each tank's box grid ((nx, ny, nz, surface bending scale,
    # element form), ...) in the stacking order, for the fast-diagonalization inverse (liquid/nodal/boxsolve.py)
    grids: Optional[tuple] = eqx.field(static=True, default=None)
    sparse: bool = eqx.field(static=True, default=False)
    # large meshes of other shapes: the constant block's solves by SciPy's sparse LU on the host
    # (`simulation.linear_solver = "sparse-host"`), not by the JAX factors of solve/factored.py
    host_lu: bool = eqx.field(static=True, default=False)
    # tanks of other shapes (jaxslosh/geometry): each node's frame (N, 3, 3); the unknowns are the free
    # components in these frames (tangential on a wall). None: the vessel's axes everywhere
    frames: Optional[jax.Array] = None
    # (3N,) the position of each nodal dof in [d; 0] (nf: held at zero): `full` as a gather, where a
    # scatter into the nodal vector compiles to a loop on the CPU (None: the scatter)
    slot: Optional[jax.Array] = None
    about: About = eqx.field(static=True, default=About())     # its tanks (and walls, structures)

    def describe(self) -> tuple:
        return inertial_lines(self)

    def with_effects(self, coriolis: bool, centrifugal: bool, about: About) -> "NodalLiquid":
        return switch_inertial(self, coriolis, centrifugal, about)

    @property
    def nf(self) -> int:
        return int(self.free.shape[0])

    def full(self, d):
        """(nf,) free-dof vector -> (N, 3) nodal field, zero on the wall-normal dofs (with elastic
        walls: equal to the wall's there, through `dof_map`)."""
        if self.dof_map is not None:
            return jnp.concatenate([d, jnp.zeros(1, d.dtype)])[self.dof_map].reshape(self.n_nodes, 3)
        if self.slot is not None:
            D = jnp.concatenate([d, jnp.zeros(1, d.dtype)])[self.slot].reshape(self.n_nodes, 3)
        else:
            D = jnp.zeros(3 * self.n_nodes, d.dtype).at[self.free].set(d).reshape(self.n_nodes, 3)
        return D if self.frames is None else jnp.einsum("nij,nj->ni", self.frames, D)

    def for_batch(self) -> "NodalLiquid":
        # Under vmap, XLA's batched gather of the nodal field (`slot`) made the residual 35-45 %
        # slower than the scatter (docs/benchmarks.md, compile time); a single run keeps the gather, whose
        # program compiles faster.
        return eqx.tree_at(lambda liquid: liquid.slot, self, None, is_leaf=lambda x: x is None)

    def free_part(self, F):
        """The transpose of `full`: nodal forces -> generalized forces on the free dofs."""
        if self.dof_map is not None:
            nf = self.free.shape[0]
            return jax.ops.segment_sum(F.reshape(-1), self.dof_map, nf + 1)[:nf]
        if self.frames is not None:
            F = jnp.einsum("nji,nj->ni", self.frames, F)
        return F.reshape(-1)[self.free]

    @property
    def m_nodes(self):
        return self.Ms.sum(axis=1)

    def total_mass(self):
        return self.Ms.sum()

    def rigid_first_moment(self):
        return self.m_nodes @ self.r

    def roundoff(self, d):
        return jnp.zeros(())          # linear rows: the solver's own floor

    def surface_heave(self, d, nodes):
        return self.nodal_fields(self.frame_field(d))[nodes, 2]

    def probe_modal(self, weights):
        return None                   # the probes read the nodal field

    def rows(self, k: Kin) -> Rows:
        """Eq. (4): the particle accelerations (body components), their inertia forces on the nodes,
        and what they do on the rigid rows and the liquid's own; the stiffness and the gravity load."""
        return particle_rows(self, k, self.full, self.m_nodes, lambda a: nodal_product(self.Ms, a))

    def kinetic(self, k: Kin):
        v = k.A.T @ k.V0 + self.full(k.d_dot) + jnp.cross(k.omega, self.r + self.full(k.c.d))
        return 0.5 * jnp.sum(v * nodal_product(self.Ms, v))

    def potential(self, k: Kin):
        d = k.c.d
        return 0.5 * d @ (self.K @ d) - k.g_b @ (self.m_nodes @ self.full(d))

    def mass_scale(self):
        return point_mass_scale(self.m_nodes, self.r)

    def d_scale(self):
        if self.frames is not None:
            return jnp.repeat(self.m_nodes, 3)[self.free]
        return self.free_part(jnp.repeat(self.m_nodes, 3))

    def frame_field(self, d):
        return self.full(d)

    def nodal_fields(self, D):
        return D

    def probe_displacements(self, weights, modal, d):
        return weights @ self.full(d)

    def constant_blocks(self):
        """(M_ff, K_ff): the mass kron(Ms, I3) and the stiffness on the unknowns, dense (NumPy for
        concrete values): the constant liquid block of the Newton matrix is formed from them."""
        traced = isinstance(self.Ms, jax.core.Tracer)
        xp = jnp if traced else np
        Ms = self.Ms if traced else np.asarray(self.Ms)
        free = np.asarray(self.free)
        if self.dof_map is None:
            M3 = xp.kron(Ms, xp.eye(3))
            if self.frames is not None:
                M3 = rotate_matrix(xp, M3, self.frames if traced else np.asarray(self.frames))
            return M3[np.ix_(free, free)], self.K
        dmap = np.asarray(self.dof_map)         # elastic tank walls: T^T kron(Ms, I3) T
        T = np.zeros((dmap.size, free.size + 1))
        T[np.arange(dmap.size), dmap] = 1.0
        T = T[:, :-1]
        return T.T @ np.kron(Ms, np.eye(3)) @ T, self.K

    @property
    def staged_start(self):
        return not self.sparse

    def step_inverse(self, c_a, c_a_sub=None) -> StepInverse:
        """Dense (liquid/base.py), or on large meshes the sparse path of sparse.py: the box-grid
        fast diagonalization, factors in JAX, or the host's LU."""
        if not self.sparse:
            return dense_step_inverse(self, c_a, c_a_sub)
        step, mass, sub, K = sparse_solver_blocks(self, c_a, c_a_sub)
        return StepInverse(step, mass, sub, abs(K).sum(axis=1))

    @classmethod
    def tank_unknowns(cls, tank) -> int:
        return nodal_unknowns(tank)

    @classmethod
    def sloshing_modes(cls, tank, g: float, n: int = 10):
        return nodal_sloshing_modes(tank, g, n)

    @classmethod
    def tank_bytes(cls, tank, sparse: bool, host_lu: bool = False, rt_dense: bool = False) -> float:
        return nodal_bytes(tank, cls.tank_unknowns(tank), sparse, host_lu)

    @classmethod
    def describe_tank(cls, tank) -> TankWords:
        return element_words(tank)

    @classmethod
    def surface_table(cls, tank, g: float):
        return None             # its validity: the free surface inside the tank (run/validity.py Watch)

    def static_start(self, g_b):
        """The discrete hydrostatic equilibrium K d0 = F_g under the body gravity g_b (docs/theory.md
        item 6): dense, or by host solves on large meshes (sparse.py)."""
        if self.sparse:
            return hydrostatic_start(self, g_b)
        return solve(self.K, self.free_part(self.m_nodes[:, None] * g_b[None, :]))
