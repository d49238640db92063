"""The deformable block of the vessel's frame: the tank liquid (eqs. 28-32) at full order, and the
terms that act on it besides its own.

The liquid's displacement d is relative to the tank, on the dofs the slip walls leave free. Its
particle kinematics keep d in the rotational terms (eqs. 1-4), so the coupled system is Lagrangian:

    T = 1/2 sum_ij Ms_ij v_i.v_j,   v_i = A^T V0 + d_dot_i + omega x (r_i + d_i)     (body components)
    V = 1/2 d^T K d - g_b.(sum_i m_i d_i)

with g_b gravity in the body frame (turning with the body: the load of eq. 32). The frozen liquid's
own weight and moment are balanced with the hull's by the displaced water (hydrostatics), or are the
vessel's Weight term; docs/theory.md item 9: GM_T and GM_L are for the frozen liquid, so only d adds a
gravity moment here.
"""
from __future__ import annotations

import abc
from typing import Any, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..fem.linalg import solve
from ..fem.slip import rotate_matrix
from .about import About
from .kinematics import mv3, quat_multiply, skew, spin_tensor_components, tv3
from .terms import AbstractTerm, Config, Kin, Rows


def nodal_product(Ms, a):
    """Ms @ a for a nodal field a (N, 3): three matrix-vector products. XLA's CPU product of a dense
    (N, N) by an (N, 3) takes a general matrix-product path that costs about twice the three
    products (benchmarks/speed/floor.py: the paper example's residual evaluates it at every Newton
    iteration). The sparse paths' matrices (solve/sparse.HostSparse) keep their own product."""
    if not isinstance(Ms, (jax.Array, np.ndarray)) or a.ndim != 2:
        return Ms @ a
    return jnp.stack([Ms @ a[:, i] for i in range(a.shape[1])], axis=1)


def point_mass_scale(m, x, total=None):
    """The rigid rows' scales of point masses m (n,) at x (n, 3), body frame: their total mass for
    the translations and their moments of inertia about the body axes for the rotations."""
    I = jnp.array([m @ (x[:, 1] ** 2 + x[:, 2] ** 2), m @ (x[:, 0] ** 2 + x[:, 2] ** 2),
                   m @ (x[:, 0] ** 2 + x[:, 1] ** 2)])
    return jnp.concatenate([jnp.full(3, m.sum() if total is None else total), I])

class AbstractLiquid(AbstractTerm):
    """The owner of the deformable unknowns d: what the solver, the build and the frames need of it
    besides its rows and energies."""
    #: its rows are nonlinear in d (physics/multimodal.py): Newton linearises its few unknowns with the
    #: rigid ones instead of using a constant block (solve/linear.py)
    nonlinear = False

    @property
    @abc.abstractmethod
    def nf(self) -> int:
        """Its unknowns."""

    @abc.abstractmethod
    def d_scale(self):
        """(nf,) a mass per row, so that a row over it is an acceleration."""

    def roundoff(self, d):
        """The round-off floor of its scaled rows at d beyond the solver's own (solve/linear.Solver.noise),
        which the Newton iterations aim at when it is above the tolerance: none for a linear liquid."""
        return jnp.zeros(())

    @abc.abstractmethod
    def frame_field(self, d):
        """What a saved frame keeps of d (the nodal field, or modal coordinates)."""

    @abc.abstractmethod
    def nodal_fields(self, D):
        """Frames' kept fields (..., k) or (..., N, 3) -> nodal displacement fields (..., N, 3)."""

    @abc.abstractmethod
    def probe_displacements(self, weights, modal, d):
        """(P, 3) displacement of the probes (interpolation `weights` (P, N), or `modal` (P, m, 3))."""

    def surface_heave(self, d, nodes):
        """The vertical displacement (k,) of the nodes `nodes` (the free surface of a tank)."""
        return self.nodal_fields(self.frame_field(d))[nodes, 2]

    def probe_modal(self, weights):
        """The probes' weights on the modal coordinates (P, m, 3), for a liquid whose d is modal."""
        return None

    def rigid_first_moment(self):
        """sum_i m_i r_i (3,) of the undeformed block about the frame origin, kg m."""
        return jnp.zeros(3)

    def for_batch(self) -> "AbstractLiquid":
        """The same liquid in the form a vmapped batch of runs computes fastest."""
        return self


def inertial_lines(liquid) -> tuple:
    """A nodal, face-normal or reduced liquid's lines: its tanks' (its `about`, set at assembly),
    then the inertial loads its `coriolis` and `centrifugal` switches keep."""
    lines = liquid.about.lines
    if liquid.coriolis:
        lines += (("Coriolis", "2 omega x d_dot on the liquid (eq. 19)"),)
    if liquid.centrifugal:
        lines += (("centrifugal", "omega x (omega x r) on the liquid (eq. 19)"),)
    return lines


class NoLiquid(AbstractLiquid):
    """A vessel without tank liquid: no unknowns, no rows."""
    nf = 0
    n_nodes = 0
    sparse = False

    def rows(self, k: Kin) -> Rows:
        return Rows(jnp.zeros(6), jnp.zeros(0))

    def d_scale(self):
        return jnp.zeros(0)

    def frame_field(self, d):
        return jnp.zeros((0, 3))

    def nodal_fields(self, D):
        return D

    def probe_displacements(self, weights, modal, d):
        return jnp.zeros((weights.shape[0], 3))

    def total_mass(self):
        return jnp.zeros(())

    def static_start(self, g_b):
        return jnp.zeros(0)

    def constant_blocks(self):
        return jnp.zeros((0, 0)), jnp.zeros((0, 0))


class Liquid(AbstractLiquid):
    """All tank liquid of the vessel, full order, as one block (tanks stacked block-diagonally);
    with elastic tank walls and structures in the vessel's frame, their nodes too."""
    r: jax.Array          # (N, 3) node positions in the vessel frame (COG origin)
    Ms: Any               # (N, N) scalar mass matrix (3N mass = kron(Ms, I3)); solve/sparse.HostSparse on large meshes
    K: Any                # (nf, nf) stiffness on the free dofs; HostSparse on large meshes
    free: jax.Array       # (nf,) indices of the free dofs in the node-major 3N vector
    n_nodes: int = eqx.field(static=True)
    coriolis: bool = eqx.field(static=True, default=True)
    centrifugal: bool = eqx.field(static=True, default=True)
    # elastic tank walls (fem/walls.py): (3N,) the unknown of each nodal dof (nf: held at zero); a
    # liquid's wall-normal dof shares the wall's unknown. None: `free` lists the free dofs
    dof_map: Optional[jax.Array] = None
    # large meshes (solve/sparse.py): each tank's box grid ((nx, ny, nz, surface bending scale,
    # element form), ...) in the stacking order, for the fast-diagonalization inverse (solve/boxsolve.py)
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

    def for_batch(self) -> "Liquid":
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

    def rows(self, k: Kin) -> Rows:
        """Eq. (4): the particle accelerations (body components), their inertia forces on the nodes,
        and what they do on the rigid rows and the liquid's own; the stiffness and the gravity load."""
        c, A, omega = k.c, k.A, k.omega
        a0, alpha = k.a6[:3], k.a6[3:6]
        D, Dv, Da = self.full(c.d), self.full(k.d_dot), self.full(k.d_acc)
        x = self.r + D
        a = tv3(A, a0) + Da + jnp.cross(alpha, x)
        if self.coriolis:
            a = a + 2.0 * jnp.cross(omega, Dv)
        if self.centrifugal:
            a = a + jnp.cross(omega, jnp.cross(omega, x))
        F = nodal_product(self.Ms, a)
        mD = self.m_nodes @ D                                       # first moment of d
        r_t = mv3(A, F.sum(axis=0))
        r_r = jnp.cross(x, F).sum(axis=0) - jnp.cross(mD, k.g_b)
        r_d = self.free_part(F - self.m_nodes[:, None] * k.g_b) + self.K @ c.d
        return Rows(jnp.concatenate([r_t, r_r]), r_d)

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

    def static_start(self, g_b):
        """The discrete hydrostatic equilibrium K d0 = F_g under the body gravity g_b (docs/theory.md
        item 6), dense (large meshes: solve/sparse.py)."""
        return solve(self.K, self.free_part(self.m_nodes[:, None] * g_b[None, :]))


class RotationPenalty(AbstractTerm):
    """The stabilized liquid element's penalty on the absolute rotation curl d + 2 theta (docs/theory.md
    item 5): d^T K_dt theta + 1/2 theta^T K_tt theta (its d-d block is in the liquid's K), with theta
    the small rotation of the body since the attitude at which the liquid is irrotational (the start).
    Rows by JAX from this potential."""
    Kdt: jax.Array        # (nf, 3)
    Ktt: jax.Array        # (3, 3)
    q_ref: jax.Array      # (4,)

    def describe(self) -> tuple:
        return (("rotation penalty", "the liquid's absolute rotation held at zero (docs/theory.md item 5): "
                                     "no spurious rotational modes of the element"),)

    def rotation(self, q):
        """theta = 2 vec(q_ref^-1 q): the small rotation since the reference attitude (body frame),
        and its derivative along body-frame rotation increments, d theta / d eps."""
        dq = quat_multiply(jnp.concatenate([self.q_ref[:1], -self.q_ref[1:]]), q)
        sgn = jnp.where(dq[0] < 0, -1.0, 1.0)
        return 2.0 * sgn * dq[1:], sgn * (dq[0] * jnp.eye(3) + skew(dq[1:]))

    def energy(self, c: Config):
        th, _ = self.rotation(c.q)
        return c.d @ (self.Kdt @ th) + 0.5 * th @ (self.Ktt @ th)

    def rows(self, k: Kin) -> Rows:
        """The gradient of `energy` along the increments, written out (tests/physics/test_model.py checks it
        with the liquid's: the whole residual against the gradient of the potential)."""
        th, J = self.rotation(k.c.q)
        d = k.c.d
        return Rows(jnp.concatenate([jnp.zeros(3), tv3(J, self.Kdt.T @ d + mv3(self.Ktt, th))]), mv3(self.Kdt, th))

    def potential(self, k: Kin):
        return self.energy(k.c)


class SpinStiffening(AbstractTerm):
    """Structures in the vessel's frame with centrifugal stiffening: the geometric stiffness of the
    stress the spin causes, K_G(omega) = sum_k (omega omega^T)_k K_k (fem/structure.py). It follows
    the current spin, so it has no potential of its own. The structures' unknowns are the block's
    last ones, from `offset` on (the liquid's come first)."""
    Kg: jax.Array         # (6, n, n) on the unknowns offset ... offset + n
    about: About = eqx.field(static=True, default=About())     # the stiffened structures
    offset: int = eqx.field(static=True, default=0)

    def rows(self, k: Kin) -> Rows:
        W = jnp.stack(spin_tensor_components(k.omega))
        d = k.c.d
        n = self.Kg.shape[1]
        f = jnp.einsum("k,kij,j->i", W, self.Kg, d[self.offset:self.offset + n])
        return Rows(jnp.zeros(6), jnp.concatenate([jnp.zeros(self.offset, d.dtype), f,
                                                   jnp.zeros(d.shape[0] - self.offset - n, d.dtype)]))

    def describe(self) -> tuple:
        return self.about.lines
