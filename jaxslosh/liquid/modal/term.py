"""The tank liquid on a modal basis (liquid/modal/reduction.py builds the basis): d = V eta.

The reduced equations are the Galerkin projection of the full ones (liquid.py), written with the
inertia invariants of the basis, computed once (Exudyn's ObjectFFRFreducedOrder does the same): with
T(P, Q) = sum_ij Ms_ij P_i Q_j^T (3x3) for nodal fields P, Q,

    S0 = sum_i m_i r_i,  U1_k = sum_i m_i U_k,i,  Q0 = T(r, r),  Q1_k = T(r, U_k),  Q2_kl = T(U_k, U_l)

so a residual costs O(m^2) small products, independent of the mesh. The rigid rows, the modal rows,
the kinetic and the potential energy are those of the full model at d = V eta, to round-off
(tests/fem/test_reduction.py checks them against liquid.py).
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ...fem.linalg import solve
from ...physics.kinematics import mv3, tv3
from ...physics.about import About
from ..words import TankWords, element_words
from ..cost import basis_bytes
from ..base import AbstractLiquid, dense_step_inverse, inertial_lines, switch_inertial, point_mass_scale
from ..face.tank_modes import face_sloshing_modes, face_unknowns
from ..nodal.tank_modes import nodal_sloshing_modes, nodal_unknowns
from ...physics.terms import Kin, Rows


class ModalLiquid(AbstractLiquid):
    """All tank liquid on a modal basis: d = V eta (eta: m modal coordinates, every tank's stacked).

    The invariants (see the module docstring) replace the dense N x N mass products of `NodalLiquid`."""
    r: jax.Array          # (N, 3) node positions in the vessel frame (for scales and outputs)
    m_nodes: jax.Array    # (N,) lumped nodal masses (row sums of the scalar mass)
    U: jax.Array          # (m, N, 3) the basis as nodal fields (zero on the wall-normal dofs)
    mass: jax.Array       # total liquid mass
    S0: jax.Array         # (3,) sum_i m_i r_i
    U1: jax.Array         # (m, 3) sum_i m_i U_k,i
    Q0: jax.Array         # (3, 3) T(r, r)
    Q1: jax.Array         # (m, 3, 3) T(r, U_k)
    Q2: jax.Array         # (m, m, 3, 3) T(U_k, U_l)
    Mr: jax.Array         # (m, m) V^T M V (the identity for concrete values)
    Kr: jax.Array         # (m, m) V^T K V
    row_scale: jax.Array  # (m,) a mass per modal row, so that row / scale is an acceleration (m/s^2)
    n_nodes: int = eqx.field(static=True)
    coriolis: bool = eqx.field(static=True, default=True)
    centrifugal: bool = eqx.field(static=True, default=True)
    about: About = eqx.field(static=True, default=About())     # its tanks and their bases
    sparse = False

    def describe(self) -> tuple:
        return inertial_lines(self)

    def with_effects(self, coriolis: bool, centrifugal: bool, about: About) -> "ModalLiquid":
        return switch_inertial(self, coriolis, centrifugal, about)

    @property
    def nf(self) -> int:
        return int(self.Mr.shape[0])

    def full(self, eta):
        """(m,) modal coordinates -> (N, 3) nodal displacement field."""
        return jnp.einsum("k,knc->nc", eta, self.U)

    def first_moment(self, eta):
        return self.U1.T @ eta

    def _W(self, eta):
        """T(x, U_l) for the deformed positions x = r + U eta: (m, 3, 3)."""
        return self.Q1 + jnp.einsum("k,klab->lab", eta, self.Q2)

    def second_moment(self, eta, W=None):
        """J = T(x, x) = sum_ij Ms_ij x_i x_j^T (3x3)."""
        W = self._W(eta) if W is None else W
        return self.Q0 + jnp.einsum("l,lab->ab", eta, W + jnp.swapaxes(self.Q1, 1, 2))

    def rows(self, k: Kin) -> Rows:
        """The liquid's share of the residual (liquid.Liquid.rows) at d = V eta: rigid translation
        rows (inertial), rigid rotation rows (body), modal rows."""
        A, omega, g_b, eta_dot = k.A, k.omega, k.g_b, k.d_dot
        eta, eta_dd = k.c.d, k.d_acc
        a0, alpha = k.a6[:3], k.a6[3:6]
        b = tv3(A, a0)
        W = self._W(eta)
        J = self.second_moment(eta, W)
        Sx = self.S0 + self.U1.T @ eta
        # translation: sum_j m_j a_j
        s = self.mass * b + self.U1.T @ eta_dd + jnp.cross(alpha, Sx)
        # rotation: sum_ij Ms_ij x_i x a_j
        Txa = jnp.einsum("l,lab->ab", eta_dd, W)
        f_r = jnp.cross(Sx, b) + _axial(Txa) + jnp.trace(J) * alpha - mv3(J, alpha)
        # modal rows: sum_ij Ms_ij U_k,i . a_j
        r_d = mv3(self.U1, b) + self.Mr @ eta_dd + mv3(_axial(W), alpha)
        if self.coriolis:
            v1 = self.U1.T @ eta_dot
            s = s + 2.0 * jnp.cross(omega, v1)
            Txv = jnp.einsum("l,lab->ab", eta_dot, W)
            f_r = f_r + 2.0 * (jnp.trace(Txv) * omega - tv3(Txv, omega))
            Tvu = jnp.einsum("l,lkab->kab", eta_dot, self.Q2)            # T(v, U_k)
            r_d = r_d + 2.0 * mv3(_axial(Tvu), omega)
        if self.centrifugal:
            s = s + jnp.cross(omega, jnp.cross(omega, Sx))
            f_r = f_r + jnp.cross(mv3(J, omega), omega)
            r_d = r_d + jnp.einsum("a,kba,b->k", omega, W, omega) - (omega @ omega) * jnp.trace(W, axis1=1, axis2=2)
        r_d = r_d - mv3(self.U1, g_b) + self.Kr @ eta
        f_r = f_r - jnp.cross(self.U1.T @ eta, g_b)
        return Rows(jnp.concatenate([mv3(A, s), f_r]), r_d)

    def kinetic(self, k: Kin):
        c = k.A.T @ k.V0
        eta, eta_dot, omega = k.c.d, k.d_dot, k.omega
        W = self._W(eta)
        J = self.second_moment(eta, W)
        Sx = self.S0 + self.U1.T @ eta
        Txv = jnp.einsum("l,lab->ab", eta_dot, W)
        return 0.5 * (self.mass * c @ c + 2.0 * c @ (self.U1.T @ eta_dot) + 2.0 * c @ jnp.cross(omega, Sx)
                      + eta_dot @ (self.Mr @ eta_dot) + 2.0 * omega @ _axial(Txv)
                      + omega @ (jnp.trace(J) * omega - J @ omega))

    def potential(self, k: Kin):
        eta = k.c.d
        return 0.5 * eta @ (self.Kr @ eta) - k.g_b @ (self.U1.T @ eta)

    def mass_scale(self):
        return point_mass_scale(self.m_nodes, self.r, self.mass)

    def d_scale(self):
        return self.row_scale

    def total_mass(self):
        return self.mass

    def rigid_first_moment(self):
        return self.S0

    def constant_blocks(self):
        return self.Mr, self.Kr

    def surface_heave(self, d, nodes):
        return self.U[:, nodes, 2].T @ d

    def probe_modal(self, weights):
        return jnp.einsum("pn,knc->pkc", weights, self.U)

    def roundoff(self, d):
        return jnp.zeros(())          # linear rows: the solver's own floor

    def for_batch(self) -> "ModalLiquid":
        return self

    def frame_field(self, d):
        return d          # the frames keep eta; the nodal field is formed after the run

    def nodal_fields(self, D):
        return jnp.einsum("...k,knc->...nc", D, self.U)

    def probe_displacements(self, weights, modal, d):
        return jnp.einsum("pkc,k->pc", modal, d)

    def step_inverse(self, c_a, c_a_sub=None):
        return dense_step_inverse(self, c_a, c_a_sub)

    # A reduced tank's basis is cut from its element's modes: it counts and lists those.
    @classmethod
    def tank_unknowns(cls, tank) -> int:
        return (face_unknowns if tank.form.face_normal else nodal_unknowns)(tank)

    @classmethod
    def sloshing_modes(cls, tank, g: float, n: int = 10):
        return (face_sloshing_modes if tank.form.face_normal else nodal_sloshing_modes)(tank, g, n)

    @classmethod
    def tank_bytes(cls, tank, sparse: bool, host_lu: bool = False, rt_dense: bool = False) -> float:
        return basis_bytes(tank, cls.tank_unknowns(tank), sparse)

    @classmethod
    def describe_tank(cls, tank) -> TankWords:
        return element_words(tank, f" on {tank.reduction.modes} modes" if tank.form.face_normal else "",
                             flux=tank.form.face_normal)

    @classmethod
    def surface_table(cls, tank, g: float):
        return None             # its validity: the free surface inside the tank (run/validity.py Watch)

    def static_start(self, g_b):
        """The discrete hydrostatic equilibrium Kr eta = V^T F_g (exact with the static correction)."""
        return solve(self.Kr, self.U1 @ g_b)


def _axial(T):
    """sum_ij Ms_ij P_i x Q_j from T = T(P, Q): the axial vector of T's antisymmetric part (..., 3)."""
    return jnp.stack([T[..., 1, 2] - T[..., 2, 1], T[..., 2, 0] - T[..., 0, 2], T[..., 0, 1] - T[..., 1, 0]], axis=-1)
