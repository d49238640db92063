"""`js.mooring` and `jaxslosh mooring`: the moored vessel's static equilibrium in still water, each
line's tensions there, the lines' 6 x 6 stiffness about the COG and the offset curve
(docs/guide/moorings.md)."""
from __future__ import annotations

import dataclasses
from typing import Optional, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..assemble.system import build
from ..physics.bodies import VESSEL, bodies_term
from ..physics.hull import HullPressure
from ..physics.kinematics import quat_exp, quat_from_rpy, quat_multiply, rotation_matrix, rpy_from_quat
from ..physics.terms import Config
from ..physics.vessel import AbstractRestoring, Weight
from ..scene.types import Scene, SceneError
from .lumped_keys import quasi_static_lines
from .term import MooringLines, mooring_term

#: Newton on the six rigid dofs: iterations, and the force (N) and moment (N m) per unit of the
#: restoring's own scale below which it has converged
MAX_ITER = 60
TOL = 1e-10


class StaticFailure(RuntimeError):
    """The static equilibrium was not found (exit status 3 on the command line)."""


@dataclasses.dataclass(frozen=True)
class MooringAnalysis:
    """What `js.mooring` returns (SI units, angles in rad): `equilibrium` [x, y, z, roll, pitch, yaw]
    of the COG from its rest position; `lines`, one dict per line at the equilibrium (name,
    fairlead_tension, anchor_tension, horizontal, vertical, seabed_length); `stiffness` (6, 6) of
    the lines about the COG at the equilibrium, K = -dF/dx (forces and moments in inertial axes,
    translations and small rotations about the COG); the offset curve: `offsets` (m) along
    `direction` (rad from +X towards +Y), the lines' `restoring` force along it (N, positive where
    it pulls back) and the most loaded line's fairlead tension `max_tension` (N)."""
    equilibrium: np.ndarray
    lines: list
    stiffness: np.ndarray
    offsets: np.ndarray
    restoring: np.ndarray
    max_tension: np.ndarray
    direction: float = 0.0
    shapes: tuple = ()        # per line, (horizontal distance from the anchor, z) points at the equilibrium (m)
    #: a scene with [[bodies]]: {name: {"equilibrium": [x, y, z, roll, pitch, yaw] of its COG from its
    #: rest pose (angles about its own axes), "stiffness": (6, 6) its lines' about its COG}}
    bodies: dict = dataclasses.field(default_factory=dict)

    def as_dict(self) -> dict:
        out = {"equilibrium": [float(x) for x in self.equilibrium], "lines": self.lines,
               "stiffness": np.asarray(self.stiffness, dtype=float).tolist(),
               "offsets": [float(x) for x in self.offsets], "restoring": [float(x) for x in self.restoring],
               "max_tension": [float(x) for x in self.max_tension], "direction": float(self.direction)}
        if self.bodies:
            out["bodies"] = {n: {"equilibrium": [float(x) for x in b["equilibrium"]],
                                 "stiffness": np.asarray(b["stiffness"], dtype=float).tolist()}
                             for n, b in self.bodies.items()}
        return out


def _rotate(theta, A):
    """A turned by the small inertial rotation vector theta."""
    return rotation_matrix(quat_exp(theta)) @ A


def static_residual(system, x):
    """The still-water rigid rows at pose x = [X0 (3), theta (3)] (theta: rotation vector from
    upright), velocities and accelerations zero: the restoring terms and the lines. The liquid is
    held as built at rest."""
    q = quat_exp(x[3:])
    c = Config(x[:3], q, jnp.zeros(system.nf))
    k = system.kin(c, jnp.zeros(3), jnp.zeros(3), jnp.zeros(system.nf), jnp.zeros(6), jnp.zeros(system.nf), 0.0)
    total = jnp.zeros(6)
    for term in system.terms:
        if isinstance(term, HullPressure):
            F, M = term.still_force_moment(k.c.X0, k.A)
            total = total - jnp.concatenate([F, M])
        elif isinstance(term, (AbstractRestoring, Weight, MooringLines)):
            total = total + term.rows(k).rigid
    return total


def _still_rows(terms, k):
    """The still-water rows of a floating frame's restoring terms (the hull's pressure, the linear
    springs, the weight) at its Kin k."""
    total = jnp.zeros(6)
    for term in terms:
        if isinstance(term, HullPressure):
            F, M = term.still_force_moment(k.c.X0, k.A)
            total = total - jnp.concatenate([F, M])
        elif isinstance(term, (AbstractRestoring, Weight)):
            total = total + term.rows(k).rigid
    return total


def _frames_config(system, x, heads):
    """The configuration of the poses x = [vessel's X0, theta; each body's offset from rest, theta]
    (theta: inertial rotation vectors from upright, a body's from its heading `heads` (S, 4))."""
    bodies = bodies_term(system)
    y = x.reshape(-1, 6)
    rest = jnp.stack([b.rest for b in bodies.bodies])
    qs = jax.vmap(lambda th, h: quat_multiply(quat_exp(th), h))(y[1:, 3:], heads)
    return Config(y[0, :3], quat_exp(y[0, 3:]), jnp.zeros(system.nf), rest + y[1:, :3], qs)


def frames_residual(system, x, heads):
    """The still-water rows of the vessel and of every [[bodies]] body (6 each, the frames' order) at
    the poses x (`_frames_config`): each frame's restoring terms, the lines on it and the
    connections between them. The liquids are held as built at rest."""
    c = _frames_config(system, x, heads)
    bodies = bodies_term(system)
    k = system.kin(c, jnp.zeros(3), jnp.zeros(3), jnp.zeros(system.nf), jnp.zeros(6), jnp.zeros(system.nf), 0.0)
    zero = jnp.zeros(6)
    rows = [_still_rows(system.terms, k)]
    for b, X, q in zip(bodies.bodies, c.Xs, c.qs):
        rows.append(_still_rows(b.terms, b.kin(X, q, zero, zero, system.gravity, 0.0)))
    rows = jnp.concatenate(rows)
    term = mooring_term(system)
    if term is not None:
        per = term.frame_rows(*term.frames(c, k.A)) if term.on_bodies else \
            jnp.zeros((bodies.S + 1, 6)).at[0].set(-term.rows(k).rigid)
        rows = rows - per.reshape(-1)
    poses = {VESSEL: (c.X0, k.A, jnp.zeros(3), jnp.zeros(3))}
    poses |= {s: (c.Xs[s], rotation_matrix(c.qs[s]), jnp.zeros(3), jnp.zeros(3)) for s in range(bodies.S)}
    return rows - bodies.link_forces(poses)


#: the several frames' Newton step: least squares, singular values below this fraction of the
#: largest cut, so that a dof nothing holds (a free vessel's surge beside a moored body) stays at rest
RCOND = 1e-12


def _least_squares(J, r):
    return jnp.linalg.lstsq(J, r, rcond=RCOND)[0]


def equilibrium(system, scale, residual=static_residual, solve=jnp.linalg.solve):
    """(the poses where the still-water rows vanish, Newton's scaled residual at the iterate before
    the last), by Newton from rest: [X0, theta] of the vessel alone (`static_residual`), or of
    every frame (`frames_residual` with its bodies' headings bound; `solve` its steps: RCOND). The
    residual and its Jacobian come from one forward-mode pass and the test is made on that
    residual: the rows (the lines' cold solve among them) appear once in the loop's body, which is
    what its compilation costs."""
    f = lambda x: residual(system, x) / scale  # noqa: E731
    jac = jax.jacfwd(lambda x: (lambda r: (r, r))(f(x)), has_aux=True)

    def step(state):
        x, _, it = state
        J, r = jac(x)
        return x - solve(J, r), jnp.max(jnp.abs(r)), it + 1

    cond = lambda s: (s[1] > TOL) & (s[2] < MAX_ITER)  # noqa: E731
    x, err, _ = jax.lax.while_loop(cond, step, (jnp.zeros(scale.shape), jnp.asarray(jnp.inf), 0))
    return x, err


def _loads(term: MooringLines, X0, A, P):
    """x = (translation, small inertial rotation about P) -> ((the lines' force, their moment about
    P + translation), the lines' state): the pose's loads with the lines' state beside them."""
    def loads(x):
        R = rotation_matrix(quat_exp(x[3:]))
        X = P + x[:3] + R @ (X0 - P)
        s = term.state(X, R @ A)
        F = s.force.sum(axis=0)
        M = jnp.cross(s.fairlead - X, s.force).sum(axis=0)
        return jnp.concatenate([F, M + jnp.cross(X - P - x[:3], F)]), s
    return loads


def stiffness(term: MooringLines, X0, A, point=None):
    """The lines' 6 x 6 stiffness K = -d(F, M)/d(x, theta) at pose (X0, A): translations and small
    inertial rotations about `point` (inertial; the COG by default), moments about it too."""
    P = X0 if point is None else jnp.asarray(point, dtype=float)
    return -jax.jacfwd(_loads(term, X0, A, P), has_aux=True)(jnp.zeros(6))[0]


@eqx.filter_jit
def _analysis(system, scale, offsets, e):
    """The equilibrium, and at it and at each offset from it along e the lines' state and
    stiffness: one program (cached by the system's structure, so that a second call with the
    same scene compiles nothing), the lines' cold solve traced twice in it (Newton's body, and the
    poses' state with its derivative, vmapped over the poses)."""
    term = mooring_term(system)
    x, err = equilibrium(system, scale)
    X0, A = x[:3], rotation_matrix(quat_exp(x[3:]))

    def at(o):
        X = X0 + o * e
        K, s = jax.jacfwd(_loads(term, X, A, X), has_aux=True)(jnp.zeros(6))
        return -K, s
    K, s = jax.vmap(at)(jnp.concatenate([jnp.zeros(1), offsets]))
    return x, err, rpy_from_quat(quat_exp(x[3:])), K[0], s


def _frame_stiffness(term: MooringLines, X, A, mask, P):
    """(6, 6) K = -d(F, M)/d(x, theta) of the lines `mask` (n,) whose frame's COG is P, the lines'
    frames X (n, 3), A (n, 3, 3) (`MooringLines.frames`): translations and small inertial rotations
    of that frame about P, moments about it too."""
    m = jnp.asarray(mask, dtype=float)

    def loads(x):
        R = rotation_matrix(quat_exp(x[3:]))
        s = term.state(jnp.where(mask[:, None], P + x[:3], X), jnp.where(mask[:, None, None], R @ A, A))
        F = s.force * m[:, None]
        return jnp.concatenate([F.sum(axis=0), jnp.cross(s.fairlead - P - x[:3], F).sum(axis=0)])
    return -jax.jacfwd(loads)(jnp.zeros(6))


@eqx.filter_jit
def _frames_analysis(system, scale, heads, offsets, e):
    """`_analysis` of a scene with [[bodies]]: the equilibrium of every frame; each frame's lines'
    stiffness there and its angles about its own axes; the lines' state at the equilibrium and with
    the vessel moved by each offset along e (the bodies held)."""
    term = mooring_term(system)
    x, err = equilibrium(system, scale, lambda sysm, x: frames_residual(sysm, x, heads), _least_squares)
    c = _frames_config(system, x, heads)
    A = rotation_matrix(c.q)
    y = x.reshape(-1, 6)
    own = jax.vmap(lambda th, h: quat_multiply(h * jnp.array([1.0, -1.0, -1.0, -1.0]),
                                               quat_multiply(quat_exp(th), h)))(y[1:, 3:], heads)
    rpy = jnp.concatenate([rpy_from_quat(c.q)[None], jax.vmap(rpy_from_quat)(own)])
    if term.on_bodies:
        X, As = term.frames(c, A)
        ends = np.array([0 if end == VESSEL else 1 + end for end in term.ends])
        centres = jnp.concatenate([c.X0[None], c.Xs])
        K = jnp.stack([_frame_stiffness(term, X, As, ends == f, centres[f]) for f in range(centres.shape[0])])
        states = jax.vmap(lambda o: term.state(jnp.where((ends == 0)[:, None], X + o * e, X), As))(
            jnp.concatenate([jnp.zeros(1), offsets]))
    else:
        K = jnp.zeros((y.shape[0], 6, 6)).at[0].set(stiffness(term, c.X0, A))
        states = jax.vmap(lambda o: term.state(c.X0 + o * e, A))(jnp.concatenate([jnp.zeros(1), offsets]))
    return x, err, rpy, K, states


def line_shape(H, V, L, w, EA, LB, hA, n=200):
    """Points (horizontal distance from the anchor, height above the anchor) along a line (NumPy,
    for the figure): its stretched tangent integrated along the unstretched arc length, the part on
    the seabed flat (friction left out of the drawing)."""
    s = np.linspace(0.0, L, n)
    if LB > 0:
        s1 = L - LB - V / w          # the part between a raised anchor and the seabed
        Vs = np.where(s < s1, -w * (s1 - s), np.where(s < s1 + LB, 0.0, V - w * (L - s)))
    else:
        Vs = V - w * (L - s)
    T = np.hypot(H, Vs)
    T = np.where(T > 0, T, 1.0)
    dx = np.where(np.hypot(H, Vs) > 0, H / T, 1.0) * (1 + np.hypot(H, Vs) / EA)
    dz = Vs / T * (1 + np.hypot(H, Vs) / EA)
    cum = lambda f: np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(s))])  # noqa: E731
    return cum(dx), cum(dz)


def mooring(scene: Scene, offsets: Optional[Sequence[float]] = None, direction: float = 0.0) -> MooringAnalysis:
    """The moored scene's static analysis in still water (docs/guide/moorings.md).

    Args:
        scene: a loaded scene with `[[mooring]]` lines.
        offsets: horizontal offsets (m) of the vessel from its equilibrium along `direction` for the
            offset curve (default: 0 to 10 % of the depth in 11 steps).
        direction: rad, from +X towards +Y.

    Returns:
        A `MooringAnalysis` (`as_dict()` is the command's JSON).
    """
    if not scene.mooring:
        raise SceneError("mooring", "the scene has no [[mooring]] lines")
    scene = quasi_static_lines(scene)        # lumped lines at rest: their catenary
    if offsets is None:
        offsets = np.linspace(0.0, 0.1 * scene.environment.depth, 11)
    offsets = np.asarray(offsets, dtype=float)
    with jax.ensure_compile_time_eval():
        system = build(scene).system
    term = mooring_term(system)
    g = float(system.gravity) if float(system.gravity) > 0 else 9.81
    m = float(system.total_mass())
    size = max(float(np.max(np.abs(np.asarray(term.fairlead)))), 1.0)
    scale = jnp.array([m * g] * 3 + [m * g * size] * 3)
    e = jnp.array([np.cos(direction), np.sin(direction), 0.0])
    bodies = bodies_term(system)
    several = bodies is not None and bodies.S > 0
    if several:        # every frame at once: the vessel, the bodies, the lines on each, the connections
        for b in scene.bodies:
            scale = jnp.concatenate([scale, jnp.array([b.mass * g] * 3 + [b.mass * g * size] * 3)])
        heads = jnp.stack([quat_from_rpy(jnp.array([0.0, 0.0, b.heading])) for b in scene.bodies])
        x, err, rpys, Ks, states = _frames_analysis(system, scale, heads, jnp.asarray(offsets), e)
        x, rpy, K = np.asarray(x).reshape(-1, 6), np.asarray(rpys[0]), Ks[0]
    else:
        x, err, rpy, K, states = _analysis(system, scale, jnp.asarray(offsets), e)
    if not (np.isfinite(float(err)) and float(err) <= 1e3 * TOL):
        raise StaticFailure(f"no static equilibrium found (Newton's scaled residual {float(err):.3g} after "
                            f"{MAX_ITER} iterations): do the lines{', the connections' if several else ''} and the "
                            f"hydrostatics hold every dof{' of every body' if several else ''}?")
    eq = np.concatenate([np.asarray(x[0, :3] if several else x[:3]), np.asarray(rpy)])
    on_bodies = {}
    if several:
        on_bodies = {b.name: {"equilibrium": np.concatenate([x[s + 1, :3], np.asarray(rpys[s + 1])]),
                              "stiffness": np.asarray(Ks[s + 1])} for s, b in enumerate(scene.bodies)}
    states = jax.tree_util.tree_map(np.asarray, states)      # NumPy from here: no more programs to compile
    s = jax.tree_util.tree_map(lambda v: v[0], states)       # at the equilibrium
    tension = np.hypot(states.horizontal, states.vertical)
    anchor = np.hypot(states.anchor_horizontal, states.anchor_vertical)
    lines, shapes = [], []
    for i, line in enumerate(scene.mooring):
        lines.append({"name": line.name, "fairlead_tension": float(tension[0, i]),
                      "anchor_tension": float(anchor[0, i]), "horizontal": float(s.horizontal[i]),
                      "vertical": float(s.vertical[i]), "seabed_length": float(s.seabed_length[i])})
        shapes.append(line_shape(float(s.horizontal[i]), float(s.vertical[i]), line.length, line.weight, line.ea,
                                 float(s.seabed_length[i]), line.anchor_height))
    vessel = np.array([line.body in ("vessel", scene.vessel.name) for line in scene.mooring], dtype=float)
    restoring = -((states.force[1:] * vessel[:, None]).sum(axis=1) @ np.array([np.cos(direction), np.sin(direction),
                                                                               0.0]))
    tmax = np.max(tension[1:], axis=1)
    return MooringAnalysis(eq, lines, np.asarray(K), offsets, restoring, tmax, float(direction),
                           tuple(shapes), on_bodies)
