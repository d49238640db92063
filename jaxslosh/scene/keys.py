"""The registry of scene keys: every real value of a scene by its dotted TOML path, which of them
`params` may trace, and the one place where overrides are resolved.

A key names a value as the scene file writes it: `vessel.hydrostatics.gm_t`, `tanks.tank.fill_depth`
or, by index, `tanks[0].fill_depth` (the canonical form is the name form). `simulate(params=...)`,
`jaxslosh sweep --param` and `identify --fit` all go through `resolve_params`; `--duration` and
`--dt` through `with_overrides`, which returns a scene validated like a loaded one. Concrete values
(each run of a sweep, concrete `params`) are checked as the loader checks a scene by `check_values`.
"""
from __future__ import annotations

import copy
import dataclasses
import difflib
import functools
from typing import Any, Iterable, Optional

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from .bodies import tank_carriers
from .fields import show
from .keydocs import KEYS as KEY_DOCS, TABLES as KEY_TABLES  # noqa: F401  default, unit, meaning (docs)
from .load import forced_span, parse_scene, step_warnings
from .lumped_keys import LUMPED_TRACEABLE
from .types import Material, Scene, SceneError


class _Keys(tuple):
    """The traceable keys; `<name>` in an entry stands for the name of any tank of the scene
    (`tanks.<name>.fill_depth` holds `tanks.tank.fill_depth`)."""

    def __contains__(self, key) -> bool:
        if not isinstance(key, str):
            return False
        for pattern in self:
            if "<name>" not in pattern:
                if key == pattern:
                    return True
                continue
            head, tail = pattern.split("<name>")
            if key.startswith(head) and key.endswith(tail) and len(key) > len(head) + len(tail):
                if not any(ch in key[len(head):len(key) - len(tail)] for ch in ".[]/"):
                    return True
        return False


# Scene values that simulate(params=...) may replace by traced values (the vessel is rebuilt per
# call; the liquid matrices are assembled from traced fill depth, density, sound speed and gravity;
# a traced damping ratio scales the modal damping, whose modes come from the scene's values; the
# harmonic forced motion's amplitude, frequency and phase are leaves of its term); a tank on a body
# takes them alike (assemble/bodies.py body_liquid).
TANK_TRACEABLE = ("fill_depth", "fluid.density", "fluid.sound_speed", "damping.ratio")
# a mooring line's values, leaves of the lines' term (jaxslosh/mooring/term.py)
MOORING_TRACEABLE = ("length", "weight", "ea", "seabed_friction")
# a connection's values, leaves of its link (physics/bodies.py)
CONNECTION_TRACEABLE = ("length", "stiffness", "damping")
# a [[bodies]] body's values, the vessel's own (without a forced motion, which a body has not):
# leaves of its rigid terms, its hull's pressure and its initial state (assemble/bodies.py)
BODY_TRACEABLE = ("mass", "inertia", "hydrostatics.waterplane_area", "hydrostatics.displaced_volume",
                  "hydrostatics.gm_t", "hydrostatics.gm_l", "initial.position", "initial.velocity",
                  "initial.angular_velocity", "initial.roll_pitch_yaw", "hull.kg", "hull.cog")


TRACEABLE = _Keys((
    "environment.gravity", "environment.water_density", "vessel.mass", "vessel.inertia",
    "vessel.hydrostatics.waterplane_area", "vessel.hydrostatics.displaced_volume",
    "vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l",
    "vessel.initial.position", "vessel.initial.velocity", "vessel.initial.angular_velocity",
    "vessel.initial.roll_pitch_yaw", "vessel.hull.kg", "vessel.hull.cog",
    "vessel.forced.amplitude", "vessel.forced.frequency", "vessel.forced.phase",
) + tuple(f"tanks.<name>.{k}" for k in TANK_TRACEABLE) + ("waves.amplitude", "waves.hs")
  + tuple(f"mooring.<name>.{k}" for k in MOORING_TRACEABLE)
  + tuple(f"connections.<name>.{k}" for k in CONNECTION_TRACEABLE)
  + tuple(f"bodies.<name>.{k}" for k in BODY_TRACEABLE))

# keys traced by the nonlinear hydrostatics alone (assemble/hull.py moves the hull's surface against the
# COG); the linear model's GM springs were derived from them when the scene was loaded
HULL_TRACEABLE = ("vessel.hull.kg", "vessel.hull.cog")
# keys the nonlinear hydrostatics does not read (the restoring is the hull's): tracing them would
# change nothing
SPRING_KEYS = ("vessel.hydrostatics.waterplane_area", "vessel.hydrostatics.displaced_volume",
               "vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l")


def owner_of(scene: Scene, key: str):
    """(the floating body a canonical key belongs to: the scene's Vessel or a Body, its key in the
    vessel's form: `bodies.barge.hull.kg` -> "vessel.hull.kg"), or (None, key) for other keys: one
    rule for the vessel's keys and every body's."""
    if key.startswith("vessel."):
        return scene.vessel, key
    if key.startswith("bodies."):
        name, _, rest = key[len("bodies."):].partition(".")
        body = next((b for b in scene.bodies if b.name == name), None)
        if body is not None:
            return body, "vessel." + rest
    return None, key


def hull_key(scene: Scene, key: str) -> bool:
    """Whether a canonical key is traced by its body's nonlinear hydrostatics alone (a hull's KG or COG)."""
    return owner_of(scene, key)[1] in HULL_TRACEABLE


def spring_key(scene: Scene, key: str) -> bool:
    """Whether a canonical key is a GM spring of a body (or the vessel) whose restoring is its hull's
    (the nonlinear hydrostatics): tracing it would change nothing."""
    owner, own = owner_of(scene, key)
    return own in SPRING_KEYS and owner is not None and owner.hydrostatics is not None and owner.hydrostatics.nonlinear


def scene_values(scene: Scene) -> dict[str, Any]:
    """Every real-valued quantity of the scene by its dotted TOML path.

    Scalars are floats; vectors (`vessel.initial.velocity`, `tanks.<name>.origin`, ...) are tuples
    of 3 floats and `vessel.inertia` a 3x3 nested tuple; a `[campaign]` table adds its duration and
    its limits (`campaign.limits.roll`, `campaign.limits.probe.B`). Tanks, structures and probes appear twice,
    by name (`tanks.tank.fill_depth`) and by index (`tanks[0].fill_depth`); `canonical_key` maps the
    index form to the name form. Integer settings (mesh counts, save_every, ...) are not values.
    """
    v: dict[str, Any] = {}
    env, sim, ves = scene.environment, scene.simulation, scene.vessel
    v["environment.gravity"] = env.gravity
    v["environment.water_density"] = env.water_density
    for key in ("duration", "dt", "alpha", "rho_inf", "tolerance"):
        v[f"simulation.{key}"] = getattr(sim, key)
    v["vessel.mass"] = ves.mass
    v["vessel.inertia"] = ves.inertia
    if ves.hydrostatics is not None:
        for key in ("waterplane_area", "displaced_volume", "gm_t", "gm_l"):
            v[f"vessel.hydrostatics.{key}"] = getattr(ves.hydrostatics, key)
    for key in ("position", "velocity", "angular_velocity", "roll_pitch_yaw"):
        v[f"vessel.initial.{key}"] = getattr(ves.initial, key)
    if ves.hull is not None:      # the COG against the hull: a box's KG, a mesh's COG in its file's coordinates
        key, value = ves.hull.cog_key()
        v[key] = value
    f = ves.forced
    if f is not None and f.profile != "record":   # a record's samples are its file's, not values of the scene
        own = ("amplitude", "frequency", "phase", "ramp") if f.profile == "harmonic" else ("rate", "duration")
        for key in own:
            v[f"vessel.forced.{key}"] = getattr(f, key)
    if scene.waves is not None:   # the wave forces are linear in these (waves.py)
        v[scene.waves.height_key] = scene.waves.height

    def material(prefix: str, m: Material) -> dict[str, float]:
        return {f"{prefix}.young": m.young, f"{prefix}.poisson": m.poisson, f"{prefix}.density": m.density}

    for i, t in enumerate(file_tanks(scene)):     # the vessel's and the bodies' alike (`tanks.body`)
        own = {"origin": t.origin, "size": t.size, "fill_depth": t.fill_depth,
               "fluid.density": t.fluid.density, "fluid.sound_speed": t.fluid.sound_speed}
        if t.damping is not None:
            own["damping.ratio"], own["damping.viscosity"] = t.damping.ratio, t.damping.viscosity
        if t.wall_spec is not None:
            own["walls.thickness"] = t.wall_spec.thickness
            own |= material("walls.material", t.wall_spec.material)
        for prefix in (f"tanks.{t.name}", f"tanks[{i}]"):
            v.update({f"{prefix}.{k}": x for k, x in own.items()})
    for i, s in enumerate(scene.structures):
        own = {"origin": s.origin, "size": s.size} | material("material", s.material)
        for prefix in (f"structures.{s.name}", f"structures[{i}]"):
            v.update({f"{prefix}.{k}": x for k, x in own.items()})
    for i, p in enumerate(scene.probes):
        for prefix in (f"probes.{p.name}", f"probes[{i}]"):
            v[f"{prefix}.point"] = p.point
    for i, m in enumerate(scene.mooring):
        own = {"length": m.length, "weight": m.weight, "ea": m.ea, "seabed_friction": m.seabed_friction,
               "fairlead": m.fairlead, "anchor": m.anchor}
        for prefix in (f"mooring.{m.name}", f"mooring[{i}]"):
            v.update({f"{prefix}.{k}": x for k, x in own.items()})
    for i, c in enumerate(scene.connections):
        own = {"length": c.length, "damping": c.damping}
        if c.stiffness is not None:
            own["stiffness"] = c.stiffness
        for prefix in (f"connections.{c.name}", f"connections[{i}]"):
            v.update({f"{prefix}.{k}": x for k, x in own.items()})
    for i, b in enumerate(scene.bodies):
        h = b.hydrostatics
        own = {"mass": b.mass, "inertia": b.inertia, "cog_height": b.cog_height, "heading": b.heading,
               "hydrostatics.waterplane_area": h.waterplane_area, "hydrostatics.displaced_volume": h.displaced_volume,
               "hydrostatics.gm_t": h.gm_t, "hydrostatics.gm_l": h.gm_l}
        own |= {f"initial.{k}": getattr(b.initial, k) for k in ("position", "velocity", "angular_velocity",
                                                                  "roll_pitch_yaw")}
        if b.hull is not None:      # as the vessel's: a box's KG, a mesh's COG
            key, value = b.hull.cog_key()
            own[key.partition(".")[2]] = value
        for prefix in (f"bodies.{b.name}", f"bodies[{i}]"):
            v.update({f"{prefix}.{k}": x for k, x in own.items()})
    if scene.campaign is not None:   # a campaign's settings (never traced: they change no run)
        if scene.campaign.duration is not None:
            v["campaign.duration"] = scene.campaign.duration
        for channel, limit in scene.campaign.limits:
            v[f"campaign.limits.{channel}"] = limit
    return v


def file_tanks(scene: Scene) -> tuple:
    """Every tank of the scene, the vessel's and each body's, in the order of the scene file's
    [[tanks]] (the `i` of `tanks[i]` keys); a scene built without a file: the vessel's, then each
    body's. The vessel's alone (`scene.tanks`) without [[bodies]]."""
    if not scene.bodies:
        return tuple(scene.tanks)
    groups = {"vessel": list(scene.tanks)} | {b.name: list(b.tanks) for b in scene.bodies}
    tables = toml_mapping(scene.text).get("tanks", []) if scene.text else []
    carriers = tank_carriers(tables, scene.vessel.name)
    if sorted(carriers) != sorted(c for c, ts in groups.items() for _ in ts):   # not this scene's file
        return tuple(t for ts in groups.values() for t in ts)
    return tuple(groups[c].pop(0) for c in carriers)


def canonical_key(scene: Scene, key: str) -> str:
    """The name form of a dotted key: `tanks[0].fill_depth` -> `tanks.tank.fill_depth` (others unchanged)."""
    for group, items in (("tanks", file_tanks(scene)), ("structures", scene.structures), ("probes", scene.probes),
                         ("mooring", scene.mooring), ("connections", scene.connections),
                         ("bodies", scene.bodies)):
        if key.startswith(group + "["):
            index, sep, rest = key[len(group) + 1:].partition("]")
            if sep and index.isdigit() and int(index) < len(items):
                return f"{group}.{items[int(index)].name}{rest}"
    return key


def check_param_keys(scene: Scene, keys: Iterable[str]) -> tuple[str, ...]:
    """Raise SceneError for a key that is not in `scene_values(scene)`, or for two keys (index form
    and name form) that name the same value. Returns the keys in their canonical (name) form."""
    known = scene_values(scene)
    seen: dict[str, str] = {}
    for key in keys:
        if not isinstance(key, str):
            raise SceneError("params", f"keys must be dotted TOML paths (strings), got {key!r}")
        if key not in known:
            close = difflib.get_close_matches(key, list(known), n=3, cutoff=0.6)
            hint = f"did you mean {', '.join(close)}? " if close else ""
            raise SceneError(key, f"not a value of this scene that params can set; {hint}"
                                  f"(known: {', '.join(k for k in known if '[' not in k)})")
        canon = canonical_key(scene, key)
        if canon in seen:
            raise SceneError(key, f"names the same value as {seen[canon]}; give it once")
        seen[canon] = key
    return tuple(seen)


def resolve_params(scene: Scene, params: Optional[dict]) -> dict:
    """`params` with canonical keys, each a traceable value of this scene given once, its value of
    the scene's shape (a scalar, 3 numbers, or for `vessel.inertia` a 3 x 3 matrix or its diagonal).
    SceneError names the first key that is not."""
    params = dict(params or {})
    keys = traceable(scene, params)
    values = scene_values(scene)
    return {key: _shaped(given, value, values[key]) for (given, value), key in zip(params.items(), keys)}


def traceable(scene: Scene, keys: Iterable[str]) -> tuple[str, ...]:
    """The canonical form of keys that params may trace; SceneError names the first that is not
    a value of this scene, is not traceable, or names a value another key names too."""
    keys = list(keys)
    canon = check_param_keys(scene, keys)
    for given, key in zip(keys, canon):
        if key not in TRACEABLE:
            raise SceneError(given, "cannot be traced by params, a sweep or a fit (traceable: "
                                    + ", ".join(traceable_keys(scene)) + ")")
        if _lumped_refused(scene, key):
            raise SceneError(given, "cannot be traced on a lumped line (its seabed has no friction); a lumped "
                                    "line traces " + ", ".join(LUMPED_TRACEABLE) + " (docs/guide/moorings-lumped.md)")
        if hull_key(scene, key) and not _hull_restoring(scene, key):
            table = key.rpartition(".hull.")[0]
            raise SceneError(given, f'is traced by the nonlinear hydrostatics only ([{table}.hydrostatics] model = '
                                    '"nonlinear", [effects] buoyancy on): the linear model\'s GM springs were fixed '
                                    f"when the scene was loaded (trace {table}.hydrostatics.gm_t there)")
    return canon


def _lumped_refused(scene: Scene, key: str) -> bool:
    """Whether a canonical key is a mooring value that a lumped line does not trace (LUMPED_TRACEABLE)."""
    return any(m.model == "lumped" and key.startswith(f"mooring.{m.name}.")
               and key[len(f"mooring.{m.name}."):] not in LUMPED_TRACEABLE for m in scene.mooring)


def _hull_restoring(scene: Scene, key: str) -> bool:
    """Whether the restoring of the key's body (or the vessel) is its hull's wetted surface (the
    nonlinear hydrostatics, switched on)."""
    h = owner_of(scene, key)[0].hydrostatics
    return h is not None and h.nonlinear and scene.effects.buoyancy


def traceable_keys(scene: Scene) -> tuple[str, ...]:
    """The keys of this scene that params may trace."""
    return tuple(k for k in scene_values(scene)
                 if "[" not in k and k in TRACEABLE and (not hull_key(scene, k) or _hull_restoring(scene, k))
                 and not _lumped_refused(scene, k))


def _shaped(key: str, value, base):
    """The value, checked against the shape of the scene's value (tracers keep their own)."""
    want = np.shape(base)
    got = np.shape(value)
    if got == want:
        return value
    if key.endswith("inertia") and got == (3,):      # the diagonal (build makes the matrix)
        return value
    what = {(): "a number", (3,): "3 numbers", (3, 3): "3 diagonal values or a 3 x 3 matrix"}.get(want, str(want))
    raise SceneError(key, f"needs {what}, got a value of shape {got}")


def with_overrides(scene: Scene, *, duration: Optional[float] = None, dt: Optional[float] = None) -> Scene:
    """The scene with its duration and step replaced (the command line's --duration and --dt),
    checked as the loader checks them."""
    if duration is None and dt is None:
        return scene
    sim = scene.simulation
    for name, v in (("duration", duration), ("dt", dt)):
        if v is not None and not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
            raise SceneError(f"simulation.{name}", f"must be a positive finite number, got {show(v)}")
    sim = dataclasses.replace(sim, duration=float(duration if duration is not None else sim.duration),
                              dt=float(dt if dt is not None else sim.dt))
    if sim.dt > sim.duration:
        raise SceneError("simulation.dt", f"{show(sim.dt)} s is longer than the duration {show(sim.duration)} s")
    forced_span(scene.vessel, sim)
    warnings = [w for w in scene.warnings if not w.startswith(("simulation.duration", "simulation.save_every"))]
    return dataclasses.replace(scene, simulation=sim, warnings=tuple(warnings + step_warnings(sim)))


def check_values(scene: Scene, values: dict) -> Scene:
    """The scene with concrete `values` for dotted keys (a run of a sweep, concrete `params`),
    checked as the loader checks a scene file: the values are written into the scene's TOML mapping
    (`scene.text`, with its current duration and step) at their keys (name or index form) and the
    mapping is parsed again (`parse_scene`). A value the loader refuses raises SceneError naming
    the given key (`vessel.mass: must be positive, got -4.1e+05`). Returns the parsed scene, whose
    warnings are the loader's for these values. A scene without text (built in Python) is returned
    as it is: there is nothing to parse again."""
    canon = check_param_keys(scene, values)
    if not scene.text:
        return scene
    mapping = copy.deepcopy(toml_mapping(scene.text))
    sim = mapping.setdefault("simulation", {})
    sim["duration"], sim["dt"] = float(scene.simulation.duration), float(scene.simulation.dt)
    given = list(values)
    for key, name in zip(given, canon):
        _set(mapping, _toml_path(scene, name), _plain(values[key]))
    try:
        return parse_scene(mapping, text=scene.text, path=scene.path)
    except SceneError as e:
        message = str(e)[len(e.key) + 2:] if e.key else str(e)
        for key, name in zip(given, canon):
            for form in (key, name, _index_form(scene, name)):
                if e.key == form or e.key.startswith((form + "[", form + ".")):  # the value or a part of it
                    raise SceneError(key + e.key[len(form):], message) from None
        shown = ", ".join(f"{k} = {show(_plain(values[k]))}" for k in given)
        raise SceneError(given[0] if len(given) == 1 else ", ".join(given),
                         f"with {shown} the scene is not valid: {e}") from None


@functools.lru_cache(maxsize=4)
def toml_mapping(text: str) -> dict:
    """The scene's TOML mapping, parsed once for the many runs of a batch (check_values copies it;
    not to be changed in place)."""
    return tomllib.loads(text)


def _plain(value):
    """A concrete value as TOML holds it: a float, or (nested) lists of floats."""
    return np.asarray(value, dtype=float).tolist()


def _toml_path(scene: Scene, key: str) -> list:
    """The path of a canonical key in the TOML mapping: `tanks.tank.fill_depth` -> ["tanks", 0, "fill_depth"]."""
    for group, items in (("tanks", file_tanks(scene)), ("structures", scene.structures), ("probes", scene.probes),
                         ("mooring", scene.mooring), ("connections", scene.connections),
                         ("bodies", scene.bodies)):
        for i, item in enumerate(items):
            head = f"{group}.{item.name}."
            if key.startswith(head):
                return [group, i] + key[len(head):].split(".")
    return key.split(".")


def _index_form(scene: Scene, key: str) -> str:
    path = _toml_path(scene, key)
    if len(path) > 1 and isinstance(path[1], int):
        return f"{path[0]}[{path[1]}]." + ".".join(path[2:])
    return key


def _set(mapping: dict, path: list, value) -> None:
    node = mapping
    for part in path[:-1]:
        node = node[part] if isinstance(part, int) else node.setdefault(part, {})
    node[path[-1]] = value
