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
from ..physics.hull import HullPressure
from ..physics.kinematics import quat_exp, rotation_matrix, rpy_from_quat
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

    def as_dict(self) -> dict:
        return {"equilibrium": [float(x) for x in self.equilibrium], "lines": self.lines,
                "stiffness": np.asarray(self.stiffness, dtype=float).tolist(),
                "offsets": [float(x) for x in self.offsets], "restoring": [float(x) for x in self.restoring],
                "max_tension": [float(x) for x in self.max_tension], "direction": float(self.direction)}


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


def equilibrium(system, scale):
    """The pose [X0, theta] where the still-water rows vanish, by Newton from rest."""
    f = lambda x: static_residual(system, x) / scale  # noqa: E731

    def step(state):
        x, _, it = state
        r = f(x)
        dx = -jnp.linalg.solve(jax.jacfwd(f)(x), r)
        x = x + dx
        return x, jnp.max(jnp.abs(f(x))), it + 1

    cond = lambda s: (s[1] > TOL) & (s[2] < MAX_ITER)  # noqa: E731
    x0 = jnp.zeros(6)
    x, err, it = jax.lax.while_loop(cond, step, (x0, jnp.max(jnp.abs(f(x0))), 0))
    return x, err


def stiffness(term: MooringLines, X0, A, point=None):
    """The lines' 6 x 6 stiffness K = -d(F, M)/d(x, theta) at pose (X0, A): translations and small
    inertial rotations about `point` (inertial; the COG by default), moments about it too."""
    P = X0 if point is None else jnp.asarray(point, dtype=float)

    def loads(x):
        R = rotation_matrix(quat_exp(x[3:]))
        X = P + x[:3] + R @ (X0 - P)
        F, M = term.force_moment(X, R @ A)
        return jnp.concatenate([F, M + jnp.cross(X - P - x[:3], F)])
    return -jax.jacfwd(loads)(jnp.zeros(6))


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
    for i, line in enumerate(scene.mooring):
        if line.body not in ("vessel", scene.vessel.name):
            raise SceneError(f"mooring[{i}].body", f"{line.body!r}: the static analysis (js.mooring, `jaxslosh "
                                                   "mooring`) takes the vessel's lines only; this line holds a body of "
                                                   "[[bodies]] (run the scene to see it moored)")
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
    x, err = eqx.filter_jit(equilibrium)(system, scale)
    if not (np.isfinite(float(err)) and float(err) <= 1e3 * TOL):
        raise StaticFailure(f"no static equilibrium found (Newton's scaled residual {float(err):.3g} after "
                            f"{MAX_ITER} iterations): do the lines and the hydrostatics hold every dof?")
    q = quat_exp(x[3:])
    X0, A = x[:3], rotation_matrix(q)
    eq = np.concatenate([np.asarray(X0), np.asarray(rpy_from_quat(q))])
    s = eqx.filter_jit(lambda t, X, R: t.state(X, R))(term, X0, A)
    lines, shapes = [], []
    for i, line in enumerate(scene.mooring):
        lines.append({"name": line.name, "fairlead_tension": float(s.fairlead_tension[i]),
                      "anchor_tension": float(s.anchor_tension[i]), "horizontal": float(s.horizontal[i]),
                      "vertical": float(s.vertical[i]), "seabed_length": float(s.seabed_length[i])})
        shapes.append(line_shape(float(s.horizontal[i]), float(s.vertical[i]), line.length, line.weight, line.ea,
                                 float(s.seabed_length[i]), line.anchor_height))
    K = np.asarray(eqx.filter_jit(stiffness)(term, X0, A))
    e = jnp.array([np.cos(direction), np.sin(direction), 0.0])

    @eqx.filter_jit
    def curve(t, offsets):
        def one(o):
            st = t.state(X0 + o * e, A)
            return -(st.force.sum(axis=0) @ e), jnp.max(st.fairlead_tension)
        return jax.vmap(one)(offsets)
    restoring, tmax = curve(term, jnp.asarray(offsets))
    return MooringAnalysis(eq, lines, K, offsets, np.asarray(restoring), np.asarray(tmax), float(direction),
                           tuple(shapes))
