"""Rigid floating bodies beside the vessel and the connections between them: one term that owns
unknowns (`Bodies`, an unknowns.AbstractOwner), docs/guide/bodies-and-connections.md.

Bodies as one family: each body is a floating frame of its own (6 rigid unknowns, rotations on the
group) whose rows are the sum of the *same term classes* as the vessel's rigid part (vessel.py:
`RigidBody`, the linear restoring `AbstractRestoring` about its own rest pose, seakeeping.py's
`LinearDamping`),
evaluated with the body's own kinematics (`Floating.kin`): a body is built by the functions that
build the vessel's rigid terms, its wave excitation among them (seakeeping.py's `WaveExcitation`,
its forces at the body's place in the incident field), and, where the body has a hull with
nonlinear hydrostatics, the vessel's hull pressure and weight terms (assemble/hull.py). Its values
are params as the vessel's (`bodies.<name>.mass`, `.inertia`, `.hydrostatics.*`, `.initial.*`,
`.hull.kg`): leaves of these terms and of its initial state.

Tanks on a body (`[[tanks]] body = ...`): each body's tanks are a liquid of the vessel's kind
(jaxslosh/liquid, built by the vessel's builder: finite elements, reduced or full, elastic walls
included, whose block is constant, or the multimodal one, whose coordinates join the exact block:
`exact`), held by its `Floating` and evaluated with the body's kinematics (the walls' mass is the
liquid's, the body's hull the rest: assemble/bodies.py hull_part): its rigid rows add to the
body's six, its own rows are this term's deformable unknowns (the layout's z after the vessel's
liquid; the configuration's `eta`, every body's tanks' stacked in the bodies' order), with the
liquid's constant blocks as their block of the Newton preconditioner (`deformable_block`). They
start at the liquid's hydrostatic equilibrium under the body's initial gravity, as the vessel's do.

Radiation: one added mass A_inf and one memory (seakeeping.py's `Memory`) over the rigid dofs of
the vessel and all bodies (6 + 6 S, the step's order): each body's own tables as its diagonal
block, a multibody file's coupling as the blocks between bodies (the memory kernels between
bodies are its columns of other bodies' dofs). The memory's states are this term's integrator
states, advanced with every frame's velocities. The vessel's own block is its own terms'.

Positions are in the frame whose origin is the vessel's COG at rest, axes inertial (the vessel's X0):
a body's frame origin is its COG, at `rest` when it floats at rest; its hydrostatic restoring reads
its offset from there (its heave) and its attitude's tilt (g = A^T e_z, independent of its heading).
Like the vessel's, a body's weight is balanced by its static buoyancy at rest.

Connections (hawsers, fenders, springs) act between two points, each on the vessel, on a body or
fixed (inertial). Their force derives from a potential U(e) of the extension e = d - L (d the
points' distance), so an undamped contact conserves energy, and the contact's switch is smoothed:
a hawser's potential is W(rho(e)), a fender's W(rho(-e)), with W the force curve's integral and
rho(x) = max(x, 0) blended by a quadratic over |x| < BAND / 2 (rho and rho' continuous): the force
W'(rho) rho' is exactly zero below -BAND/2 and exactly the curve's beyond BAND/2. The damping
c de/dt acts through the same contact factor rho' and never more than cancels the elastic force (a
hawser does not push, a fender does not pull).
"""
from __future__ import annotations

import dataclasses
from typing import Any, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
from jax.scipy.linalg import block_diag
import numpy as np

from .about import About
from .floating import AbstractFloating, frame_kin
from .kinematics import quat_exp, quat_multiply, rotation_matrix
from .seakeeping import Memory
from .terms import Config, Kin, Rows, Unknowns
from .unknowns import AbstractOwner

#: m: the width of the smoothed contact switch of hawsers and fenders (centred on first contact)
BAND = 1e-3
#: the end index of the vessel and of a fixed (inertial) point in `Link.ends`
VESSEL, FIXED = -1, -2
_D_EPS2 = 1e-24      # m^2: keeps the direction defined (and differentiable) where the points meet


def end_index(names) -> dict:
    """{scene name: end index} of the ends a connection or a mooring line may name: the bodies
    (`names`, their order in [[bodies]]), "vessel" and "fixed"."""
    return {n: s for s, n in enumerate(names)} | {"vessel": VESSEL, "fixed": FIXED}


def point_motion(p, pose):
    """The inertial position and velocity of a body's point p (its frame, from the COG) at `pose` =
    (X, A, V, omega): COG, rotation matrix, COG velocity (inertial), angular velocity (body frame)."""
    X, A, V, w = pose
    return X + A @ p, V + A @ jnp.cross(w, p)


def frame_slots(ends) -> np.ndarray:
    """Each end's frame among the vessel's (0) and the bodies' (1 + slot), as a line's or a term's
    rows are stacked per frame (the vessel's first)."""
    return np.array([0 if e == VESSEL else 1 + e for e in ends], dtype=int)


def body_rest(b, vessel_cog: float) -> np.ndarray:
    """(3,) a scene body's COG at rest in the vessel-at-rest frame (`vessel_cog`: the vessel's COG height)."""
    return np.array([b.position[0], b.position[1], b.cog_height - vessel_cog], dtype=float)


def weight_balanced(scene, b) -> bool:
    """Whether a scene body's weight is balanced at rest, so that its buoyancy also carries its lines'
    vertical pull there: linear hydrostatics (springs about its rest pose), or `[effects] buoyancy`
    off; not where its hull's pressure carries it (it then sinks under the pull). The rule of
    assemble/hull.py `restoring`, which the vessel follows too."""
    hs = b.hydrostatics
    return hs is not None and not (hs.nonlinear and scene.effects.buoyancy)


def ramp(x, band=BAND):
    """(rho, rho'): max(x, 0) with its corner replaced by (x + band/2)^2 / (2 band) on |x| < band/2."""
    h = 0.5 * band
    inside = (x + h) ** 2 / (2.0 * band)
    rho = jnp.where(x <= -h, 0.0, jnp.where(x >= h, x, inside))
    slope = jnp.where(x <= -h, 0.0, jnp.where(x >= h, 1.0, (x + h) / band))
    return rho, slope


class Link(eqx.Module):
    """One connection: ends (VESSEL, a body's index or FIXED), a point in each end's frame, its
    unstretched length and force curve (deflection xs, force fs from (0, 0), extended with the last
    slope) and its damping."""
    ends: tuple = eqx.field(static=True)
    kind: str = eqx.field(static=True)          # "hawser" | "fender" | "spring"
    pa: jax.Array = None
    pb: jax.Array = None
    length: jax.Array = None
    xs: jax.Array = None
    fs: jax.Array = None
    damping: jax.Array = None

    def curve(self, x):
        """(W(x), F(x)): the curve's energy and force at deflection x >= 0."""
        xs, fs = self.xs, self.fs
        # a curve has a handful of points: compared with all of them at once (the default search's
        # loop of bisections made a tenth of the FLNG scene's step program)
        i = jnp.clip(jnp.searchsorted(xs, x, side="right", method="compare_all") - 1, 0, xs.shape[0] - 2)
        slope = (fs[1:] - fs[:-1]) / (xs[1:] - xs[:-1])
        W_nodes = jnp.concatenate([jnp.zeros(1), jnp.cumsum(0.5 * (fs[1:] + fs[:-1]) * (xs[1:] - xs[:-1]))])
        s = x - xs[i]
        return W_nodes[i] + fs[i] * s + 0.5 * slope[i] * s * s, fs[i] + slope[i] * s

    def law(self, e):
        """(U(e), dU/de, the contact factor of the damping) at extension e."""
        if self.kind == "spring":       # W(|e|) is C1: F(0) = 0
            # each side's curve on its own branch: through sign(e) F(|e|) the derivative at e = 0 (a
            # spring at its length: the RAOs' rest state) would be sign'(0) F(0) + sign(0) F' = 0, not k
            (Wp, Fp), (Wm, Fm) = self.curve(e), self.curve(-e)
            return jnp.where(e >= 0, Wp, Wm), jnp.where(e >= 0, Fp, -Fm), jnp.ones_like(e)
        sign = 1.0 if self.kind == "hawser" else -1.0
        rho, slope = ramp(sign * e)
        W, F = self.curve(rho)
        return W, sign * F * slope, slope

    def state(self, poses):
        """(tension T (> 0 pulls), extension e, U, the unit vector a -> b) of this link, `poses[end]`
        = (X, A, V, omega) (omega body frame)."""
        def point(end, p):
            return (p, jnp.zeros(3)) if end == FIXED else point_motion(p, poses[end])
        return self.state_at(*point(self.ends[0], self.pa), *point(self.ends[1], self.pb))

    def state_at(self, Pa, Va, Pb, Vb):
        """`state` for its two points at Pa, Pb (inertial) moving at Va, Vb."""
        dv = Pb - Pa
        d = jnp.sqrt(dv @ dv + _D_EPS2)
        n = dv / d
        e = d - self.length
        U, dU, contact = self.law(e)
        Td = self.damping * contact * (n @ (Vb - Va))
        # a hawser's damping cancels its elastic pull at most (a rope does not push), a fender's its push
        if self.kind == "hawser":
            Td = jnp.maximum(Td, -dU)
        elif self.kind == "fender":
            Td = jnp.minimum(Td, -dU)
        return dU + Td, e, U, n


def links_state(links: tuple, poses: dict, S: int):
    """(T (n,), e (n,), U (n,), rows (S + 1, 6)) of the connections `links` (Link), `poses[end]` =
    (X, A, V, omega) of the vessel and the S bodies: their tensions, extensions, energies in the
    links' order, and their generalized forces (translation inertial, rotation body) on the bodies
    (rows 0..S-1) and the vessel (row S).

    The links of one kind and curve size are evaluated as one, Link.state_at mapped over their
    arrays stacked (jax.vmap), their ends' poses gathered by index (a fixed point's pose the
    identity, which gives its point and a zero velocity exactly): the program holds one link's
    law per group, not one per connection (twelve connections made a fifth of the FLNG scene's
    program, docs/benchmarks.md)."""
    n = len(links)
    if not n:
        return jnp.zeros(0), jnp.zeros(0), jnp.zeros(0), jnp.zeros((S + 1, 6))
    z3 = jnp.zeros(3)
    ends = [poses[s] for s in range(S)] + [poses[VESSEL], (z3, jnp.eye(3), z3, z3)]
    X, A, V, W = (jnp.stack(x) for x in zip(*ends))
    slot = {VESSEL: S, FIXED: S + 1}
    groups: dict = {}
    for i, link in enumerate(links):       # static: by kind and curve size, at most a few groups
        groups.setdefault((link.kind, link.xs.shape[0]), []).append(i)
    rows = jnp.zeros((S + 2, 6))
    T, e, U = jnp.zeros(n), jnp.zeros(n), jnp.zeros(n)
    for idx in groups.values():
        stacked = jax.tree_util.tree_map(lambda *x: jnp.stack(x), *[dataclasses.replace(links[i], ends=(0, 0))
                                                                    for i in idx])
        ia = np.array([slot.get(links[i].ends[0], links[i].ends[0]) for i in idx])
        ib = np.array([slot.get(links[i].ends[1], links[i].ends[1]) for i in idx])

        def one(link, Xa, Aa, Va, Wa, Xb, Ab, Vb, Wb):
            Ti, ei, Ui, ni = link.state_at(Xa + Aa @ link.pa, Va + Aa @ jnp.cross(Wa, link.pa),
                                           Xb + Ab @ link.pb, Vb + Ab @ jnp.cross(Wb, link.pb))
            fa = Ti * ni
            fb = -Ti * ni
            return (Ti, ei, Ui, jnp.concatenate([fa, jnp.cross(link.pa, Aa.T @ fa)]),
                    jnp.concatenate([fb, jnp.cross(link.pb, Ab.T @ fb)]))
        Ti, ei, Ui, ra, rb = jax.vmap(one)(stacked, X[ia], A[ia], V[ia], W[ia], X[ib], A[ib], V[ib], W[ib])
        rows = rows.at[ia].add(ra).at[ib].add(rb)
        T, e, U = T.at[np.array(idx)].set(Ti), e.at[np.array(idx)].set(ei), U.at[np.array(idx)].set(Ui)
    return T, e, U, rows[:S + 1]


class Floating(AbstractFloating):
    """One body's floating frame (a floating body as the vessel is one: floating.AbstractFloating
    sums its terms): its rigid terms (the vessel's classes, evaluated with its own kinematics), its
    rest pose and its initial state; and the liquid of the tanks it carries (`tank`: a liquid of the
    vessel's kind, jaxslosh/liquid, built by the vessel's builder; None without tanks) with the
    terms that act on that liquid (`tank_terms`: its rotation penalty)."""
    terms: tuple
    rest: jax.Array        # (3,) its COG at rest, in the vessel-at-rest frame
    x0: jax.Array          # (3,) its COG at t = 0, same frame
    q0: jax.Array          # (4,) its attitude at t = 0 (its heading included)
    v0: jax.Array          # (6,) V (inertial), omega (body) at t = 0
    tank: Any = None
    tank_terms: tuple = ()
    gravity_turning: bool = eqx.field(static=True, default=True)   # off: its gravity stays as at the start

    def start_attitude(self):
        return self.q0

    @property
    def nf(self) -> int:
        """Its tanks' liquid unknowns."""
        return 0 if self.tank is None else self.tank.nf

    def kin(self, X, q, v, a, gravity, t, d=None, d_dot=None, d_acc=None) -> Kin:
        """The body's Kin: its offset from rest as the configuration's X0 (what the hydrostatics read),
        its tanks' liquid unknowns as the deformable ones (d, their rates d_dot and d_acc), its
        gravity frozen at the start where it does not turn (the vessel's rule)."""
        e = jnp.zeros(0)
        return frame_kin(Config(X - self.rest, q, e if d is None else d), v[:3], v[3:], e if d_dot is None else d_dot,
                         a, None if a is None else (e if d_acc is None else d_acc), t, gravity,
                         self.gravity_attitude())

    def carried(self):
        """Its terms on its tanks' liquid: the liquid's own, then the others'."""
        return () if self.tank is None else (self.tank, *self.tank_terms)

    def frame_terms(self) -> tuple:
        """Its rigid terms, then its liquid and the terms on it."""
        return self.terms + self.carried()

    def rows(self, k: Kin):
        """(its six rows, its liquid's rows)."""
        rigid, d, _ = self.frame_rows(k)
        return rigid, jnp.zeros(0) if d is None else d

    def kinetic(self, k: Kin):
        return self.frame_kinetic(k)

    def potential(self, k: Kin):
        return self.frame_potential(k)

    def mass_scale(self):
        return self.frame_mass_scale()


class Bodies(AbstractOwner):
    """The `[[bodies]]` (S floating frames beside the vessel's) and the `[[connections]]`. Without
    bodies (connections from the vessel to fixed points only) it owns no unknowns and is a plain
    term: its rows and potential are then the connections' on the vessel."""
    bodies: tuple
    links: tuple
    gravity: jax.Array
    added_mass: Optional[jax.Array] = None     # (6 + 6 S, 6 + 6 S) the bodies' radiation A_inf
    memory: Optional[Memory] = None            # over the 6 + 6 S rigid dofs
    names: tuple = eqx.field(static=True, default=())
    link_names: tuple = eqx.field(static=True, default=())
    about: About = eqx.field(static=True, default=About())

    @property
    def S(self) -> int:
        return len(self.bodies)

    def describe(self) -> tuple:
        return self.about.lines

    @property
    def M(self) -> int:
        """Its bodies' tanks' liquid unknowns (the owner's deformable ones), stacked in the bodies' order."""
        return sum(b.nf for b in self.bodies)

    def exact(self) -> bool:
        """A body's nonlinear (multimodal) liquid: every deformable unknown linearised exactly, as the
        vessel's multimodal liquid is (its rows' mass and stiffness move with the free surface)."""
        return any(b.tank is not None and b.tank.nonlinear for b in self.bodies)

    def tank_slices(self) -> tuple:
        """(S,) each body's slice of the stacked liquid unknowns of the bodies' tanks."""
        out, k = [], 0
        for b in self.bodies:
            out.append(slice(k, k + b.nf))
            k += b.nf
        return tuple(out)

    def unknowns(self) -> Unknowns:
        return Unknowns(frames=self.S, deformable=self.M)

    def settles(self) -> bool:
        """Its unknowns start where the scene puts them, not at a static equilibrium (a body held by a
        hawser alone has none in surge)."""
        return False

    # ------------------------------------------------------------ poses and connections
    def poses(self, c: Config, vy):
        """{end: (X, A, V, omega)} of the vessel (-1) and the bodies from the configuration and the
        rigid velocities (vessel's six, then six per body)."""
        out = {VESSEL: (c.X0, rotation_matrix(c.q), vy[:3], vy[3:6])}
        for s in range(self.S):
            out[s] = (c.Xs[s], rotation_matrix(c.qs[s]), vy[6 + 6 * s:9 + 6 * s], vy[9 + 6 * s:12 + 6 * s])
        return out

    def link_forces(self, poses):
        """(6 + 6 S,) the connections' generalized forces on the vessel and the bodies."""
        rows = links_state(self.links, poses, self.S)[3]
        return jnp.concatenate([rows[self.S], rows[:self.S].reshape(-1)])

    def link_potential(self, poses):
        return jnp.sum(links_state(self.links, poses, self.S)[2])

    def link_states(self, c: Config, vy):
        """(tensions (n,), extensions (n,)) of the connections."""
        return links_state(self.links, self.poses(c, vy), self.S)[:2]

    # ------------------------------------------------------------ a plain term without bodies
    def rows(self, k: Kin) -> Rows:
        if self.S:
            return Rows(jnp.zeros(6))
        return Rows(-self.link_forces({VESSEL: (k.c.X0, k.A, k.V0, k.omega)}))

    def potential(self, k: Kin):
        if self.S:
            return jnp.zeros(())
        return self.link_potential({VESSEL: (k.c.X0, k.A, k.V0, k.omega)})

    # ------------------------------------------------------------ the owner's hooks
    def start(self, system, c0: Config, v0):
        # each body's tank liquid at its discrete hydrostatic equilibrium under the body's initial gravity,
        # as the vessel's liquid starts (assemble/system.py)
        etas = [b.tank.static_start(b.kin(b.x0, b.q0, jnp.zeros(6), None, self.gravity, 0.0).g_b)
                for b in self.bodies if b.tank is not None]
        c = c0._replace(Xs=jnp.stack([b.x0 for b in self.bodies]), qs=jnp.stack([b.q0 for b in self.bodies]),
                        eta=jnp.concatenate([jnp.zeros(0), *etas]))
        v = jnp.concatenate([v0[:6], *[b.v0 for b in self.bodies], v0[6:], jnp.zeros(self.M)])
        return c, v, jnp.zeros(0)

    def carried_velocities(self, system, c: Config, v):
        return v

    def advance(self, c: Config, out: Config, y, z) -> Config:
        st = y.reshape(self.S, 6)
        qs = jax.vmap(lambda q, th: quat_multiply(q, quat_exp(th)))(c.qs, st[:, 3:])
        return out._replace(Xs=c.Xs + st[:, :3], qs=qs, eta=c.eta + z)

    def body_kins(self, system, c: Config, vy, ay=None, t=0.0, vz=None, az=None):
        """Each body's Kin; `vz`, `az`: the rates of the deformable unknowns (the vessel's liquid's,
        then the bodies' tanks'), for the bodies' tanks."""
        nf = system.nf

        def tank(x, sl):
            return None if x is None else x[nf:][sl]
        return [b.kin(c.Xs[s], c.qs[s], vy[6 + 6 * s:12 + 6 * s], None if ay is None else ay[6 + 6 * s:12 + 6 * s],
                      system.gravity, t, c.eta[sl], tank(vz, sl), tank(az, sl))
                for s, (b, sl) in enumerate(zip(self.bodies, self.tank_slices()))]

    def add_rows(self, system, c: Config, core_y, core_z, vy, vz, ay, az, t=0.0, z=None):
        own = [b.rows(k) for b, k in zip(self.bodies, self.body_kins(system, c, vy, ay, t, vz, az))]
        rows = jnp.concatenate([core_y, *[r[0] for r in own]]) - self.link_forces(self.poses(c, vy))
        core_z = jnp.concatenate([core_z, *[r[1] for r in own]])
        if self.added_mass is not None:
            rows = rows + self.added_mass @ ay[:rows.shape[0]]
        if self.memory is not None and z is not None and z.size:
            rows = rows + self.memory.force(z)
        return rows, core_z

    # ------------------------------------------------------------ the radiation memory's states
    def state_init(self):
        return jnp.zeros((0,)) if self.memory is None else self.memory.init()

    def state_coefficients(self, h):
        return () if self.memory is None else self.memory.coefficients(h)

    def state_advance(self, z, v_old, v_new, coef):
        return z if self.memory is None else self.memory.advance(z, v_old, v_new, coef)

    def extra_kinetic(self, system, c: Config, v):
        vy = v[:6 + 6 * self.S]
        T = sum((b.kinetic(k) for b, k in zip(self.bodies, self.body_kins(system, c, vy, vz=v[6 + 6 * self.S:]))),
                jnp.zeros(()))
        return T if self.added_mass is None else T + 0.5 * vy @ (self.added_mass @ vy)

    def extra_potential(self, system, c: Config):
        vy = jnp.zeros(6 + 6 * self.S)
        V = sum((b.potential(k) for b, k in zip(self.bodies, self.body_kins(system, c, vy))), jnp.zeros(()))
        return V + self.link_potential(self.poses(c, vy))

    def add_scales(self, y, z):
        y = jnp.concatenate([y, *[b.mass_scale() for b in self.bodies]])
        z = jnp.concatenate([z, *[b.tank.d_scale() for b in self.bodies if b.tank is not None]])
        return (y if self.added_mass is None else y.at[6:].add(jnp.diag(self.added_mass)[6:])), z

    def constraint(self, system, c: Config, alg):
        return jnp.zeros(0)

    def constraint_rows(self, system, c: Config, alg, g_rows, gscale):
        return jnp.zeros(system.layout().n)

    def alg_scales(self, row_factor, err_factor):
        return [], jnp.zeros(0)

    def deformable_block(self, c_m, c_k):
        """c_m M + c_k K of its bodies' tanks' liquid (block diagonal over the bodies; each tank's
        constant blocks, as the vessel's liquid gives them to the solver)."""
        blocks = [c_m * M + c_k * K for M, K in (b.tank.constant_blocks() for b in self.bodies if b.tank is not None)]
        return block_diag(*blocks) if blocks else jnp.zeros((0, 0))

    def block_diagonal(self, c_m, c_k):
        return jnp.diag(self.deformable_block(c_m, c_k))

    def initial_constraint_rows(self, system, c: Config, v, alg0, mscale):
        return lambda x: jnp.zeros_like(x)

    def initial_alg(self, alg0, alg_a):
        return alg_a


def bodies_term(system) -> Optional[Bodies]:
    """The system's bodies-and-connections term, or None."""
    return next((t for t in system.terms if isinstance(t, Bodies)), None)
