"""Flexible substructures in their own floating frames, tied by localized Lagrange multipliers
(paper eqs. 12-27): the partitioned system of eq. (27) around the vessel-and-liquid core of system.py.

Unknowns, in the order the Newton iterations see them (x):

    y   = vessel (dX0, Theta) | per structure s: (dX_s, Theta_s)        "rigid", nonlinear
    alg = per interface: frame positions X_f (n, 3), then per side k its multipliers lambda_k (n, 3)
    z   = liquid free dofs d | per structure: elastic modal coordinates eta_s    constant blocks

The dynamic vectors (velocities, accelerations) are [y, z]; `alg` is algebraic (solved at t_{n+1}).

A structure's deformation is u = Phi eta in its own frame (structure.py: range(Phi) = range(P^T), so
eta is the paper's filtered d in the basis that makes M_P and K_P diagonal). Its particle kinematics
keep u in the rotational terms (eq. 4), so the inertia forces include the centrifugal
(P M Omega R_r omega) and Coriolis (2 P Omega M d_dot) terms of eq. (19) and the system stays
Lagrangian. Each interface is a frame of n nodes with independent positions X_f (inertial) and,
for each side tied to it, its own multipliers in that side's body frame (eq. 24):

    structure side:  g = A_s^T (X_s - X_f) + r + u   = 0      (structure frame)
    vessel side:     g = A_v^T (X_v - X_f) + rho     = 0      (vessel frame, rho from the vessel COG)
    frame:           sum_k A_k lambda_k              = 0      (frame equilibrium, last row of eq. 27)

Constraint forces are the transposed constraint Jacobian times the multipliers (a vector-Jacobian
product through the configuration update, so rotations are varied on the group like every other
row). Constraint rows are scaled to forces by m_ref / (beta h^2) (PHYSICS.md item 8).

Gravity: with hydrostatics (a floating vessel whose GM_T, GM_L are for the whole frozen ship) the
structures' weight is balanced like the liquid's: its potential is -m_s g . (X_s - X_v - A_v c_s),
the work of the displacement of the structure's centre of gravity away from where the frozen ship
would carry it. Without hydrostatics, gravity acts in full.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp

from .kinematics import quat_exp, quat_multiply, rotation_matrix, spin_tensor_components
from .terms import Config


class Body(eqx.Module):
    """One elastic structure (structure.StructureModel) as the time loop needs it."""
    r: jax.Array          # (N, 3) node positions from its centre of gravity, structure frame
    Ms: jax.Array         # (N, N) scalar mass
    Phi: jax.Array        # (3N, m) elastic modes, mass-orthonormal
    omega2: jax.Array     # (m,) their squared angular frequencies
    mass: jax.Array       # total mass
    c0: jax.Array         # (3,) its centre of gravity in the vessel frame at rest
    Kg: Optional[jax.Array] = None   # (6, m, m) centrifugal stiffness per component of omega omega^T

    @property
    def n_modes(self) -> int:
        return int(self.Phi.shape[1])

    def u(self, eta):
        return (self.Phi @ eta).reshape(-1, 3)


class Side(eqx.Module):
    """One body tied to an interface frame: the vessel (body = -1, `points` in the vessel frame from
    its COG) or structure `body` (its nodes `nodes`, in the frame's node order)."""
    body: int = eqx.field(static=True)
    nodes: jax.Array
    points: jax.Array


class Interface(eqx.Module):
    sides: tuple
    m_ref: jax.Array      # kg: scales the constraint and frame rows
    L_ref: float = eqx.field(static=True, default=1.0)

    @property
    def n(self) -> int:
        return int(self.sides[0].nodes.shape[0])

    @property
    def size(self) -> int:
        return 3 * self.n * (1 + len(self.sides))


class Flex(eqx.Module):
    bodies: tuple
    interfaces: tuple

    @property
    def S(self) -> int:
        return len(self.bodies)

    @property
    def n_modal(self) -> int:
        return sum(b.n_modes for b in self.bodies)

    @property
    def n_alg(self) -> int:
        return sum(i.size for i in self.interfaces)


class Layout(NamedTuple):
    """Sizes of the blocks of a system's unknowns (static)."""
    S: int          # structures
    nf: int         # liquid free dofs
    m: int          # structure modal coordinates
    n_alg: int      # interface frame positions and multipliers

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

    def to_x(self, dyn, alg):
        return jnp.concatenate([dyn[:self.n_rigid], alg, dyn[self.n_rigid:]])

    def from_x(self, x):
        """(dyn, alg) of a Newton vector."""
        r, s = self.n_rigid, self.n_small
        return jnp.concatenate([x[:r], x[s:]]), x[r:s]

    def split(self, dyn):
        """vessel (6,), structures (S, 6), liquid (nf,), modal (m,) of a dynamic vector."""
        r = self.n_rigid
        return dyn[:6], dyn[6:r].reshape(self.S, 6), dyn[r:r + self.nf], dyn[r + self.nf:]


def layout(system) -> Layout:
    flex = system.flex
    if flex is None:
        return Layout(0, system.nf, 0, 0)
    return Layout(flex.S, system.nf, flex.n_modal, flex.n_alg)


def advance(system, c: Config, delta) -> Config:
    """Apply a dynamic increment: translations added, rotations on the group (q exp(Theta))."""
    r = layout(system).n_rigid
    return advance_parts(system, c, delta[:r], delta[r:])


def advance_parts(system, c: Config, y, z) -> Config:
    """`advance` for the rigid increments y (vessel, structures) and the others z (liquid, modal)
    apart (see inertia_rows_parts)."""
    L = layout(system)
    out = Config(c.X0 + y[:3], quat_multiply(c.q, quat_exp(y[3:6])), c.d + z[:L.nf])
    if L.S == 0:
        return out
    st = y[6:].reshape(L.S, 6)
    qs = jax.vmap(lambda q, th: quat_multiply(q, quat_exp(th)))(c.qs, st[:, 3:])
    return out._replace(Xs=c.Xs + st[:, :3], qs=qs, eta=c.eta + z[L.nf:])


def split_eta(flex: Flex, eta):
    out, k = [], 0
    for b in flex.bodies:
        out.append(eta[k:k + b.n_modes])
        k += b.n_modes
    return out


def split_alg(flex: Flex, alg):
    """Per interface: (X_f (n, 3), [lambda_k (n, 3) per side])."""
    out, k = [], 0
    for itf in flex.interfaces:
        n3 = 3 * itf.n
        Xf = alg[k:k + n3].reshape(-1, 3)
        lams = [alg[k + n3 * (j + 1):k + n3 * (j + 2)].reshape(-1, 3) for j in range(len(itf.sides))]
        out.append((Xf, lams))
        k += itf.size
    return out


def constraint(system, c: Config, alg):
    """g of every side of every interface, concatenated (m)."""
    flex = system.flex
    A_v = rotation_matrix(c.q)
    etas = split_eta(flex, c.eta)
    gs = []
    for itf, (Xf, _) in zip(flex.interfaces, split_alg(flex, alg)):
        for side in itf.sides:
            if side.body < 0:
                g = (c.X0[None, :] - Xf) @ A_v + side.points
            else:
                b = flex.bodies[side.body]
                A_s = rotation_matrix(c.qs[side.body])
                rows = (3 * side.nodes[:, None] + jnp.arange(3)).reshape(-1)
                u = (b.Phi[rows] @ etas[side.body]).reshape(-1, 3)
                g = (c.Xs[side.body][None, :] - Xf) @ A_s + b.r[side.nodes] + u
            gs.append(g.reshape(-1))
    return jnp.concatenate(gs)


def _side_terms(system, c: Config, side, Xf, etas):
    """(A_k, p, u_rows) of a side: its rotation, p = A_k^T (X_k - X_f) per node, and for a structure
    the modal rows of its tied nodes (None for the vessel)."""
    if side.body < 0:
        A = rotation_matrix(c.q)
        return A, (c.X0[None, :] - Xf) @ A, None
    b = system.flex.bodies[side.body]
    A = rotation_matrix(c.qs[side.body])
    rows = (3 * side.nodes[:, None] + jnp.arange(3)).reshape(-1)
    return A, (c.Xs[side.body][None, :] - Xf) @ A, b.Phi[rows]


def _frame_rows(system, c: Config, alg):
    """The multipliers' virtual work lambda . delta g (eq. 24), by hand: for a side with rotation A_k
    and p = A_k^T (X_k - X_f), the translation row gets A_k sum lambda, the rotation row (body-frame
    variations: delta(A^T w) = (A^T w) x delta theta) sum lambda x p, a structure's modal rows
    Phi_tied^T lambda, and the frame rows -A_k lambda (their sum is the frame equilibrium of
    eq. 27's last row). Returns (dyn forces, frame rows per interface); `test_multibody` checks this
    against the vector-Jacobian product of `constraint`."""
    flex = system.flex
    L = layout(system)
    etas = split_eta(flex, c.eta)
    ves = jnp.zeros(6)
    rig = jnp.zeros((L.S, 6))
    modal = [jnp.zeros(b.n_modes) for b in flex.bodies]
    frames = []
    for itf, (Xf, lams) in zip(flex.interfaces, split_alg(flex, alg)):
        fr = jnp.zeros_like(Xf)
        for side, lam in zip(itf.sides, lams):
            A, p, Phi_t = _side_terms(system, c, side, Xf, etas)
            f = jnp.concatenate([A @ lam.sum(axis=0), jnp.cross(lam, p).sum(axis=0)])
            if side.body < 0:
                ves = ves + f
            else:
                rig = rig.at[side.body].add(f)
                modal[side.body] = modal[side.body] + Phi_t.T @ lam.reshape(-1)
            fr = fr - lam @ A.T
        frames.append(fr.reshape(-1))
    f_dyn = jnp.concatenate([ves, rig.reshape(-1), jnp.zeros(L.nf), *modal])
    return f_dyn, frames


def _struct_kinematics(b: Body, A_s, V_s, om, eta, eta_d):
    """Body-frame particle velocities (N, 3) of structure b (eq. 3 with u kept in the rotation)."""
    u = b.u(eta)
    return A_s.T @ V_s + b.u(eta_d) + jnp.cross(om, b.r + u)


def structure_kinetic(system, c: Config, v):
    flex = system.flex
    L = layout(system)
    _, st, _, de = L.split(v)
    T = jnp.zeros(())
    for s, (b, eta, eta_d) in enumerate(zip(flex.bodies, split_eta(flex, c.eta), split_eta(flex, de))):
        w = _struct_kinematics(b, rotation_matrix(c.qs[s]), st[s, :3], st[s, 3:], eta, eta_d)
        T = T + 0.5 * jnp.sum(w * (b.Ms @ w))
    return T


def structure_potential(system, c: Config):
    """Elastic energy 1/2 eta . omega^2 eta plus gravity (balanced against the frozen ship when the
    vessel floats on hydrostatics; see the module docstring)."""
    flex = system.flex
    g_vec = jnp.array([0.0, 0.0, -system.gravity])
    A_v = rotation_matrix(c.q)
    V = jnp.zeros(())
    for s, (b, eta) in enumerate(zip(flex.bodies, split_eta(flex, c.eta))):
        V = V + 0.5 * eta @ (b.omega2 * eta)
        x = c.Xs[s]
        if system.balanced:
            x = x - c.X0 - A_v @ b.c0
        V = V - b.mass * g_vec @ x
    return V


def inertia_rows(system, c: Config, v, acc, t, z=None):
    """Dyn rows without the multipliers: the vessel-and-liquid residual of model.py, each structure's
    rigid and elastic inertia rows, and the forces of the structures' potential (elastic, gravity)."""
    r = layout(system).n_rigid
    return jnp.concatenate(inertia_rows_parts(system, c, v[:r], v[r:], acc[:r], acc[r:], t, z))


def inertia_rows_parts(system, c: Config, vy, vz, ay, az, t, z=None, core=True):
    """`inertia_rows` as (rigid rows (n_rigid,), the others (nf + m,)), with the rates of the rigid
    unknowns (y: vessel, structures) and of the others (z: liquid, modal) passed apart, as
    System.residual_parts does for the vessel and its liquid (the Newton preconditioner's rigid rows
    over z are then a transpose in z alone). `core=False`: without the vessel-and-liquid terms (zero
    on the liquid's rows, the structures' balance alone on the vessel's)."""
    L = layout(system)
    ves_v, st_v, d_v, e_v = vy[:6], vy[6:].reshape(L.S, 6), vz[:L.nf], vz[L.nf:]
    ves_a, st_a, d_a, e_a = ay[:6], ay[6:].reshape(L.S, 6), az[:L.nf], az[L.nf:]
    if core:
        core_y, core_z = system.residual_parts(c, ves_v[:3], ves_v[3:], d_v, ves_a, d_a, t, z)
    else:
        core_y, core_z = jnp.zeros(6), jnp.zeros(L.nf)
    flex = system.flex
    rigid_s, modal = [], []
    for s, (b, eta, eta_d, eta_dd) in enumerate(zip(flex.bodies, split_eta(flex, c.eta), split_eta(flex, e_v),
                                                     split_eta(flex, e_a))):
        A_s = rotation_matrix(c.qs[s])
        om, al = st_v[s, 3:], st_a[s, 3:]
        x = b.r + b.u(eta)
        a = A_s.T @ st_a[s, :3] + b.u(eta_dd) + jnp.cross(al, x) + 2.0 * jnp.cross(om, b.u(eta_d)) \
            + jnp.cross(om, jnp.cross(om, x))                       # eq. (4), body components
        F = b.Ms @ a                                                # inertia forces on the nodes
        rigid_s.append(jnp.concatenate([A_s @ F.sum(axis=0), jnp.cross(x, F).sum(axis=0)]))
        r_eta = b.Phi.T @ F.reshape(-1)
        if b.Kg is not None:                                        # centrifugal stiffening (structure.py)
            r_eta = r_eta + jnp.einsum("k,kij,j->i", jnp.stack(spin_tensor_components(om)), b.Kg, eta)
        modal.append(r_eta)
    gy, gz = potential_forces_parts(system, c)
    if system.motion.prescribed:            # the vessel's rows prescribe its motion
        gy = jnp.concatenate([jnp.zeros(6), gy[6:]])
    return jnp.concatenate([core_y, *rigid_s]) + gy, jnp.concatenate([core_z, *modal]) + gz


def constraint_rows(system, c: Config, alg, g_rows, gscale):
    """The multipliers' part, in Newton order [y, alg, z]: their generalized forces on the dynamic
    unknowns (dg/d delta)^T lambda, the frame equilibrium rows, and `g_rows` (the constraints g, or
    their second time derivative at the start) times `gscale` per interface."""
    L = layout(system)
    f_dyn, f_frames = _frame_rows(system, c, alg)
    if system.motion.prescribed:
        f_dyn = f_dyn.at[:6].set(0.0)
    return L.to_x(f_dyn, _alg_rows(system.flex, f_frames, g_rows, gscale))


def potential_forces(system, c: Config):
    """The gradient of `structure_potential` along the increments, by hand (`test_multibody` checks
    it against jax.grad): omega^2 eta on the modal rows, -m_s g on each structure's translation and,
    when balanced, +m_s g on the vessel's translation and c_s x (m_s A_v^T g) on its rotation."""
    return jnp.concatenate(potential_forces_parts(system, c))


def potential_forces_parts(system, c: Config):
    """`potential_forces` as (rigid rows, the others), as inertia_rows_parts."""
    flex = system.flex
    L = layout(system)
    g_vec = jnp.array([0.0, 0.0, -system.gravity])
    A_v = rotation_matrix(c.q)
    ves = jnp.zeros(6)
    rig, modal = [], []
    for b, eta in zip(flex.bodies, split_eta(flex, c.eta)):
        mg = b.mass * g_vec
        rig.append(jnp.concatenate([-mg, jnp.zeros(3)]))
        modal.append(b.omega2 * eta)
        if system.balanced:
            ves = ves + jnp.concatenate([mg, jnp.cross(b.c0, A_v.T @ mg)])
    return jnp.concatenate([ves, *rig]), jnp.concatenate([jnp.zeros(L.nf), *modal])


def residual(system, c: Config, v, acc, alg, t, gscale):
    """All rows in Newton order [y, alg, z] (inertia_rows + constraint_rows)."""
    L = layout(system)
    main = L.to_x(inertia_rows(system, c, v, acc, t), jnp.zeros(L.n_alg))
    return main + constraint_rows(system, c, alg, constraint(system, c, alg), gscale)


def _alg_rows(flex, f_frames, g, gscale):
    rows, k = [], 0
    for itf, fr, gsc in zip(flex.interfaces, f_frames, gscale):
        ng = 3 * itf.n * len(itf.sides)
        rows += [fr, gsc * g[k:k + ng]]
        k += ng
    return jnp.concatenate(rows)


def frame_velocities(system, c: Config, v):
    """alg-shaped vector: each frame node's velocity (that of the point of its first side that
    coincides with it), zero in the multiplier entries."""
    flex = system.flex
    L = layout(system)
    ves, st, _, de = L.split(v)
    A_v = rotation_matrix(c.q)
    etas, etas_d = split_eta(flex, c.eta), split_eta(flex, de)
    out = []
    for itf in flex.interfaces:
        side = itf.sides[0]
        if side.body < 0:
            V = ves[:3][None, :] + jnp.cross(ves[3:], side.points) @ A_v.T
        else:
            b = flex.bodies[side.body]
            A_s = rotation_matrix(c.qs[side.body])
            x = b.r[side.nodes] + b.u(etas[side.body])[side.nodes]
            w = b.u(etas_d[side.body])[side.nodes] + jnp.cross(st[side.body, 3:], x)
            V = st[side.body, :3][None, :] + w @ A_s.T
        out += [V.reshape(-1), jnp.zeros(3 * itf.n * len(itf.sides))]
    return jnp.concatenate(out)


def initial_residuals(system, c: Config, v, alg0, t, mscale, z=None):
    """The initial accelerations as (R_main, R_c, main_parts) of x = [acc_y, (frame accelerations,
    multipliers), acc_z]; the constraint rows are d^2 g / dt^2 = 0 times `mscale` (per interface);
    main_parts(acc_y, acc_z): R_main's rows apart (inertia_rows_parts)."""
    L = layout(system)
    pos_mask = position_mask(system.flex)
    Vf = frame_velocities(system, c, v)
    r = L.n_rigid

    def main_parts(ay, az):
        return inertia_rows_parts(system, c, v[:r], v[r:], ay, az, t, z)

    def R_main(x):
        return in_x(L, *main_parts(x[:r], x[L.n_small:]))

    def R_c(x):
        acc, alg_a = L.from_x(x)
        alg = jnp.where(pos_mask, alg0, alg_a)                 # positions known, multipliers unknown
        gdd = constraint_acceleration(system, c, v, acc, alg0, Vf, jnp.where(pos_mask, alg_a, 0.0))
        return constraint_rows(system, c, alg, gdd, mscale)

    return R_main, R_c, main_parts


def in_x(L: Layout, rows_y, rows_z):
    """Rigid and other dynamic rows in Newton order [y, alg, z], zero on the alg rows."""
    return jnp.concatenate([rows_y, jnp.zeros(L.n_alg, rows_y.dtype), rows_z])


def position_mask(flex):
    m = []
    for itf in flex.interfaces:
        m += [jnp.ones(3 * itf.n, dtype=bool), jnp.zeros(3 * itf.n * len(itf.sides), dtype=bool)]
    return jnp.concatenate(m)


def constraint_acceleration(system, c: Config, v, acc, alg0, alg_v, alg_a):
    """d^2 g / dt^2 along the motion with velocities v and accelerations acc, the frames at alg0
    moving with the velocities alg_v and accelerations alg_a (their multiplier entries unused).
    With p = A^T w, w = X_k - X_f and body rates omega, alpha (A' = A omega~):
    d2/dt2 (A^T w) = -alpha x p + omega x (omega x p) - 2 omega x (A^T w') + A^T w'',
    plus Phi eta'' for a structure (`test_multibody` checks it against nested jvp of `constraint`)."""
    flex = system.flex
    L = layout(system)
    ves_v, st_v, _, e_v = L.split(v)
    ves_a, st_a, _, e_a = L.split(acc)
    etas_a = split_eta(flex, e_a)
    out = []
    for itf, (Xf, _), (Vf, _), (Af, _) in zip(flex.interfaces, split_alg(flex, alg0), split_alg(flex, alg_v),
                                             split_alg(flex, alg_a)):
        for side in itf.sides:
            A, p, Phi_t = _side_terms(system, c, side, Xf, None) if side.body < 0 else \
                _side_terms(system, c, side, Xf, None)
            if side.body < 0:
                V, a, om, al = ves_v[:3], ves_a[:3], ves_v[3:], ves_a[3:]
            else:
                V, a, om, al = st_v[side.body, :3], st_a[side.body, :3], st_v[side.body, 3:], st_a[side.body, 3:]
            wd = (V[None, :] - Vf) @ A
            wdd = (a[None, :] - Af) @ A
            gdd = -jnp.cross(al, p) + jnp.cross(om, jnp.cross(om, p)) - 2.0 * jnp.cross(om, wd) + wdd
            if side.body >= 0:
                gdd = gdd + (Phi_t @ etas_a[side.body]).reshape(-1, 3)
            out.append(gdd.reshape(-1))
    return jnp.concatenate(out)


def scales(system):
    """Characteristic mass of each dynamic unknown (dyn order): the vessel-and-liquid scales of
    model.py, each structure's mass and principal inertia about its COG, and sqrt(m_s) for its
    mass-normalised modal coordinates (so that every row over its scale is an acceleration)."""
    base = system.scales()
    flex = system.flex
    L = layout(system)
    rig, modal = [], []
    for b in flex.bodies:
        mn = b.Ms.sum(axis=1)
        x = b.r
        I = jnp.array([mn @ (x[:, 1] ** 2 + x[:, 2] ** 2), mn @ (x[:, 0] ** 2 + x[:, 2] ** 2),
                       mn @ (x[:, 0] ** 2 + x[:, 1] ** 2)])
        rig.append(jnp.concatenate([jnp.full(3, b.mass), I]))
        modal.append(jnp.full(b.n_modes, jnp.sqrt(b.mass)))
    return jnp.concatenate([base[:6], *rig, base[6:6 + L.nf], *modal])


def alg_scales(system, row_factor, err_factor):
    """Per interface: frame rows (scale m_ref) and constraint rows; returns (gscale per interface:
    the factor the g rows are multiplied by, and the alg part of the error scale)."""
    gsc, sc = [], []
    for itf in system.flex.interfaces:
        f = itf.m_ref * row_factor
        gsc.append(f)
        sc += [jnp.full(3 * itf.n, itf.m_ref), jnp.full(3 * itf.n * len(itf.sides), f * err_factor(itf))]
    return gsc, jnp.concatenate(sc)
