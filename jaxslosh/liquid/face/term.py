"""The face-normal liquid element ("rt", liquid/face/element.py) at full order: the unknowns d are the
volumes moved through the free faces (m^3), and the displacement inside each element is its
Raviart-Thomas field u = sum_f phi_f d_f.

The kinetic energy of the element is the integral of rho |v|^2 at its 2 x 2 x 2 Gauss points (the
consistent RT0 mass liquid/face/element.py assembles), so the liquid is written as liquid/base.py's
`NodalLiquid` with the Gauss points as its particles, each with the diagonal mass rho det J: the same
particle kinematics (eqs. 1-4)

    T = 1/2 sum_g m_g |A^T V0 + u_g' + omega x (r_g + u_g)|^2,   V = 1/2 d^T K d - g_b . sum_g m_g u_g,

with u_g = G d (each Gauss point's field from the six faces of its element). K's kernel (the
circulation modes, divergence-free with no surface flux) has no stiffness of the liquid's own: an
ideal liquid's absolute flow stays irrotational (Kelvin), so relative to the tank its circulation
is the part -P C theta of the tank's rotation it does not follow. The penalty
1/2 kappa |P (d + C theta)|_M^2 (liquid/base.py RotationPenalty: its d-d block is in K) holds it
there, as the reduced basis does on its three circulation vectors (liquid/face/element.py face_basis);
without it, a start with the tank turning (an initial angular velocity) would leave the liquid
with the rigid rotation's vorticity, and second-order terms would drift in the kernel. With it, K
is definite and the hydrostatic start solves K d0 = F_g.

Outputs and probes read the nodal field of the element's patch recovery (FaceModel.nodal_field),
here as fixed weights of each Gauss point's displacement on the nodes of its element.

Elastic tank walls (liquid/face/walls.py): their free nodal dofs are unknowns after the faces', a wall
face's flux is a fixed combination of them (`wall_rows`, `wall_cols`, `wall_coef`: the map Tw as
triplets), and the walls are particles too, at their elements' Gauss points (`n_liquid_points`
splits r and m), each moving with the trilinear interpolation of its element's nodal unknowns.
Their nodes follow each tank's liquid nodes in the nodal fields.

Structures in the vessel's frame (assemble/structures.py HeldStructure) take the same road without
the faces: their free nodal dofs are unknowns after every tank's, their Gauss points particles
after the walls', and no face's flux is tied to them. Their nodes come last in the nodal fields.
"""
from __future__ import annotations

from typing import Any, Optional

import equinox as eqx
import jax
import jax.numpy as jnp

from ...fem.linalg import solve
from ...physics.about import About
from ..words import TankWords, element_words
from ..cost import face_bytes
from ..base import AbstractLiquid, StepInverse, dense_step_inverse, inertial_lines, switch_inertial, particle_rows, point_mass_scale
from .inverse import face_solver_blocks
from .tank_modes import face_sloshing_modes, face_unknowns
from ...physics.terms import Kin, Rows


class FaceLiquid(AbstractLiquid):
    """All tank liquid on face fluxes (tanks stacked: every tank's free faces, then the next's)."""
    r: jax.Array          # (G, 3) Gauss points in the vessel frame
    m: jax.Array          # (G,) their masses rho det J
    phi: jax.Array        # (G, 6, 3) the six face fields of each Gauss point's element there
    slots: jax.Array      # (G, 6) each field's unknown (nf: a held face, zero)
    K: Any                # (nf, nf) stiffness (compression, free surface, circulation penalty); sparse:
    #                       liquid/face/blocks.FaceStiffness, kappa M + B^T Y B
    Mff: Any              # (nf, nf) the consistent mass on the unknowns (the Newton block); sparse: None
    scale: jax.Array      # (nf,) a mass per row (M_ff's diagonal times the face's area: row / scale in m/s^2)
    rec_nodes: jax.Array  # (G, 8) the nodes the recovery spreads each Gauss point's field on
    rec_w: jax.Array      # (G, 8) and its weights
    n_nodes: int = eqx.field(static=True)
    # sparse (no dense matrix on the faces): M^-1 (liquid/face/inverse.MassInverse) and the static
    # start's columns K^-1 F for unit gravity along each axis (nf, 3), both formed at build time
    Minv: Any = None
    start: Any = None
    sparse: bool = eqx.field(static=True, default=False)
    # the sparse blocks' `phi` element by element, (E, 6, P * 3): each element's six face fields at its P
    # points, faces before points, the layout XLA's CPU products over the elements read without a copy.
    # From `phi` (G, 6, 3) as a parameter of the step, each residual copied it to this layout twice (the
    # field and the forces), 0.5 MB each on the horizontal cylinder 6x12x6, most of the residual's time
    # (docs/benchmarks.md, the shaped tanks against their floor); None: the points' own slots
    phi_e: Optional[jax.Array] = None
    # elastic walls and structures in the vessel's frame (None without): the wall faces' fluxes
    # qw = segment_sum(coef * d[cols], rows), held in slots nf + 1 + j of the liquid points' gathers;
    # the wall (and structure) points' shape values (Gw, 8) and their corners' unknowns (Gw, 8, 3);
    # each node's own unknown (n_nodes, 3) (nf: a liquid node or a held one)
    wall_rows: Optional[jax.Array] = None
    wall_cols: Optional[jax.Array] = None
    wall_coef: Optional[jax.Array] = None
    wall_N: Optional[jax.Array] = None
    wall_slots: Optional[jax.Array] = None
    node_slots: Optional[jax.Array] = None
    n_wall_faces: int = eqx.field(static=True, default=0)
    n_liquid_points: int = eqx.field(static=True, default=-1)     # -1: every point is the liquid's
    coriolis: bool = eqx.field(static=True, default=True)
    centrifugal: bool = eqx.field(static=True, default=True)
    about: About = eqx.field(static=True, default=About())     # its tanks

    def describe(self) -> tuple:
        return inertial_lines(self)

    def with_effects(self, coriolis: bool, centrifugal: bool, about: About) -> "FaceLiquid":
        return switch_inertial(self, coriolis, centrifugal, about)

    @property
    def nf(self) -> int:
        return int(self.K.shape[0])

    def _by_element(self) -> int:
        """Points per element where every point's six unknowns are its element's, as the blocks
        without dense matrices on the faces have them (no walls or structures; the points element
        by element, assemble/face_liquid.py): the gathers and scatters then run over the elements'
        slots (FaceOps), a P-th of the points' (0: the points' own slots)."""
        if self.phi_e is None or self.wall_N is not None:
            return 0
        return self.r.shape[0] // self.K.ops.slots.shape[0]

    def field(self, d):
        """(nf,) unknowns -> (G, 3) displacements at the points (the liquid's Gauss points, then the
        walls')."""
        P = self._by_element()
        if P:                   # (a batched product over the elements: XLA's CPU fuses it as a loop)
            return jnp.einsum("efx,ef->ex", self.phi_e, self.K.ops.gather(d)).reshape(-1, 3)
        dz = jnp.concatenate([d, jnp.zeros(1, d.dtype)])
        if self.wall_N is None:
            return jnp.einsum("gfi,gf->gi", self.phi, dz[self.slots])
        qw = jax.ops.segment_sum(self.wall_coef * d[self.wall_cols], self.wall_rows, self.n_wall_faces)
        u = jnp.einsum("gfi,gf->gi", self.phi, jnp.concatenate([dz, qw])[self.slots])
        return jnp.concatenate([u, jnp.einsum("ga,gai->gi", self.wall_N, dz[self.wall_slots])])

    def free_part(self, F):
        """The transpose of `field`: forces (G, 3) at the points -> generalized forces (nf,)."""
        nf = self.nf
        P = self._by_element()
        if P:                   # each element's six unknowns summed over its points, then scattered
            return self.K.ops.scatter(jnp.einsum("efx,ex->ef", self.phi_e, F.reshape(self.phi_e.shape[0], -1)))
        if self.wall_N is None:
            local = jnp.einsum("gfi,gi->gf", self.phi, F)
            return jax.ops.segment_sum(local.reshape(-1), self.slots.reshape(-1), nf + 1)[:nf]
        G = self.n_liquid_points
        local = jnp.einsum("gfi,gi->gf", self.phi, F[:G])
        acc = jax.ops.segment_sum(local.reshape(-1), self.slots.reshape(-1), nf + 1 + self.n_wall_faces)
        out = acc[:nf] + jax.ops.segment_sum(self.wall_coef * acc[nf + 1:][self.wall_rows], self.wall_cols, nf)
        wl = self.wall_N[:, :, None] * F[G:][:, None, :]
        return out + jax.ops.segment_sum(wl.reshape(-1), self.wall_slots.reshape(-1), nf + 1)[:nf]

    def total_mass(self):
        return self.m.sum()

    def rigid_first_moment(self):
        return self.m @ self.r

    def roundoff(self, d):
        return jnp.zeros(())          # linear rows: the solver's own floor

    def surface_heave(self, d, nodes):
        return self.nodal_fields(self.frame_field(d))[nodes, 2]

    def probe_modal(self, weights):
        return None                   # the probes read the recovered nodal field

    def for_batch(self) -> "FaceLiquid":
        return self

    def rows(self, k: Kin) -> Rows:
        return particle_rows(self, k, self.field, self.m, lambda a: self.m[:, None] * a)

    def kinetic(self, k: Kin):
        v = k.A.T @ k.V0 + self.field(k.d_dot) + jnp.cross(k.omega, self.r + self.field(k.c.d))
        return 0.5 * jnp.sum(self.m[:, None] * v * v)

    def potential(self, k: Kin):
        d = k.c.d
        return 0.5 * d @ (self.K @ d) - k.g_b @ (self.m @ self.field(d))

    def mass_scale(self):
        return point_mass_scale(self.m, self.r)

    def d_scale(self):
        return self.scale

    def frame_field(self, d):
        return d          # the frames keep the fluxes; the nodal field is formed after the run

    def nodal_fields(self, D):
        """Face fluxes (..., nf) -> the recovered nodal displacement fields (..., N, 3)."""
        def one(d):
            u = self.field(d)[:self.rec_w.shape[0]]                     # (G, 3) the liquid's points
            contrib = self.rec_w[:, :, None] * u[:, None, :]            # (G, 8, 3)
            out = jax.ops.segment_sum(contrib.reshape(-1, 3), self.rec_nodes.reshape(-1), self.n_nodes)
            if self.node_slots is None:
                return out
            return out + jnp.concatenate([d, jnp.zeros(1, d.dtype)])[self.node_slots]   # the walls' nodes
        flat = D.reshape((-1, D.shape[-1]))
        return jax.vmap(one)(flat).reshape(D.shape[:-1] + (self.n_nodes, 3))

    def probe_displacements(self, weights, modal, d):
        return weights @ self.nodal_fields(d)

    def constant_blocks(self):
        """(M_ff, K_ff) dense; the sparse liquid's formed from its products (the solver does not ask
        for them: liquid/face/inverse.py)."""
        if self.sparse:
            eye = jnp.eye(self.nf)
            return self.Minv.ops.elementwise(self.Minv.Me, eye), self.K @ eye
        return self.Mff, self.K

    def step_inverse(self, c_a, c_a_sub=None) -> StepInverse:
        """Dense (liquid/base.py), or sparse: the Schur complement's blocks (inverse.py)."""
        if not self.sparse:
            return dense_step_inverse(self, c_a, c_a_sub)
        return StepInverse(*face_solver_blocks(self, c_a, c_a_sub))

    @classmethod
    def tank_unknowns(cls, tank) -> int:
        return face_unknowns(tank)

    @classmethod
    def sloshing_modes(cls, tank, g: float, n: int = 10):
        return face_sloshing_modes(tank, g, n)

    @classmethod
    def tank_bytes(cls, tank, sparse: bool, host_lu: bool = False, rt_dense: bool = False) -> float:
        return face_bytes(tank, rt_dense)

    @classmethod
    def describe_tank(cls, tank) -> TankWords:
        return element_words(tank, " at full order", flux=True)

    @classmethod
    def surface_table(cls, tank, g: float):
        return None             # its validity: the free surface inside the tank (run/validity.py Watch)

    def static_start(self, g_b):
        """The discrete hydrostatic equilibrium K d0 = F_g: K holds the absolute-rotation penalty on
        the circulation, so it is definite, and the load of a uniform field has no circulation part
        (the start is at rest in the kernel). Sparse: the columns formed at build time."""
        if self.start is not None:
            return self.start @ g_b
        return solve(self.K, self.free_part(self.m[:, None] * g_b[None, :]))
