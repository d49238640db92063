"""The fitted parameters: scene keys, their bounds and the transformed variable theta the
optimisers see (log for positive quantities, a sigmoid between two bounds)."""
from __future__ import annotations

import math
from typing import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from ..hull.hydrostatics import rest_hydrostatics
from ..scene.keys import canonical_key, owner_of, scene_values, spring_key, traceable
from ..scene.types import Scene, SceneError


# keys whose values are positive by nature: fitted in log by default
POSITIVE = ("environment.gravity", "environment.water_density", "vessel.mass", "vessel.inertia",
            "vessel.hydrostatics.waterplane_area", "vessel.hydrostatics.displaced_volume",
            "vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l", "vessel.hull.kg")
# ... and of every [[bodies]] body and [[connections]] connection (after the name)
POSITIVE_OWN = {"bodies": ("mass", "inertia", "hydrostatics.waterplane_area", "hydrostatics.displaced_volume",
                           "hydrostatics.gm_t", "hydrostatics.gm_l", "hull.kg"),
                "connections": ("length", "stiffness")}


def inertia_key(key: str) -> bool:
    """Whether a canonical key is the vessel's or a body's inertia (fitted by its diagonal)."""
    return key == "vessel.inertia" or (key.startswith("bodies.") and key.count(".") == 2 and key.endswith(".inertia"))


def positive(key: str) -> bool:
    """Whether a fitted key's value is positive by nature (fitted in log by default)."""
    group, _, rest = key.partition(".")
    return key in POSITIVE or rest.partition(".")[2] in POSITIVE_OWN.get(group, ())


class Param:
    """One fitted key: its slice of theta, its transform and how it goes into simulate(params=)."""

    def __init__(self, key, base, start, lo, hi):
        self.key = key
        self.base = base                              # the scene's value (np array; 3x3 for inertia)
        self.start = np.atleast_1d(np.asarray(start, dtype=float))
        self.size = self.start.size
        self.lo, self.hi = lo, hi
        self.scalar = np.ndim(start) == 0
        self.scale = np.where(self.start != 0.0, np.abs(self.start), 1.0)

    def theta_of(self, p):
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            u = (p - lo) / (hi - lo)
            return np.log(u) - np.log1p(-u)
        if lo is not None:
            return np.log(p - lo)
        if hi is not None:
            return np.log(hi - p)
        return p / self.scale

    def p_of(self, th):
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            return lo + (hi - lo) * jax.nn.sigmoid(th)
        if lo is not None:
            return lo + jnp.exp(th)
        if hi is not None:
            return hi - jnp.exp(th)
        return self.scale * th

    def dp_dtheta(self, th):
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            s = 1.0 / (1.0 + np.exp(-th))
            return (hi - lo) * s * (1 - s)
        if lo is not None:
            return np.exp(th)
        if hi is not None:
            return -np.exp(th)
        return self.scale

    def param_value(self, p):
        """The value simulate(params=) takes for this key, from the fitted components p."""
        if inertia_key(self.key):
            i = np.arange(3)
            return jnp.asarray(self.base).at[i, i].set(p)
        return p[0] if self.scalar else p


def _bound_pair(key, b):
    if b is None:
        return None, None
    try:
        lo, hi = b
    except (TypeError, ValueError):
        raise SceneError(f"bounds.{key}", f"expected (lo, hi), got {b!r}")
    lo = None if lo is None or (isinstance(lo, (int, float)) and lo == -math.inf) else float(lo)
    hi = None if hi is None or (isinstance(hi, (int, float)) and hi == math.inf) else float(hi)
    if lo is not None and hi is not None and not lo < hi:
        raise SceneError(f"bounds.{key}", f"the lower bound {lo} is not below the upper bound {hi}")
    return lo, hi


def fit_keys(scene: Scene, fit: Sequence[str]) -> tuple:
    """Validate the keys to fit; SceneError naming a key that is unknown or cannot be fitted."""
    if isinstance(fit, str):
        fit = [fit]
    fit = list(fit)
    if not fit:
        raise SceneError("fit", "give at least one key to fit")
    keys = traceable(scene, fit)
    for given, key in zip(fit, keys):
        if spring_key(scene, key):
            hull = key.rpartition(".hydrostatics.")[0] + ".hull"
            raise SceneError(given, 'model = "nonlinear" takes its restoring from the hull, which this value '
                                    f"does not enter: fit {hull}.kg (a mesh: {hull}.cog); the fit reports "
                                    "the implied GM0 = KM - KG")
    return keys


# GM0 = KM - KG of the hull at rest: what a fitted KG (a mesh's COG) implies for the small-angle
# springs, reported beside it (the vessel's keys; a body's after its `bodies.<name>.`)
IMPLIED_BY_KG = ("vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l")


def _fitted_hulls(keys) -> list:
    """(the prefix `vessel` or `bodies.<name>`, the hull key) of each fitted KG or COG."""
    return [(k.rpartition(".hull.")[0], k) for k in keys if k.endswith((".hull.kg", ".hull.cog"))
            and (k.startswith("vessel.") or k.startswith("bodies."))]


def implied_keys(keys) -> tuple:
    """The scene values that follow from the fitted keys (the GM0s of a fitted KG or COG, the
    vessel's or a body's, and a body's `cog_height`, its hull's kg - draft unless given): a record
    made with another KG differs in them too, and the fit reports the GM0s."""
    return tuple(f"{prefix}.{k.partition('.')[2]}" for prefix, _ in _fitted_hulls(keys)
                 for k in IMPLIED_BY_KG + (("vessel.cog_height",) if prefix != "vessel" else ()))


def implied_values(scene: Scene, values: dict, errors: dict) -> tuple[dict, dict]:
    """({key: value}, {key: standard error}) of the implied keys: GM0 = KM - KG with the hull's KM
    (the scene's GM0 plus its KG) for a fitted KG, whose standard error it shares (dGM0/dKG = -1);
    for a mesh's fitted COG the GM0s of its surface at rest about that COG, with the standard
    error of the COG's height (exact for a COG on the centre plane of a symmetric hull). For the
    vessel and each body whose KG or COG is fitted."""
    out, se = {}, {}
    for prefix, key in _fitted_hulls(values):
        owner = owner_of(scene, key)[0]
        h, hull = owner.hydrostatics, owner.hull
        names = [f"{prefix}.{k.partition('.')[2]}" for k in IMPLIED_BY_KG]
        if key.endswith(".kg"):
            kg0, kg = hull.kg, values[key]
            own = {"gm_t": h.gm_t + kg0 - kg, "gm_l": h.gm_l + kg0 - kg}
            err = errors[key]
        else:
            env = scene.environment
            cog = np.asarray(values[key], dtype=float)
            tris = hull.triangles() + (np.asarray(hull.cog, dtype=float) - cog)
            own = rest_hydrostatics(tris, -cog[2], env.water_density, env.gravity)
            err = errors[key][2]
        for name in names:
            out[name], se[name] = own[name.rpartition(".")[2]], err
    return out, se


def make_params(scene: Scene, keys, x0, bounds) -> list:

    values = scene_values(scene)
    x0 = {canonical_key(scene, k): v for k, v in (x0 or {}).items()}
    bounds = {canonical_key(scene, k): v for k, v in (bounds or {}).items()}
    for k in list(x0) + list(bounds):
        if k not in keys:
            raise SceneError(k, f"given in x0 or bounds but not fitted (fitted: {', '.join(keys)})")
    out = []
    for key in keys:
        base = np.asarray(values[key], dtype=float)
        default = np.diag(base) if inertia_key(key) else base
        start = np.asarray(x0.get(key, default), dtype=float)
        if start.shape != default.shape:
            raise SceneError(f"x0.{key}", f"expected shape {default.shape}, got {start.shape}")
        if key in bounds:
            lo, hi = _bound_pair(key, bounds[key])
        else:
            lo, hi = (0.0, None) if positive(key) else (None, None)
        if not np.all(np.isfinite(start)):
            raise SceneError(f"x0.{key}", "the start must be finite")
        if (lo is not None and np.any(start <= lo)) or (hi is not None and np.any(start >= hi)):
            why = "; the value must stay positive" if positive(key) and key not in bounds else ""
            raise SceneError(key, f"the start {start.tolist()} is not strictly inside the bounds ({lo}, {hi}){why}")
        out.append(Param(key, base, start, lo, hi))
    return out


def param_value(scene: Scene, key: str, value):
    if inertia_key(key):
        base = np.array(scene_values(scene)[key], dtype=float)
        base[np.arange(3), np.arange(3)] = value
        return base
    return np.asarray(value, dtype=float) if isinstance(value, list) else float(value)
