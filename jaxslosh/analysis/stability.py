"""Large-angle statical stability (docs/guide/stability.md): the righting lever GZ at
fixed heels, the vessel free to sink and trim at the scene's displacement, with the tank liquids
frozen at rest and level at each heel; GM0 both ways, the angle of vanishing stability and the
IS Code 2008 Part A 2.2 criteria.

At each heel the equilibrium is found in the vessel frame (origin at the ship's COG without its
liquid), where the sea's up direction is n = R^T e_z, R = R_y(pitch) R_x(roll):
* the water plane n . x = c that holds the displaced volume (ship + liquid) / rho, by a bracketed
  Newton iteration on c (dV/dc is the waterplane area);
* each tank's level free surface the same way on the tank's own closed surface;
* the free angle (pitch at a roll heel, roll at a pitch heel) by Newton until the centre of
  buoyancy is vertically under the centre of gravity in that direction.
GZ is then the horizontal lever between weight and buoyancy about the heel axis, positive when it
rights the vessel. Everything is traced once and vmapped over the angles; the iterations are
`lax.fori_loop`s of fixed counts, their residuals checked on the host afterwards.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from typing import Optional

import jax
import jax.numpy as jnp
import numpy as np

from ..hull.clip import submerged, submerged_and_cut
from ..hull.hydrostatics import first_vanishing
from ..hull.surface import HullMeshError
from ..hull.tanks import tank_surface
from ..staging import START_OPTIONS
from .bodystability import bodies_stability, linear_stability
from ..scene.load import load_scene
from ..scene.types import SceneError, Vessel

#: most iterations of the bracketed Newton solves of a plane's offset and of the free angle (each
#: stops when converged)
LEVEL_ITERATIONS = 60
TRIM_ITERATIONS = 20
#: rad: the step of the free lever's difference quotient (Newton converges to its round-off all the same)
TRIM_STEP = 1e-6
#: rad: the half step of GM0's central difference of GZ (its error is GZ''' GM0_STEP^2 / 6)
GM0_STEP = 1e-4
#: a solve counts as converged when the volume is within this fraction and the free lever within
#: this fraction of the hull's size
TOLERANCE = 1e-8
#: the default heels, degrees (the command line's 0:80:81)
DEFAULT_DEGREES = (0.0, 80.0, 81)
#: Gauss-Legendre points of the criteria's areas on 0-30 and on 30-40 degrees
_AREA_POINTS = (16, 8)
AXES = ("roll", "pitch")


class StabilityFailure(RuntimeError):
    """An equilibrium that did not converge (exit status 3 on the command line)."""


@dataclass(frozen=True)
class Criterion:
    name: str
    value: float
    limit: float
    passed: bool

    def as_dict(self):
        return {"name": self.name, "value": self.value, "limit": self.limit, "pass": self.passed}


@dataclass(frozen=True)
class Stability:
    """What `js.stability` returns: the fields docs/guide/stability.md lists (also as `s["gz"]` and `s.as_dict()`).
    Angles in rad, levers in m; `gz` with the liquids level, `gz_frozen` with them frozen at rest."""
    angle: np.ndarray
    gz: np.ndarray
    gz_frozen: np.ndarray
    gm0: float
    gm0_frozen: float
    vanishing_angle: Optional[float]
    criteria: tuple = ()
    axis: str = "roll"
    sinkage: np.ndarray = field(default=None, repr=False)   # m: the water plane's rise in the vessel frame from upright
    trim: np.ndarray = field(default=None, repr=False)      # rad: the free angle (pitch at a roll heel, roll at a pitch heel)
    #: {name: bodystability.LinearStability} of the scene's [[bodies]]
    bodies: dict = field(default_factory=dict)
    #: "hull": the vessel's curves from its hull; "linear": from its linear hydrostatics (a vessel
    #: without a hull beside bodies, docs/guide/stability.md#bodies)
    model: str = "hull"
    #: a body's name where this is a [[bodies]] body's curves from its own hull (an entry of `bodies`)
    name: str = ""

    def as_dict(self):
        """The JSON object of `jaxslosh stability --json` (docs/guide/stability.md)."""
        out = {"angle": [float(a) for a in self.angle], "gz": [float(g) for g in self.gz],
               "gz_frozen": [float(g) for g in self.gz_frozen], "gm0": float(self.gm0),
               "gm0_frozen": float(self.gm0_frozen),
               "vanishing_angle": None if self.vanishing_angle is None else float(self.vanishing_angle),
               "criteria": [c.as_dict() for c in self.criteria]}
        if self.name:                                   # a body's entry in "bodies": its curves from its hull
            out["model"] = self.model
        elif self.bodies or self.model != "hull":       # a scene of the vessel alone: its object as ever
            out["model"] = self.model
            out["bodies"] = {n: b.as_dict() for n, b in self.bodies.items()}
        return out

    def __getitem__(self, key):
        return self.as_dict()[key]


# ------------------------------------------------------------------------------------- the model

def hull_surface(scene):
    """The hull's closed surface (n, 3, 3) in the vessel frame: the box with its deck, or a closed
    mesh (hull/surface.py); SceneError naming the key when the scene has none this analysis can use."""
    hull = scene.vessel.hull
    if hull is None:
        raise SceneError("vessel.hull", "stability needs the hull's geometry: add a [vessel.hull] table "
                                        '(a box: length, beam, draft, kg and depth; or type = "mesh", a closed mesh)')
    if hull.closed_form and hull.depth is None:
        raise SceneError("vessel.hull.depth", "stability needs the box's depth from keel to deck (m): at large "
                                              "heels the deck edge immerses")
    try:
        return np.asarray(hull.triangles())
    except HullMeshError as e:
        raise SceneError("vessel.hull.file", str(e)) from None


@dataclass(frozen=True)
class _Model:
    hull: np.ndarray            # (n, 3, 3) vessel frame
    volume: float               # m^3 displaced: (ship + liquid) / rho
    mass: float                 # kg, ship + liquid
    tanks: np.ndarray           # (k, m, 3, 3) tank surfaces in the vessel frame, padded with repeated vertices
    tank_volume: np.ndarray     # (k,) the liquid's volume in its surface (at rest below the fill plane)
    tank_mass: np.ndarray       # (k,) kg
    rest_centroid: np.ndarray   # (k, 3) vessel frame
    size: float                 # m, the hull's extent: the scale of the lever tolerance


#: each tank's liquid at rest: (volume, first moment) under its fill plane
_rest_state = jax.jit(jax.vmap(submerged, in_axes=(0, None, 0)))


def build_model(scene) -> _Model:
    hull = np.asarray(hull_surface(scene))
    rho = scene.environment.water_density
    mass_l = np.array([t.liquid_mass for t in scene.tanks])
    mass = float(scene.vessel.mass + mass_l.sum())
    total = float(np.sum(np.einsum("ij,ij->i", np.cross(hull[:, 1] - hull[:, 0], hull[:, 2] - hull[:, 0]),
                                   hull.sum(axis=1))) / 18.0)      # V = 1/3 int x . N dS, exact on flat faces
    if mass / rho >= total:
        raise SceneError("vessel.mass", f"the ship and its liquid ({mass:.6g} kg) need {mass / rho:.6g} m^3 "
                                        f"displaced, more than the whole hull to its deck ({total:.6g} m^3)")
    tanks, vol, cen = _tanks(scene)
    return _Model(hull=hull, volume=mass / rho, mass=mass, tanks=tanks, tank_volume=vol, tank_mass=mass_l,
                  rest_centroid=cen, size=float(np.ptp(hull.reshape(-1, 3), axis=0).max()))


def _tanks(scene):
    """(surfaces (k, m, 3, 3) in the vessel frame, padded with repeated vertices; the liquid's volume
    in each at rest (k,); its centroid there (k, 3)) of the scene's tanks."""
    surfaces = [tank_surface(t) + np.asarray(t.origin) for t in scene.tanks]
    m = max((len(s) for s in surfaces), default=1)
    tanks = np.zeros((len(surfaces), m, 3, 3))
    for i, s in enumerate(surfaces):
        tanks[i, :len(s)] = s
        tanks[i, len(s):] = s[0, 0]                 # zero-area padding on a vertex of the tank
    vol, cen = np.zeros(len(surfaces)), np.zeros((len(surfaces), 3))
    if surfaces:
        fill = np.array([t.origin[2] + t.fill_depth for t in scene.tanks])
        v, mom = _rest_state(jnp.asarray(tanks), jnp.array([0.0, 0.0, 1.0]), jnp.asarray(fill))
        vol, cen = np.asarray(v), np.asarray(mom) / np.asarray(v)[:, None]
    return tanks, vol, cen


@functools.partial(jax.jit, static_argnames=("axis",))
def _level_levers(tanks, v_l, m_l, rest, heels, *, axis):
    """(heels,) the change of GZ times the displacement (kg m) when the tanks' liquids turn level at
    each heel (no sinkage nor trim: a vessel on linear springs), their rest state the frozen one."""
    def one(heel):
        R = _rotation(heel, 0.0) if axis == "roll" else _rotation(0.0, heel)
        _, V, S = jax.vmap(level, in_axes=(0, None, 0))(tanks, R[2], v_l)
        shift = R @ (m_l @ (S / V[:, None] - rest))       # the liquids' first moment moved, world axes
        return shift[1] if axis == "roll" else -shift[0]  # the COG moved by it: gz = -d[1] (roll), d[0] (pitch)
    return jax.vmap(one)(heels)


def _rotation(roll, pitch):
    cr, sr, cp, sp = jnp.cos(roll), jnp.sin(roll), jnp.cos(pitch), jnp.sin(pitch)
    one, zero = jnp.ones_like(roll), jnp.zeros_like(roll)
    Rx = jnp.array([[one, zero, zero], [zero, cr, -sr], [zero, sr, cr]])
    Ry = jnp.array([[cp, zero, sp], [zero, one, zero], [-sp, zero, cp]])
    return Ry @ Rx


def level(tris, n, volume, iterations=LEVEL_ITERATIONS):
    """(offset c, volume, first moment) of the plane n . x = c under which the closed surface holds
    `volume`: Newton's steps on c (dV/dc is the cut's area), kept inside a bracket that every step
    narrows (a bisection where a step would leave it)."""
    h = tris.reshape(-1, 3) @ n
    lo0, hi0 = h.min(), h.max()
    full = submerged(tris, n, hi0)[0]

    def step(s):
        i, lo, hi, c, _ = s
        v, _, a = submerged_and_cut(tris, n, c)
        f = v - volume
        lo = jnp.where(f <= 0, c, lo)
        hi = jnp.where(f > 0, c, hi)
        ok = a > 0
        cn = c - jnp.where(ok, f / jnp.where(ok, a, 1.0), 0.0)
        inside = ok & (cn > lo) & (cn < hi)
        done = jnp.abs(f) <= TOLERANCE * 1e-4 * full
        return i + 1, lo, hi, jnp.where(done, c, jnp.where(inside, cn, 0.5 * (lo + hi))), done

    def going(s):
        return (s[0] < iterations) & ~s[4]

    c0 = lo0 + (hi0 - lo0) * volume / full
    # until the volume is within round-off (one more step then costs nothing: Newton's is quadratic)
    _, _, _, c, _ = jax.lax.while_loop(going, step, (0, lo0, hi0, c0, False))
    V, S = submerged(tris, n, c)
    return c, V, S


def _levers(arrays, axis: str, has_tanks: bool):
    """(heel, frozen) -> (gz, free angle, offset, volume error, free lever): the equilibrium at one
    heel with the liquids frozen (1.0) or level (0.0). Frozen and level share one program; the
    slope of the free lever for Newton's steps is a difference of two states computed side by side
    (vmapped: no second copy of the program, as a jvp through the plane solves would make)."""
    hull, tanks, m_l, v_l, rest, mass, volume, size = arrays
    free = 0 if axis == "roll" else 1          # the world component of B - G the free angle zeroes

    def attitude(heel, psi):
        return _rotation(heel, psi) if axis == "roll" else _rotation(psi, heel)

    def centre_of_gravity(n, frozen):
        c = rest
        if has_tanks:
            _, V, S = jax.vmap(level, in_axes=(0, None, 0))(tanks, n, v_l)
            c = jnp.where(frozen > 0.5, rest, S / V[:, None])
        return (m_l @ c) / mass             # the ship's own COG is the origin

    def state(heel, psi, frozen):
        R = attitude(heel, psi)
        n = R[2]                            # the sea's up direction in the vessel frame
        off, V, S = level(hull, n, volume)
        d = R @ (S / V - centre_of_gravity(n, frozen))
        return d, off, V

    pair = jax.vmap(state, in_axes=(None, 0, None))

    def solve(heel, frozen):
        def newton(s):
            i, psi, _ = s
            d, _, _ = pair(heel, psi + jnp.array([0.0, TRIM_STEP]), frozen)
            g, dg = d[0, free], (d[1, free] - d[0, free]) / TRIM_STEP
            ok = jnp.abs(dg) > 0
            return i + 1, psi - jnp.where(ok, g / jnp.where(ok, dg, 1.0), 0.0), jnp.abs(g) <= 1e-3 * TOLERANCE * size

        _, psi, _ = jax.lax.while_loop(lambda s: (s[0] < TRIM_ITERATIONS) & ~s[2], newton,
                                       (0, jnp.zeros_like(heel), False))
        d, off, V = state(heel, psi, frozen)
        gz = -d[1] if axis == "roll" else d[0]
        return gz, psi, off, V / volume - 1.0, d[free]

    return solve


# The model's numbers are arguments, not constants of the program: scenes whose hull and tanks have
# the same counts of triangles share it (and the heels are padded to a multiple of _PAD). It runs
# once per call: XLA's optimisation off halves its compile and costs little at run time.
_PAD = 64


@functools.partial(jax.jit, static_argnames=("axis", "has_tanks"), compiler_options=START_OPTIONS)
def _curves(arrays, heels, *, axis, has_tanks):
    """Both equilibria (level, frozen) at every heel: arrays (heels, 2)."""
    solve = _levers(arrays, axis, has_tanks)
    return jax.vmap(jax.vmap(solve, in_axes=(None, 0)), in_axes=(0, None))(heels, jnp.array([0.0, 1.0]))


def _check(what, angles, verr, lever, size):
    bad = ~((np.abs(verr) < TOLERANCE) & (np.abs(lever) < TOLERANCE * size))
    if np.any(bad):
        i = int(np.argmax(bad))
        raise StabilityFailure(f"the equilibrium with the liquids {what} at {np.degrees(angles[i]):.6g} deg did "
                               f"not converge (volume off by {verr[i]:.3g}, free lever {lever[i]:.3g} m)")


def is_code_criteria(angle, gz, gm0, area_30, area_40, area_30_40):
    """IS Code 2008 Part A 2.2 on a GZ curve (rad, m) that covers 0-40 degrees and beyond."""
    a, g = np.asarray(angle), np.asarray(gz)
    i = int(np.argmax(g))
    a_max = float(a[i])
    if 0 < i < len(a) - 1:                # the parabola through the top three samples
        y0, y1, y2 = g[i - 1], g[i], g[i + 1]
        den = y0 - 2 * y1 + y2
        if den < 0:
            a_max = float(a[i] + 0.5 * (a[i + 1] - a[i]) * (y0 - y2) / den)
    past_30 = a >= np.radians(30.0) - 1e-12
    gz_30 = float(g[past_30].max()) if past_30.any() else float("nan")
    rows = [("area 0-30 deg (m rad)", area_30, 0.055), ("area 0-40 deg (m rad)", area_40, 0.090),
            ("area 30-40 deg (m rad)", area_30_40, 0.030), ("GZ at an angle >= 30 deg (m)", gz_30, 0.20),
            ("angle of maximum GZ (rad)", a_max, float(np.radians(25.0))), ("GM0 (m)", gm0, 0.15)]
    return tuple(Criterion(name, float(v), float(lim), bool(v >= lim)) for name, v, lim in rows)


def _gauss(lo, hi, n):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (hi - lo) * x + 0.5 * (hi + lo), 0.5 * (hi - lo) * w


def stability(scene, angles=None, axis: str = "roll", *, criteria: bool = True) -> Stability:
    """GZ (m) at the heels `angles` (rad; default 0 to 80 degrees by 1) about the `axis` "roll" or
    "pitch", with the liquids level and frozen; GM0 both ways; the angle of vanishing stability;
    the IS Code 2008 Part A 2.2 criteria (roll only) on the level curve. `scene`: a Scene or the
    path of a scene file. Raises SceneError for a scene without what it needs (naming the key),
    StabilityFailure where an equilibrium does not converge. `criteria=False` skips the criteria
    and the heels they are computed at (`criteria` is then empty). A scene's [[bodies]] add their
    linear curves (`bodies`, analysis/bodystability.py); a vessel without a hull beside them gets
    its own linear curve (model "linear")."""
    if isinstance(scene, str) or hasattr(scene, "__fspath__"):
        scene = load_scene(scene)
    if axis not in AXES:
        raise ValueError(f"axis must be one of {AXES}, got {axis!r}")
    if angles is None:
        angles = np.radians(np.linspace(*DEFAULT_DEGREES))
    angles = np.atleast_1d(np.asarray(angles, dtype=float))
    if angles.ndim != 1 or not np.all(np.isfinite(angles)):
        raise ValueError("angles must be a 1-D array of finite numbers (rad)")
    bodies = bodies_stability(scene, angles, axis)
    for i, b in enumerate(scene.bodies):      # a body's own hull gives its large-angle curves
        if b.hull is not None and (not b.hull.closed_form or b.hull.depth is not None):
            bodies[b.name] = _body_hull(scene, i, angles, axis, criteria)
        elif b.tanks and b.hydrostatics is not None:     # its linear curve, its liquids frozen and level
            bodies[b.name] = dataclasses.replace(_linear_vessel(_alone(scene, i), angles, axis, {}), name=b.name)
    if bodies and scene.vessel.hull is None and scene.vessel.hydrostatics is not None:
        return _linear_vessel(scene, angles, axis, bodies)
    model = build_model(scene)
    grid = np.radians(np.linspace(*DEFAULT_DEGREES))
    x30, w30 = _gauss(0.0, np.radians(30.0), _AREA_POINTS[0])
    x40, w40 = _gauss(np.radians(30.0), np.radians(40.0), _AREA_POINTS[1])
    # the angles asked for, upright (the sinkage's zero), GM0's two points and the criteria's own
    # (roll: the default grid and the areas' Gauss points), each distinct heel solved once
    judged = criteria and axis == "roll"
    parts = [angles, [0.0, -GM0_STEP, GM0_STEP]] + ([grid, x30, x40] if judged else [])
    every, where = np.unique(np.concatenate(parts), return_inverse=True)
    where = np.split(where.reshape(-1), np.cumsum([len(p) for p in parts])[:-1])
    k = len(every)
    heels = np.concatenate([every, np.zeros(-k % _PAD)])
    tanks = len(model.tank_mass) > 0
    arrays = tuple(jnp.asarray(x, dtype=float) for x in (
        model.hull, model.tanks if tanks else np.zeros((1, 1, 3, 3)), model.tank_mass if tanks else np.zeros(1),
        model.tank_volume if tanks else np.ones(1), model.rest_centroid if tanks else np.zeros((1, 3)),
        model.mass, model.volume, model.size))
    gz2, psi2, off2, verr2, lever2 = (np.asarray(x)[:k] for x in _curves(arrays, jnp.asarray(heels), axis=axis,
                                                                         has_tanks=tanks))
    for j, what in enumerate(("level", "frozen")):
        _check(what, every, verr2[:, j], lever2[:, j], model.size)
    at = where[0]
    up, minus, plus = where[1]
    gm0, gm0_f = ((gz2[plus] - gz2[minus]) / (2 * GM0_STEP)).tolist()
    gz, gz_f = gz2[at, 0] + 0.0, gz2[at, 1] + 0.0         # + 0.0: no -0.0 upright
    crit = ()
    if judged:
        a30 = float(w30 @ gz2[where[3], 0])
        a3040 = float(w40 @ gz2[where[4], 0])
        crit = is_code_criteria(grid, gz2[where[2], 0], gm0, a30, a30 + a3040, a3040)
    return Stability(angle=angles, gz=gz, gz_frozen=gz_f, gm0=gm0, gm0_frozen=gm0_f,
                     vanishing_angle=first_vanishing(angles, gz), criteria=crit, axis=axis,
                     sinkage=off2[at, 0] - off2[up, 0], trim=psi2[at, 0], bodies=bodies)


def _body_hull(scene, i: int, angles, axis: str, criteria: bool) -> Stability:
    """The Stability of the body `scene.bodies[i]` from its hull, the vessel's analysis on the body as
    the only vessel of the scene with its own tanks (docs/guide/stability.md#bodies)."""
    try:
        s = stability(_alone(scene, i), angles, axis, criteria=criteria)
    except SceneError as e:      # its keys are the body's
        key = e.key.replace("vessel", f"bodies[{i}]", 1)
        raise SceneError(key, str(e)[len(e.key) + 2:].replace("vessel", "body")) from None
    return dataclasses.replace(s, name=scene.bodies[i].name)


def _alone(scene, i: int):
    """The body `scene.bodies[i]` as the only vessel of the scene, with its own tanks."""
    b = scene.bodies[i]
    return dataclasses.replace(scene, vessel=Vessel(mass=b.mass, inertia=b.inertia, hydrostatics=b.hydrostatics,
                                                    hull=b.hull, name=b.name, cog_height=b.cog_height),
                               tanks=b.tanks, bodies=(), connections=(), mooring=())


def _linear_vessel(scene, angles, axis: str, bodies: dict) -> Stability:
    """The Stability of a vessel without a hull beside bodies: its linear hydrostatics' curve, as the
    bodies' (it neither sinks nor trims at a heel; no criteria: they judge a hull's curve, which
    linear springs only approximate near upright). Its GM is the ship's with the tank liquids
    frozen (as its run's springs hold it): that is the frozen curve, and the level one adds each
    tank's liquid turned level in its own shape (the free-surface effect)."""
    env = scene.environment
    h = scene.vessel.hydrostatics
    v = linear_stability(scene.vessel.name, h, env.water_density, env.gravity, angles, axis)
    gz, gm0 = v.gz, v.gm0
    if scene.tanks:
        tanks, vol, cen = _tanks(scene)
        mass_l = np.array([t.liquid_mass for t in scene.tanks])
        heels = np.concatenate([angles, [-GM0_STEP, GM0_STEP]])
        lever = np.asarray(_level_levers(jnp.asarray(tanks), jnp.asarray(vol), jnp.asarray(mass_l), jnp.asarray(cen),
                                         jnp.asarray(heels), axis=axis)) / (env.water_density * h.displaced_volume)
        gz = v.gz + lever[:-2] + 0.0
        gm0 = v.gm0 + float((lever[-1] - lever[-2]) / (2 * GM0_STEP))
    zero = np.zeros_like(v.gz)
    return Stability(angle=angles, gz=gz, gz_frozen=v.gz, gm0=gm0, gm0_frozen=v.gm0,
                     vanishing_angle=first_vanishing(angles, gz), axis=axis, sinkage=zero, trim=zero, bodies=bodies,
                     model="linear")
