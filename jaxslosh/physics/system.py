"""The assembled model: a rigid vessel (floating frame at its COG) carrying liquid in rigid tanks.

Static model, dynamic state (STYLE.md habit 3): `System` holds everything that is constant in the
body frame (the vessel's mass and inertia, hydrostatic coefficients, the liquid's mass and
stiffness matrices on its free dofs); `Config`/`Vel` are the dynamic unknowns.

Generalised coordinates: X0 (inertial position of the vessel COG), q (Euler parameters), d (liquid
displacement relative to the tank, on the dofs the slip walls leave free). Generalised velocities:
V0 = dX0/dt (inertial), omega (body frame), d_dot. Particle kinematics are eq. (1)-(4) of the paper
with d kept in the rotational terms, so the system is Lagrangian with kinetic energy

    T = 1/2 m_v |V0|^2 + 1/2 omega.I_v omega + 1/2 sum_ij Ms_ij v_i.v_j,
    v_i = A^T V0 + d_dot_i + omega x (r_i + d_i)                     (body components)

and potential energy V = V_h(X0, q) + 1/2 d^T K d - g_b(q).(sum_i m_i d_i), where g_b = A^T g is
gravity turning with the body (eq. 32) and V_h the hydrostatic restoring of eqs. (33)-(36). GM_T and
GM_L are for the frozen liquid (PHYSICS.md item 9), so only the liquid's displacement d adds a
gravity moment. The residual below is the virtual work of inertia minus applied forces (eq. 26),
written once as a pure function; tangents come from JAX.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .kinematics import G_matrix, mv3, quat_exp, quat_multiply, rotation_matrix, skew, spin_tensor_components, tv3
from .modal_liquid import ReducedLiquid

# eq. (36): q^T A_phi q = 2 (q0 q1 + q2 q3) = sin(roll) cos(pitch), q^T A_theta q = 2 (q0 q2 - q1 q3)
A_PHI = np.array([[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1], [0, 0, 1, 0]], dtype=float)
A_THETA = np.array([[0, 0, 1, 0], [0, 0, 0, -1], [1, 0, 0, 0], [0, -1, 0, 0]], dtype=float)


class Config(NamedTuple):
    X0: jax.Array      # (3,) inertial position of the vessel COG
    q: jax.Array       # (4,) Euler parameters, scalar first
    d: jax.Array       # (nf,) liquid displacement on free dofs, tank frame
    Xs: Optional[jax.Array] = None    # (S, 3) origins of the structures' floating frames (their COG), inertial
    qs: Optional[jax.Array] = None    # (S, 4) their Euler parameters
    eta: Optional[jax.Array] = None   # (m,) their elastic modal coordinates, stacked (multibody.py)


class Hydro(eqx.Module):
    """Linear hydrostatic restoring about the initial equilibrium (eqs. 33-36)."""
    rho_w: jax.Array
    gravity: jax.Array
    waterplane_area: jax.Array
    displaced_volume: jax.Array
    gm_t: jax.Array
    gm_l: jax.Array
    moment_form: str = eqx.field(static=True, default="conservative")

    def force(self, X0):
        """Eq. (35) in the inertial frame: F_z = -rho g A_w (Z0 - Z0^0), equilibrium at Z0^0 = 0."""
        return jnp.array([0.0, 0.0, -self.rho_w * self.gravity * self.waterplane_area * X0[2]])

    def moment_paper(self, q):
        """Eq. (36), body frame."""
        k = self.rho_w * self.gravity * self.displaced_volume
        return -k * jnp.array([self.gm_t * (q @ A_PHI @ q), self.gm_l * (q @ A_THETA @ q), 0.0])

    def potential(self, X0, q):
        """Restoring energy. The moment part, k_T g_y^2 + k_L g_x^2 over (1 + g_z) with g = A^T e_z,
        is 1/2 (k_T roll^2 + k_L pitch^2) to second order, exact for pure roll and pure pitch, and
        its gradient is eq. (36) exactly when GM_T = GM_L (eq. (36) is not conservative otherwise)."""
        k = self.rho_w * self.gravity * self.displaced_volume
        g = rotation_matrix(q)[2]
        heave = 0.5 * self.rho_w * self.gravity * self.waterplane_area * X0[2] ** 2
        return heave + k * (self.gm_t * g[1] ** 2 + self.gm_l * g[0] ** 2) / (1.0 + g[2])

    def moment(self, q):
        if self.moment_form == "paper":
            return self.moment_paper(q)
        # conservative: minus the derivative of the potential along body-frame rotations. With
        # g = A^T e_z, a body rotation d theta changes g by g x d theta, so M = g x dV/dg.
        k = self.rho_w * self.gravity * self.displaced_volume
        g = rotation_matrix(q)[2]
        D = 1.0 + g[2]
        N = self.gm_t * g[1] ** 2 + self.gm_l * g[0] ** 2
        dV_dg = k * jnp.array([2.0 * self.gm_l * g[0] / D, 2.0 * self.gm_t * g[1] / D, -N / D ** 2])
        return jnp.cross(g, dV_dg)


class Forced(eqx.Module):
    """Prescribed harmonic motion of one rigid dof (the others held at zero): the rigid rows of the
    residual prescribe the accelerations, scaled by the rigid masses like the free rows."""
    dof: int = eqx.field(static=True)      # 0-2 surge, sway, heave; 3-5 roll, pitch, yaw
    amplitude: jax.Array
    frequency: jax.Array
    ramp: float = eqx.field(static=True, default=0.0)
    profile: str = eqx.field(static=True, default="harmonic")
    rate: float = eqx.field(static=True, default=0.0)      # spin-up: final rate, rad/s
    duration: float = eqx.field(static=True, default=1.0)  # spin-up: its time, s

    def value(self, t):
        if self.profile == "spin-up":
            T, W = self.duration, self.rate
            c = T / (2.0 * jnp.pi)
            up = W / T * (0.5 * t * t + c * c * (jnp.cos(t / c) - 1.0))
            return jnp.where(t < T, up, W * (0.5 * T) + W * (t - T))
        x = self.amplitude * jnp.sin(self.frequency * t)
        if self.ramp > 0:
            x = x * jnp.where(t < self.ramp, 0.5 * (1.0 - jnp.cos(jnp.pi * t / self.ramp)), 1.0)
        return x

    def rates(self, t):
        """Prescribed (dX0/dt, omega) at time t."""
        v = jax.jvp(self.value, (t,), (jnp.ones_like(t),))[1]
        return jnp.zeros(6).at[self.dof].set(v)

    def accelerations(self, t):
        a = jax.jvp(lambda tt: jax.jvp(self.value, (tt,), (jnp.ones_like(tt),))[1], (t,), (jnp.ones_like(t),))[1]
        return jnp.zeros(6).at[self.dof].set(a)

    def rigid_rows(self, acc, t, scale):
        """The prescribed accelerations (a single-axis rotation has omega_dot = theta_ddot e);
        positions and velocities follow by the scheme from the prescribed initial rates."""
        return scale * (acc[:6] - self.accelerations(t))


class Liquid(eqx.Module):
    """All tank liquid of the vessel, as one block (tanks stacked block-diagonally)."""
    r: jax.Array          # (N, 3) node positions in the vessel frame (COG origin)
    Ms: jax.Array         # (N, N) scalar mass matrix (3N mass = kron(Ms, I3))
    K: jax.Array          # (nf, nf) stiffness on the free dofs
    free: jax.Array       # (nf,) indices of the free dofs in the node-major 3N vector
    n_nodes: int = eqx.field(static=True)
    Kdt: Optional[jax.Array] = None   # (nf, 3) d-theta block of the absolute-rotation penalty
    Ktt: Optional[jax.Array] = None   # (3, 3) theta-theta block
    # elastic tank walls (tankwalls.py): (3N,) the unknown of each nodal dof (nf: held at zero); a
    # liquid's wall-normal dof shares the wall's unknown. None: `free` lists the free dofs
    dof_map: Optional[jax.Array] = None
    # structures in the vessel's frame with centrifugal stiffening: (6, nf, nf) per component of
    # omega omega^T (structure.centrifugal_stiffness), None without
    Kg: Optional[jax.Array] = None
    # large meshes (sparse.py): each tank's box grid ((nx, ny, nz, surface bending scale, element
    # form), ...) in the stacking order, for the fast-diagonalization inverse (boxsolve.py)
    grids: Optional[tuple] = eqx.field(static=True, default=None)

    def full(self, d):
        """(nf,) free-dof vector -> (N, 3) nodal field, zero on the wall-normal dofs (with elastic
        walls: equal to the wall's there, through `dof_map`)."""
        if self.dof_map is not None:
            return jnp.concatenate([d, jnp.zeros(1, d.dtype)])[self.dof_map].reshape(self.n_nodes, 3)
        return jnp.zeros(3 * self.n_nodes, d.dtype).at[self.free].set(d).reshape(self.n_nodes, 3)

    def free_part(self, F):
        """The transpose of `full`: nodal forces -> generalized forces on the free dofs."""
        if self.dof_map is not None:
            nf = self.free.shape[0]
            return jax.ops.segment_sum(F.reshape(-1), self.dof_map, nf + 1)[:nf]
        return F.reshape(-1)[self.free]

    @property
    def m_nodes(self):
        return self.Ms.sum(axis=1)


class System(eqx.Module):
    mass: jax.Array                 # vessel mass (no liquid)
    inertia: jax.Array              # (3, 3) about the vessel COG, body axes
    gravity: jax.Array              # m/s^2, along -Z
    hydro: Optional[Hydro]
    liquid: Optional[Liquid]
    forced: Optional[Forced] = None
    g_fixed: Optional[jax.Array] = None   # body-frame gravity on the liquid when it does not turn (effect off)
    q_ref: Optional[jax.Array] = None     # attitude at which the liquid's absolute rotation is zero (t = 0)
    balanced: bool = eqx.field(static=True, default=True)      # weight balanced by static buoyancy
    coriolis: bool = eqx.field(static=True, default=True)
    centrifugal: bool = eqx.field(static=True, default=True)
    flex: Optional[object] = None         # flexible structures and their interfaces (multibody.Flex)
    # first moment (kg m, body frame) of the hull's own mass about the frame origin. The scene's
    # vessel mass and inertia are the whole ship's but the liquid (SPEC), about its COG; flexible
    # structures and elastic tank walls carry their own mass, so the hull is the ship less them,
    # and its COG is off the origin by hull_S / mass. None: at the origin
    hull_S: Optional[jax.Array] = None
    sea: Optional[eqx.Module] = None      # waves and hull hydrodynamics (hydrodynamics.Seakeeping)

    @property
    def nf(self) -> int:
        if isinstance(self.liquid, ReducedLiquid):
            return self.liquid.nf
        return 0 if self.liquid is None else int(self.liquid.free.shape[0])

    @property
    def n(self) -> int:
        return 6 + self.nf

    def total_mass(self):
        m = self.mass
        if isinstance(self.liquid, ReducedLiquid):
            m = m + self.liquid.mass
        elif self.liquid is not None:
            m = m + self.liquid.Ms.sum()
        return m

    # ---------------------------------------------------------------- equations of motion
    def residual(self, c: Config, V0, omega, d_dot, acc, t=0.0, mu=None):
        """Virtual work of inertia minus applied forces (eq. 26) for the unknown accelerations
        acc = (dV0/dt (3, inertial), d omega/dt (3, body), d2 d/dt2 (nf)). Rows: translation
        (inertial, N), rotation (body, N m), liquid free dofs (N). `mu` (6,): the radiation memory
        force at t (hydrodynamics.py), from the integrator's radiation states."""
        A = rotation_matrix(c.q)
        a0, alpha = acc[:3], acc[3:6]
        g_vec = jnp.array([0.0, 0.0, -self.gravity])
        g_b = tv3(A, g_vec) if self.g_fixed is None else self.g_fixed
        r_t = self.mass * a0
        r_r = mv3(self.inertia, alpha) + jnp.cross(omega, mv3(self.inertia, omega))
        if self.hull_S is not None:    # a reference point off the hull's COG (eq. 14 with r_G)
            S = self.hull_S
            r_t = r_t + mv3(A, jnp.cross(alpha, S) + jnp.cross(omega, jnp.cross(omega, S)))
            r_r = r_r + jnp.cross(S, tv3(A, a0))
            if not self.balanced:
                r_r = r_r - jnp.cross(S, g_b)
        parts = []
        if isinstance(self.liquid, ReducedLiquid):    # modal liquid: the same rows from its inertia invariants (reduction.py)
            f_t, f_r, r_d = self.liquid.rows(self, c, omega, d_dot, acc, A, g_b)
            r_t, r_r = r_t + f_t, r_r + f_r
            parts.append(r_d)
        elif self.liquid is not None:
            L = self.liquid
            D, Dv, Da = L.full(c.d), L.full(d_dot), L.full(acc[6:])
            x = L.r + D
            a = tv3(A, a0) + Da + jnp.cross(alpha, x)                     # eq. (4), body components
            if self.coriolis:
                a = a + 2.0 * jnp.cross(omega, Dv)
            if self.centrifugal:
                a = a + jnp.cross(omega, jnp.cross(omega, x))
            F = L.Ms @ a                                             # inertia forces on nodes
            r_t = r_t + mv3(A, F.sum(axis=0))
            r_r = r_r + jnp.cross(x, F).sum(axis=0)
            mD = L.m_nodes @ D                                       # first moment of d
            r_d = L.free_part(F - L.m_nodes[:, None] * g_b) + L.K @ c.d
            if L.Kg is not None:    # a spin-dependent stiffness: the prestress follows the current spin
                r_d = r_d + jnp.einsum("k,kij,j->i", jnp.stack(spin_tensor_components(omega)), L.Kg, c.d)
            if L.Kdt is not None:   # the penalty on the absolute rotation curl d + 2 theta (PHYSICS.md item 5)
                th, J = self.liquid_rotation(c.q, with_jacobian=True)
                r_d = r_d + mv3(L.Kdt, th)
                r_r = r_r + tv3(J, L.Kdt.T @ c.d + mv3(L.Ktt, th))
            parts.append(r_d)
            if self.balanced:
                r_r = r_r - jnp.cross(mD, g_b)
            else:
                r_r = r_r - jnp.cross(L.m_nodes @ L.r + mD, g_b)
        if self.hydro is not None:
            r_t = r_t - self.hydro.force(c.X0)
            r_r = r_r - self.hydro.moment(c.q)
        if not self.balanced:
            r_t = r_t - self.total_mass() * g_vec
        rigid = jnp.concatenate([r_t, r_r])
        if self.sea is not None:   # waves and hull hydrodynamics: excitation, added mass, memory (hydrodynamics.py)
            rigid = rigid + self.sea.rigid_rows(acc[:6], jnp.concatenate([V0, omega]), t, mu)
        if self.forced is not None:
            rigid = self.forced.rigid_rows(acc, t, self.scales()[:6])
        return jnp.concatenate([rigid, *parts])

    def liquid_rotation(self, q, with_jacobian=False):
        """theta = 2 vec(q_ref^-1 q): the small rotation of the body since the reference attitude
        (body frame); with its derivative along body-frame rotation increments, d theta / d eps."""
        dq = quat_multiply(jnp.concatenate([self.q_ref[:1], -self.q_ref[1:]]), q)
        sgn = jnp.where(dq[0] < 0, -1.0, 1.0)
        th = 2.0 * sgn * dq[1:]
        if not with_jacobian:
            return th
        return th, sgn * (dq[0] * jnp.eye(3) + skew(dq[1:]))

    def _penalty(self, d, q):
        """The theta-dependent part of the rotation-penalty energy: d^T K_dt theta + 1/2 theta^T K_tt theta."""
        L = self.liquid
        th = self.liquid_rotation(q)
        return d @ (L.Kdt @ th) + 0.5 * th @ (L.Ktt @ th)

    # ---------------------------------------------------------------- energies
    def kinetic_energy(self, c: Config, V0, omega, d_dot):
        T = 0.5 * self.mass * V0 @ V0 + 0.5 * omega @ self.inertia @ omega
        if self.hull_S is not None:
            T = T + V0 @ (rotation_matrix(c.q) @ jnp.cross(omega, self.hull_S))
        if isinstance(self.liquid, ReducedLiquid):
            return T + self.liquid.kinetic_energy(rotation_matrix(c.q), V0, omega, c.d, d_dot)
        if self.liquid is not None:
            L = self.liquid
            A = rotation_matrix(c.q)
            v = A.T @ V0 + L.full(d_dot) + jnp.cross(omega, L.r + L.full(c.d))
            T = T + 0.5 * jnp.sum(v * (L.Ms @ v))
        if self.sea is not None:   # the added mass at infinite frequency moves with the hull
            T = T + self.sea.kinetic_energy(jnp.concatenate([V0, omega]))
        return T

    def potential_energy(self, c: Config):
        V = jnp.zeros(())
        A = rotation_matrix(c.q)
        g_b = A.T @ jnp.array([0.0, 0.0, -self.gravity]) if self.g_fixed is None else self.g_fixed
        if self.hydro is not None:
            V = V + self.hydro.potential(c.X0, c.q)
        if not self.balanced:
            V = V + self.total_mass() * self.gravity * c.X0[2]
            if self.hull_S is not None:
                V = V - g_b @ self.hull_S
        if isinstance(self.liquid, ReducedLiquid):
            return V + self.liquid.potential_energy(self, c.q, c.d, g_b)
        if self.liquid is not None:
            L = self.liquid
            V = V + 0.5 * c.d @ (L.K @ c.d) - g_b @ (L.m_nodes @ L.full(c.d))
            if L.Kdt is not None:
                V = V + self._penalty(c.d, c.q)
            if not self.balanced:
                V = V - g_b @ (L.m_nodes @ L.r)
        return V

    # ---------------------------------------------------------------- scales
    def scales(self):
        """Characteristic mass (kg or kg m^2) of each unknown, to scale residual rows to O(1)."""
        m = self.total_mass()
        I = jnp.diag(self.inertia)
        if self.liquid is not None:
            L = self.liquid
            x = L.r
            I = I + jnp.array([
                L.m_nodes @ (x[:, 1] ** 2 + x[:, 2] ** 2),
                L.m_nodes @ (x[:, 0] ** 2 + x[:, 2] ** 2),
                L.m_nodes @ (x[:, 0] ** 2 + x[:, 1] ** 2)])
        s = [jnp.full(3, m), I]
        if self.sea is not None:   # added mass at infinite frequency (hydrodynamics.py)
            a = self.sea.added_mass_diagonal()
            s = [s[0] + a[:3], s[1] + a[3:]]
        if isinstance(self.liquid, ReducedLiquid):
            s.append(self.liquid.row_scale)
        elif self.liquid is not None:
            s.append(self.liquid.free_part(jnp.repeat(self.liquid.m_nodes, 3)))
        return jnp.concatenate(s)


def advance_config(c: Config, delta) -> Config:
    """Apply an increment (dX0, Theta, dd): rotations on the group, q_{n+1} = q_n exp(Theta)."""
    return Config(c.X0 + delta[:3], quat_multiply(c.q, quat_exp(delta[3:6])), c.d + delta[6:])


def omega_from_qdot(q, q_dot):
    """omega = 2 G(q) q_dot (body frame)."""
    return 2.0 * G_matrix(q) @ q_dot


__all__ = ["Config", "Hydro", "Liquid", "System", "advance_config", "omega_from_qdot", "skew"]
