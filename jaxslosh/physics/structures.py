"""Flexible substructures in their own floating frames, tied by localized Lagrange multipliers
(paper eqs. 12-27): the partitioned system of eq. (27) around the vessel-and-liquid core of system.py,
as one term that owns unknowns (`Structures`, an unknowns.AbstractOwner: the step sees it only
through the System's layout and hooks).

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
row). Constraint rows are scaled to forces by m_ref / (beta h^2) (docs/theory.md item 8).

Gravity: with hydrostatics (a floating vessel whose GM_T, GM_L are for the whole frozen ship) the
structures' weight is balanced like the liquid's: its potential is -m_s g . (X_s - X_v - A_v c_s),
the work of the displacement of the structure's centre of gravity away from where the frozen ship
would carry it. Without hydrostatics, gravity acts in full.
"""
from __future__ import annotations

from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp

from .kinematics import quat_exp, quat_multiply, rotation_matrix, spin_tensor_components
from .about import About
from .terms import Config, Kin, Rows, Unknowns
from .unknowns import AbstractOwner


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


class Structures(AbstractOwner):
    """The flexible structures and their interfaces as a term of the step: its unknowns beside the
    vessel's and the liquid's (6 rigid per structure, its modal coordinates), the algebraic ones
    (interface frames and multipliers), its constraints and its start (terms.AbstractTerm's hooks
    for extra unknowns). Its rows on the vessel's and the liquid's unknowns are none: its balance of
    the vessel's weight enters through `add_rows`, with its own rows."""
    bodies: tuple
    interfaces: tuple
    about: About = eqx.field(static=True, default=About())     # the structures, as `check` lists them

    def describe(self) -> tuple:
        return self.about.lines

    @property
    def S(self) -> int:
        return len(self.bodies)

    @property
    def n_modal(self) -> int:
        return sum(b.n_modes for b in self.bodies)

    @property
    def n_alg(self) -> int:
        return sum(i.size for i in self.interfaces)

    def rows(self, k: Kin) -> Rows:
        return Rows(jnp.zeros(6))

    def unknowns(self) -> Unknowns:
        return Unknowns(frames=self.S, alg=self.n_alg, deformable=self.n_modal)

    # ------------------------------------------------------------ configuration
    def start(self, system, c0: Config, v0):
        """Structures at rest relative to the vessel, undeformed: frames aligned with the vessel's,
        at their centres of gravity, moving with it; interface frames on the vessel's attachment
        points. Returns (c, v, alg)."""
        A = rotation_matrix(c0.q)
        V, om = v0[:3], v0[3:6]
        Xs = jnp.stack([c0.X0 + A @ b.c0 for b in self.bodies])
        qs = jnp.tile(c0.q, (self.S, 1))
        c = c0._replace(Xs=Xs, qs=qs, eta=jnp.zeros(self.n_modal))
        rig = jnp.concatenate([jnp.concatenate([V + A @ jnp.cross(om, b.c0), om]) for b in self.bodies])
        v = jnp.concatenate([v0[:6], rig, v0[6:], jnp.zeros(self.n_modal)])
        alg = []
        for itf in self.interfaces:
            alg += [(c0.X0[None, :] + itf.sides[0].points @ A.T).reshape(-1), jnp.zeros(3 * itf.n * len(itf.sides))]
        return c, v, jnp.concatenate(alg)

    def carried_velocities(self, system, c: Config, v):
        """Every structure moving rigidly with the vessel: V_s = V + (A omega) x (X_s - X0),
        omega_s = A_s^T A omega; no elastic rates."""
        ves, _, d_v, _ = system.layout().split(v)
        w = rotation_matrix(c.q) @ ves[3:]
        rig = jnp.concatenate([jnp.concatenate([ves[:3] + jnp.cross(w, c.Xs[k] - c.X0),
                                                rotation_matrix(c.qs[k]).T @ w]) for k in range(self.S)])
        return jnp.concatenate([ves, rig, d_v, jnp.zeros(self.n_modal)])

    def advance(self, c: Config, out: Config, y, z) -> Config:
        """`out` with this term's unknowns advanced from c by its rigid increments y (6 per
        structure: translation, rotation on the group) and modal ones z."""
        st = y.reshape(self.S, 6)
        qs = jax.vmap(lambda q, th: quat_multiply(q, quat_exp(th)))(c.qs, st[:, 3:])
        return out._replace(Xs=c.Xs + st[:, :3], qs=qs, eta=c.eta + z)

    def split_eta(self, eta):
        out, k = [], 0
        for b in self.bodies:
            out.append(eta[k:k + b.n_modes])
            k += b.n_modes
        return out

    def split_alg(self, alg):
        """Per interface: (X_f (n, 3), [lambda_k (n, 3) per side])."""
        out, k = [], 0
        for itf in self.interfaces:
            n3 = 3 * itf.n
            Xf = alg[k:k + n3].reshape(-1, 3)
            lams = [alg[k + n3 * (j + 1):k + n3 * (j + 2)].reshape(-1, 3) for j in range(len(itf.sides))]
            out.append((Xf, lams))
            k += itf.size
        return out

    # ------------------------------------------------------------ constraints
    def constraint(self, system, c: Config, alg):
        """g of every side of every interface, concatenated (m)."""
        A_v = rotation_matrix(c.q)
        etas = self.split_eta(c.eta)
        gs = []
        for itf, (Xf, _) in zip(self.interfaces, self.split_alg(alg)):
            for side in itf.sides:
                if side.body < 0:
                    g = (c.X0[None, :] - Xf) @ A_v + side.points
                else:
                    b = self.bodies[side.body]
                    A_s = rotation_matrix(c.qs[side.body])
                    rows = (3 * side.nodes[:, None] + jnp.arange(3)).reshape(-1)
                    u = (b.Phi[rows] @ etas[side.body]).reshape(-1, 3)
                    g = (c.Xs[side.body][None, :] - Xf) @ A_s + b.r[side.nodes] + u
                gs.append(g.reshape(-1))
        return jnp.concatenate(gs)

    def _side_terms(self, c: Config, side, Xf):
        """(A_k, p, u_rows) of a side: its rotation, p = A_k^T (X_k - X_f) per node, and for a
        structure the modal rows of its tied nodes (None for the vessel)."""
        if side.body < 0:
            A = rotation_matrix(c.q)
            return A, (c.X0[None, :] - Xf) @ A, None
        b = self.bodies[side.body]
        A = rotation_matrix(c.qs[side.body])
        rows = (3 * side.nodes[:, None] + jnp.arange(3)).reshape(-1)
        return A, (c.Xs[side.body][None, :] - Xf) @ A, b.Phi[rows]

    def frame_rows(self, system, c: Config, alg):
        """The multipliers' virtual work lambda . delta g (eq. 24), by hand: for a side with rotation
        A_k and p = A_k^T (X_k - X_f), the translation row gets A_k sum lambda, the rotation row
        (body-frame variations: delta(A^T w) = (A^T w) x delta theta) sum lambda x p, a structure's
        modal rows Phi_tied^T lambda, and the frame rows -A_k lambda (their sum is the frame
        equilibrium of eq. 27's last row). Returns (dyn forces, frame rows per interface);
        `test_multibody` checks this against the vector-Jacobian product of `constraint`."""
        L = system.layout()
        ves = jnp.zeros(6)
        rig = jnp.zeros((L.S, 6))
        modal = [jnp.zeros(b.n_modes) for b in self.bodies]
        frames = []
        for itf, (Xf, lams) in zip(self.interfaces, self.split_alg(alg)):
            fr = jnp.zeros_like(Xf)
            for side, lam in zip(itf.sides, lams):
                A, p, Phi_t = self._side_terms(c, side, Xf)
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

    def constraint_rows(self, system, c: Config, alg, g_rows, gscale):
        """The multipliers' part, in Newton order [y, alg, z]: their generalized forces on the
        dynamic unknowns (dg/d delta)^T lambda, the frame equilibrium rows, and `g_rows` (the
        constraints g, or their second time derivative at the start) times `gscale` per interface."""
        f_dyn, f_frames = self.frame_rows(system, c, alg)
        rows, k = [], 0
        for itf, fr, gsc in zip(self.interfaces, f_frames, gscale):
            ng = 3 * itf.n * len(itf.sides)
            rows += [fr, gsc * g_rows[k:k + ng]]
            k += ng
        return system.layout().to_x(f_dyn, jnp.concatenate(rows))

    def position_mask(self):
        """True on the alg entries that are frame positions (False: multipliers)."""
        m = []
        for itf in self.interfaces:
            m += [jnp.ones(3 * itf.n, dtype=bool), jnp.zeros(3 * itf.n * len(itf.sides), dtype=bool)]
        return jnp.concatenate(m)

    def frame_velocities(self, system, c: Config, v):
        """alg-shaped vector: each frame node's velocity (that of the point of its first side that
        coincides with it), zero in the multiplier entries."""
        ves, st, _, de = system.layout().split(v)
        A_v = rotation_matrix(c.q)
        etas, etas_d = self.split_eta(c.eta), self.split_eta(de)
        out = []
        for itf in self.interfaces:
            side = itf.sides[0]
            if side.body < 0:
                V = ves[:3][None, :] + jnp.cross(ves[3:], side.points) @ A_v.T
            else:
                b = self.bodies[side.body]
                A_s = rotation_matrix(c.qs[side.body])
                x = b.r[side.nodes] + b.u(etas[side.body])[side.nodes]
                w = b.u(etas_d[side.body])[side.nodes] + jnp.cross(st[side.body, 3:], x)
                V = st[side.body, :3][None, :] + w @ A_s.T
            out += [V.reshape(-1), jnp.zeros(3 * itf.n * len(itf.sides))]
        return jnp.concatenate(out)

    def constraint_acceleration(self, system, c: Config, v, acc, alg0, alg_v, alg_a):
        """d^2 g / dt^2 along the motion with velocities v and accelerations acc, the frames at alg0
        moving with the velocities alg_v and accelerations alg_a (their multiplier entries unused).
        With p = A^T w, w = X_k - X_f and body rates omega, alpha (A' = A omega~):
        d2/dt2 (A^T w) = -alpha x p + omega x (omega x p) - 2 omega x (A^T w') + A^T w'',
        plus Phi eta'' for a structure (`test_multibody` checks it against nested jvp of `constraint`)."""
        L = system.layout()
        ves_v, st_v, _, e_v = L.split(v)
        ves_a, st_a, _, e_a = L.split(acc)
        etas_a = self.split_eta(e_a)
        out = []
        for itf, (Xf, _), (Vf, _), (Af, _) in zip(self.interfaces, self.split_alg(alg0), self.split_alg(alg_v),
                                                 self.split_alg(alg_a)):
            for side in itf.sides:
                A, p, Phi_t = self._side_terms(c, side, Xf)
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

    def initial_constraint_rows(self, system, c: Config, v, alg0, mscale):
        """The constraint rows of the initial accelerations, x = [acc_y, (frame accelerations,
        multipliers), acc_z] -> rows: d^2 g / dt^2 = 0 times `mscale` (per interface), the frames'
        positions known (alg0) and their multipliers unknown."""
        L = system.layout()
        pos_mask = self.position_mask()
        Vf = self.frame_velocities(system, c, v)

        def R_c(x):
            acc, alg_a = L.from_x(x)
            alg = jnp.where(pos_mask, alg0, alg_a)                 # positions known, multipliers unknown
            gdd = self.constraint_acceleration(system, c, v, acc, alg0, Vf, jnp.where(pos_mask, alg_a, 0.0))
            return self.constraint_rows(system, c, alg, gdd, mscale)

        return R_c

    def initial_alg(self, alg0, alg_a):
        """The algebraic unknowns at t = 0: the frames where they are, the multipliers solved."""
        return jnp.where(self.position_mask(), alg0, alg_a)

    # ------------------------------------------------------------ energies and rows
    def extra_kinetic(self, system, c: Config, v):
        _, st, _, de = system.layout().split(v)
        T = jnp.zeros(())
        for s, (b, eta, eta_d) in enumerate(zip(self.bodies, self.split_eta(c.eta), self.split_eta(de))):
            A_s = rotation_matrix(c.qs[s])
            u = b.u(eta)
            w = A_s.T @ st[s, :3] + b.u(eta_d) + jnp.cross(st[s, 3:], b.r + u)   # eq. 3, u in the rotation
            T = T + 0.5 * jnp.sum(w * (b.Ms @ w))
        return T

    def extra_potential(self, system, c: Config):
        """Elastic energy 1/2 eta . omega^2 eta plus gravity (balanced against the frozen ship when
        the vessel floats on hydrostatics; see the module docstring)."""
        g_vec = jnp.array([0.0, 0.0, -system.gravity])
        A_v = rotation_matrix(c.q)
        V = jnp.zeros(())
        for s, (b, eta) in enumerate(zip(self.bodies, self.split_eta(c.eta))):
            V = V + 0.5 * eta @ (b.omega2 * eta)
            x = c.Xs[s]
            if system.balanced:
                x = x - c.X0 - A_v @ b.c0
            V = V - b.mass * g_vec @ x
        return V

    def add_rows(self, system, c: Config, core_y, core_z, vy, vz, ay, az, t=0.0, z=None):
        """The rows of the whole dynamic vector from the vessel-and-liquid ones (core_y (6,), core_z
        (nf,)): each structure's rigid and elastic inertia rows appended, and the forces of its
        potential (elastic, gravity) added, the vessel's share too (a prescribed motion replaces the
        vessel's rows afterwards: System.hold)."""
        L = system.layout()
        st_v, e_v = vy[6:].reshape(L.S, 6), vz[L.nf:]
        st_a, e_a = ay[6:].reshape(L.S, 6), az[L.nf:]
        rigid_s, modal = [], []
        for s, (b, eta, eta_d, eta_dd) in enumerate(zip(self.bodies, self.split_eta(c.eta), self.split_eta(e_v),
                                                         self.split_eta(e_a))):
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
        gy, gz = self.potential_forces_parts(system, c)
        return jnp.concatenate([core_y, *rigid_s]) + gy, jnp.concatenate([core_z, *modal]) + gz

    def potential_forces_parts(self, system, c: Config):
        """The gradient of `extra_potential` along the increments, by hand, as (rigid rows, the
        others) (`test_multibody` checks it against jax.grad): omega^2 eta on the modal rows, -m_s g
        on each structure's translation and, when balanced, +m_s g on the vessel's translation and
        c_s x (m_s A_v^T g) on its rotation."""
        L = system.layout()
        g_vec = jnp.array([0.0, 0.0, -system.gravity])
        A_v = rotation_matrix(c.q)
        ves = jnp.zeros(6)
        rig, modal = [], []
        for b, eta in zip(self.bodies, self.split_eta(c.eta)):
            mg = b.mass * g_vec
            rig.append(jnp.concatenate([-mg, jnp.zeros(3)]))
            modal.append(b.omega2 * eta)
            if system.balanced:
                ves = ves + jnp.concatenate([mg, jnp.cross(b.c0, A_v.T @ mg)])
        return jnp.concatenate([ves, *rig]), jnp.concatenate([jnp.zeros(L.nf), *modal])

    # ------------------------------------------------------------ scales and the constant block
    def add_scales(self, y, z):
        """The rigid and deformable scales with this term's appended: each structure's mass and
        principal inertia about its COG, and sqrt(m_s) for its mass-normalised modal coordinates
        (so that every row over its scale is an acceleration)."""
        rig, modal = [], []
        for b in self.bodies:
            mn = b.Ms.sum(axis=1)
            x = b.r
            I = jnp.array([mn @ (x[:, 1] ** 2 + x[:, 2] ** 2), mn @ (x[:, 0] ** 2 + x[:, 2] ** 2),
                           mn @ (x[:, 0] ** 2 + x[:, 1] ** 2)])
            rig.append(jnp.concatenate([jnp.full(3, b.mass), I]))
            modal.append(jnp.full(b.n_modes, jnp.sqrt(b.mass)))
        return jnp.concatenate([y, *rig]), jnp.concatenate([z, *modal])

    def alg_scales(self, row_factor, err_factor):
        """Per interface: frame rows (scale m_ref) and constraint rows; returns (gscale per
        interface: the factor the g rows are multiplied by, and the alg part of the error scale)."""
        gsc, sc = [], []
        for itf in self.interfaces:
            f = itf.m_ref * row_factor
            gsc.append(f)
            sc += [jnp.full(3 * itf.n, itf.m_ref), jnp.full(3 * itf.n * len(itf.sides), f * err_factor(itf))]
        return gsc, jnp.concatenate(sc)

    def block_diagonal(self, c_m, c_k):
        """The diagonal of its deformable block of c_m M + c_k K: modal (Phi^T M Phi = I,
        Phi^T K Phi = omega^2), so c_m + c_k omega^2."""
        w2 = jax.lax.stop_gradient(jnp.concatenate([b.omega2 for b in self.bodies]))
        return c_m + c_k * w2
