"""Scene loader: a TOML file (SPEC.md section 1) to a validated, immutable `Scene`.

Every input error is raised as one `SceneError` whose message starts with the dotted key of the
offending value (`tanks[0].fill_depth: 4.5 m is above the tank height 4.0 m`); nothing is built
from a scene that fails. Physically doubtful but legal choices (GM <= 0, a displacement that does
not carry the mass) load, with a sentence in `Scene.warnings` that says what they mean.

Each table is read by `_read`, which takes a field spec `{key: (kind, check)}`: it rejects unknown
keys, missing required keys and wrong types, converts the values (ints are accepted for floats,
booleans are never numbers) and runs the per-value checks. Rules that involve several values
(dt <= duration, fill_depth <= height, probes inside their owner, unique names) follow per table.

No JAX here: loading a scene is plain Python (and NumPy for the inertia's eigenvalues).
"""
from __future__ import annotations

import datetime
import difflib
import math
import os
import re
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Optional

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from .scene_types import (EFFECTS, Effects, Environment, Forced, Fluid, Hydrostatics, Initial, Material, Probe, Reduction, Scene, SceneError,
                          Simulation, Structure, Tank, Vessel, Walls)

__all__ = ["ELEMENT_FORMS", "SCHEMES", "WALLS", "FACES", "MOMENTS", "PROBE_TOLERANCE",
           "load_scene", "parse_scene", "scene_values", "check_param_keys", "canonical_key", "describe"]

ELEMENT_FORMS = ("stabilized", "paper")          # [tanks.fluid] element: liquid element forms (liquid.py)
SCHEMES = ("newmark", "hht", "generalized-alpha")
LINEAR_SOLVERS = ("auto", "dense", "sparse")      # [simulation] linear_solver (sparse.py)
WALLS = ("rigid", "elastic")
FACES = ("x-", "x+", "y-", "y+", "z-", "z+")
MOMENTS = ("paper", "conservative")
FORCED_DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")   # [vessel.forced] dof
PROBE_TOLERANCE = 1e-9                           # m: how far outside its owner a probe may lie
MASS_BALANCE_TOLERANCE = 0.01                    # relative mismatch of weight and buoyancy that warns
HHT_ALPHA_MAX = 1.0 / 3.0


# --------------------------------------------------------------------------------------------
# Entry points


def load_scene(path_or_text: str | os.PathLike) -> Scene:
    """Load and validate a scene from a .toml path, or from TOML text (a string with a newline)."""
    if isinstance(path_or_text, str) and "\n" in path_or_text:
        text, path = path_or_text, ""
    else:
        path = os.fspath(path_or_text)
        try:
            text = Path(path).read_text(encoding="utf-8")
        except FileNotFoundError:
            raise SceneError("", f"{path}: no such file") from None
        except IsADirectoryError:
            raise SceneError("", f"{path}: is a directory, not a scene file") from None
        except UnicodeDecodeError as e:
            raise SceneError("", f"{path}: not valid TOML: not UTF-8 text ({e.reason} at byte {e.start})") from None
        except OSError as e:
            raise SceneError("", f"{path}: cannot be read ({e.strerror})") from None
    try:
        mapping = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:  # its message ends with "(at line L, column C)"
        raise SceneError("", f"{path or '<text>'}: not valid TOML: {e}{_toml_hint(text, str(e))}") from None
    return parse_scene(mapping, text=text, path=path)


def _toml_hint(text: str, message: str) -> str:
    """A hint for the one TOML error SPEC's own wording invites: `walls = "elastic"` plus `[tanks.walls]`."""
    m = re.search(r"at line (\d+)", message)
    lines = text.splitlines()
    if m and "overwrite" in message and 0 < int(m.group(1)) <= len(lines):
        line = lines[int(m.group(1)) - 1].replace(" ", "")
        if line.startswith("[tanks.walls") or line.startswith("walls."):
            return ('; a tank\'s walls are either walls = "rigid" or a [tanks.walls] table (which makes them '
                    'elastic): remove the line walls = "elastic"')
    return ""


def parse_scene(mapping: Mapping[str, Any], text: str = "", path: str = "") -> Scene:
    """Validate a parsed TOML mapping and build the `Scene` (`text`, `path` are stored in it)."""
    top = _read(mapping, "", {
        "title": ("str", None),
        "environment": ("table", None),
        "simulation": ("table", None),
        "vessel": ("table", None),
        "tanks": ("tables", None),
        "structures": ("tables", None),
        "probes": ("tables", None),
        "effects": ("table", None),
        "waves": ("table", None),
    }, required=("simulation", "vessel"))
    warnings: list[str] = []
    title = top.get("title", Path(path).stem if path else "")
    environment = _environment(mapping.get("environment", {}))
    simulation = _simulation(mapping["simulation"], warnings)
    vessel = _vessel(mapping["vessel"], environment, warnings)
    tanks = tuple(_tank(t, f"tanks[{i}]") for i, t in enumerate(mapping.get("tanks", [])))
    structures = tuple(_structure(s, f"structures[{i}]") for i, s in enumerate(mapping.get("structures", [])))
    probes = tuple(_probe(p, f"probes[{i}]") for i, p in enumerate(mapping.get("probes", [])))
    _unique_names(tanks, "tanks", "tank")
    _unique_names(structures, "structures", "structure")
    _attachments(structures)
    _unique_names(probes, "probes", "probe")
    for i, probe in enumerate(probes):
        _place_probe(probe, f"probes[{i}]", tanks, structures)
    _mass_balance(vessel, tanks, environment, warnings, structures)
    effects = Effects(**_read(mapping.get("effects", {}), "effects", {k: ("bool", None) for k in EFFECTS}))
    waves = None
    if "waves" in mapping:   # incident waves (scene_waves.py)
        from .scene_waves import read_waves
        waves = read_waves(mapping["waves"], warnings)
    scene = Scene(title=title, environment=environment, simulation=simulation, vessel=vessel, tanks=tanks,
                  structures=structures, probes=probes, effects=effects, text=text, path=path,
                  warnings=tuple(warnings), waves=waves)
    if waves is not None or vessel.hull is not None or vessel.hydrodynamics is not None:
        import dataclasses
        from .scene_waves import check_waves
        scene = check_waves(scene, path, warnings)
        scene = dataclasses.replace(scene, warnings=tuple(warnings))
    if simulation.energy_projection:
        _conservative(scene)
    return scene


def _conservative(scene: Scene) -> None:
    """`simulation.energy_projection` holds the total energy at its initial value: only right when
    nothing in the scene adds or removes energy and the equations are those of that energy."""
    v, e = scene.vessel, scene.effects
    why = []
    if v.forced is not None:
        why.append("[vessel.forced] prescribes motion (it does work)")
    if scene.waves is not None or v.hydrodynamics is not None or v.hull is not None:
        why.append("waves and hull hydrodynamics add and radiate energy")
    if scene.structures:
        why.append("flexible structures are not covered by the projection")
    if v.hydrostatics is not None and v.hydrostatics.moment != "conservative":
        why.append('vessel.hydrostatics.moment = "paper" is not the gradient of a potential')
    off = [k for k in ("coriolis", "centrifugal", "gravity_turning") if not getattr(e, k)]
    if off:
        why.append(f"effects {', '.join(off)} off: the equations are no longer those of the total energy")
    if why:
        raise SceneError("simulation.energy_projection",
                         "needs a conservative scene (the total energy must stay constant), but " + "; ".join(why))


# --------------------------------------------------------------------------------------------
# Values and checks used by the field specs

Check = Optional[Callable[[Any], Optional[str]]]


def _positive(v):
    return None if v > 0 else f"must be positive, got {_show(v)}"


def _non_negative(v):
    return None if v >= 0 else f"must be >= 0, got {_show(v)}"


def _at_least(n: int) -> Check:
    return lambda v: None if v >= n else f"must be >= {n}, got {_show(v)}"


def _one_of(options: tuple[str, ...]) -> Check:
    listed = " | ".join(f'"{o}"' for o in options)
    return lambda v: None if v in options else f"must be one of {listed}, got {_show(v)}"


def _counts(v):
    return None if all(n >= 1 for n in v) else f"each count must be >= 1, got {_show(v)}"


def _sizes(v):
    return None if all(x > 0 for x in v) else f"each component must be positive, got {_show(v)}"


def _name(v):
    if not v.strip():
        return "must be a non-empty string"
    bad = [c for c in ".[]/" if c in v]
    if bad:  # names are parts of dotted parameter keys and of result-file group paths
        return f"{_show(v)} may not contain {' or '.join(repr(c) for c in bad)}"
    return None


def _poisson(v):
    return None if -1.0 < v < 0.5 else f"must lie in (-1, 0.5), got {_show(v)}"


# --------------------------------------------------------------------------------------------
# Tables


def _environment(table) -> Environment:
    v = _read(table, "environment", {
        "gravity": ("float", _non_negative),
        "water_density": ("float", _positive),
    })
    return Environment(**v)


def _simulation(table, warnings: list[str]) -> Simulation:
    v = _read(table, "simulation", {
        "duration": ("float", _positive),
        "dt": ("float", _positive),
        "scheme": ("str", _one_of(SCHEMES)),
        "alpha": ("float", None),
        "rho_inf": ("float", None),
        "save_every": ("int", _at_least(1)),
        "tolerance": ("float", _positive),
        "max_iterations": ("int", _at_least(1)),
        "chunk": ("int", _non_negative),
        "substeps": ("int", _non_negative),
        "linear_solver": ("str", _one_of(LINEAR_SOLVERS)),
        "energy_projection": ("bool", None),
    }, required=("duration", "dt"))
    sim = Simulation(**v)
    if sim.dt > sim.duration:
        raise SceneError("simulation.dt", f"{_show(sim.dt)} s is longer than the duration {_show(sim.duration)} s")
    if sim.scheme == "newmark" and sim.alpha != 0.0:
        raise SceneError("simulation.alpha", (
            f'{_show(sim.alpha)} with scheme = "newmark": newmark is the trapezoidal rule (gamma = 1/2, '
            f"beta = 1/4), and with alpha != 0 those coefficients amplify the response instead of damping it; "
            f'use scheme = "hht" (gamma = 1/2 + alpha, beta = (1 + alpha)^2 / 4) or remove alpha'))
    if sim.energy_projection and sim.scheme != "newmark":
        raise SceneError("simulation.energy_projection", (
            f'needs scheme = "newmark" (the trapezoidal rule), got "{sim.scheme}": it holds the total energy at '
            f"its initial value, which contradicts the numerical damping of {sim.scheme}"))
    if not 0.0 <= sim.alpha <= HHT_ALPHA_MAX + 1e-12:
        raise SceneError("simulation.alpha", f"must lie in [0, 1/3], got {_show(sim.alpha)}")
    if not 0.0 <= sim.rho_inf <= 1.0:
        raise SceneError("simulation.rho_inf", f"must lie in [0, 1], got {_show(sim.rho_inf)}")
    if "rho_inf" in v and sim.scheme != "generalized-alpha":
        warnings.append(f'simulation.rho_inf = {_show(sim.rho_inf)} is ignored with scheme = "{sim.scheme}" '
                        f'(it only sets scheme = "generalized-alpha")')
    if sim.alpha != 0.0 and sim.scheme == "generalized-alpha":
        warnings.append(f'simulation.alpha = {_show(sim.alpha)} is ignored with scheme = "generalized-alpha" '
                        f"(its damping is set by rho_inf)")
    steps = sim.duration / sim.dt
    if abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
        warnings.append(f"simulation.duration = {_show(sim.duration)} s is not a whole number of steps of "
                        f"{_show(sim.dt)} s; the run takes {sim.n_steps} steps, to t = {sim.n_steps * sim.dt:.6g} s")
    return sim


def _vessel(table, environment: Environment, warnings: list[str]) -> Vessel:
    v = _read(table, "vessel", {
        "mass": ("float", _positive),
        "inertia": ("inertia", None),
        "hydrostatics": ("table", None),
        "initial": ("table", None),
        "forced": ("table", None),
        "hull": ("table", None),
        "hydrodynamics": ("table", None),
    }, required=("mass", "inertia"))
    inertia = v["inertia"]
    _inertia_warnings(inertia, warnings)
    hydrostatics = _hydrostatics(table["hydrostatics"], warnings) if "hydrostatics" in table else None
    hull = hydrodynamics = None
    if "hull" in table or "hydrodynamics" in table:   # hull and its hydrodynamics (scene_waves.py)
        from .scene_waves import hull_hydrostatics, read_hull, read_hydrodynamics
        hull = read_hull(table["hull"]) if "hull" in table else None
        if hull is not None:
            hydrostatics = hull_hydrostatics(hull, hydrostatics, warnings)
        hydrodynamics = read_hydrodynamics(table["hydrodynamics"], hull) if "hydrodynamics" in table else None
    if hydrostatics is None and environment.gravity > 0:
        warnings.append(f"vessel: no [vessel.hydrostatics] table, so nothing holds the vessel up: it falls "
                        f"freely under gravity {_show(environment.gravity)} m/s^2")
    initial = Initial(**_read(table.get("initial", {}), "vessel.initial", {
        "position": ("vec3", None),
        "velocity": ("vec3", None),
        "angular_velocity": ("vec3", None),
        "roll_pitch_yaw": ("vec3", None),
    }))
    forced = None
    if "forced" in table:
        f = _read(table["forced"], "vessel.forced", {
            "dof": ("str", _one_of(FORCED_DOFS)),
            "profile": ("str", _one_of(("harmonic", "spin-up"))),
            "amplitude": ("float", None),
            "frequency": ("float", _positive),
            "ramp": ("float", _non_negative),
            "rate": ("float", None),
            "duration": ("float", _positive),
        }, required=("dof",))
        profile = f.get("profile", "harmonic")
        need = ("amplitude", "frequency") if profile == "harmonic" else ("rate", "duration")
        for k in need:
            if k not in f:
                raise SceneError(f"vessel.forced.{k}", f"is required for the {profile} profile")
        other = ("rate", "duration") if profile == "harmonic" else ("amplitude", "frequency", "ramp")
        for k in other:
            if k in f:
                raise SceneError(f"vessel.forced.{k}", f"does not belong to the {profile} profile "
                                                       f"(it takes {', '.join(need)})")
        if profile == "spin-up" and f["dof"] not in ("roll", "pitch", "yaw"):
            raise SceneError("vessel.forced.dof", f"the spin-up profile turns a rotation (roll, pitch or yaw), "
                                                  f"not {f['dof']!r}")
        forced = Forced(**f)
    return Vessel(mass=v["mass"], inertia=inertia, hydrostatics=hydrostatics, initial=initial, forced=forced,
                  hull=hull, hydrodynamics=hydrodynamics)


def _hydrostatics(table, warnings: list[str]) -> Hydrostatics:
    where = "vessel.hydrostatics"
    h = Hydrostatics(**_read(table, where, {
        "waterplane_area": ("float", _positive),
        "displaced_volume": ("float", _positive),
        "gm_t": ("float", None),
        "gm_l": ("float", None),
        "moment": ("str", _one_of(MOMENTS)),
    }, required=("waterplane_area", "displaced_volume", "gm_t", "gm_l")))
    for key, value, motion in (("gm_t", h.gm_t, "roll"), ("gm_l", h.gm_l, "pitch")):
        if value <= 0:
            warnings.append(f"{where}.{key} = {_show(value)} m <= 0: the vessel is statically unstable in "
                            f"{motion}; it will capsize or loll")
    return h


def _inertia_warnings(inertia, warnings: list[str]) -> None:
    i1, i2, i3 = sorted(np.linalg.eigvalsh(np.asarray(inertia)))
    if i1 + i2 < i3 * (1 - 1e-9):
        warnings.append(f"vessel.inertia: the principal moments {i1:.6g}, {i2:.6g}, {i3:.6g} kg m^2 break the "
                        f"triangle inequality I1 + I2 >= I3 that every rigid body's inertia keeps")


def _material(table, where: str) -> Material:
    return Material(**_read(table, where, {
        "young": ("float", _positive),
        "poisson": ("float", _poisson),
        "density": ("float", _positive),
    }, required=("young", "poisson", "density")))


def _tank(table, where: str) -> Tank:
    v = _read(table, where, {
        "name": ("str", _name),
        "origin": ("vec3", None),
        "size": ("vec3", _sizes),
        "fill_depth": ("float", None),
        "mesh": ("mesh", _counts),
        "walls": ("str_or_table", None),
        "fluid": ("table", None),
        "reduction": ("table", None),
    }, required=("name", "origin", "size", "fill_depth", "mesh"))
    # SPEC writes `walls = "elastic"` and a `[tanks.walls]` table, but TOML cannot hold both under
    # one key: `walls` is either the string "rigid" or the table, which makes the walls elastic.
    raw_walls = table.get("walls", "rigid")
    if isinstance(raw_walls, dict):
        walls, wall_spec = "elastic", _walls(raw_walls, f"{where}.walls")
    else:
        walls, wall_spec = raw_walls, None
        msg = _one_of(WALLS)(walls)
        if msg:
            raise SceneError(f"{where}.walls", msg)
    if walls == "elastic" and wall_spec is None:
        raise SceneError(f"{where}.walls", 'elastic walls need a [tanks.walls] table (thickness, material, '
                                           'optional mesh) instead of walls = "elastic"')
    height = v["size"][2]
    depth = v["fill_depth"]
    if depth <= 0:
        raise SceneError(f"{where}.fill_depth", f"must be positive, got {_show(depth)}")
    if depth > height:
        raise SceneError(f"{where}.fill_depth", f"{_show(depth)} m is above the tank height {_show(height)} m")
    fluid = Fluid(**_read(table.get("fluid", {}), f"{where}.fluid", {
        "density": ("float", _positive),
        "sound_speed": ("float", _positive),
        "element": ("str", _one_of(ELEMENT_FORMS)),
    }))
    reduction = None
    if "reduction" in table:
        reduction = Reduction(**_read(table["reduction"], f"{where}.reduction", {
            "modes": ("int", _at_least(1)),
            "static_correction": ("bool", None),
        }, required=("modes",)))
    return Tank(name=v["name"], origin=v["origin"], size=v["size"], fill_depth=depth, mesh=v["mesh"],
                walls=walls, fluid=fluid, wall_spec=wall_spec, reduction=reduction)


def _walls(table, where: str) -> Walls:
    v = _read(table, where, {
        "thickness": ("float", _positive),
        "material": ("table", None),
        "mesh": ("mesh", _counts),
    }, required=("thickness", "material"))
    return Walls(thickness=v["thickness"], material=_material(table["material"], f"{where}.material"),
                 mesh=v.get("mesh"))


def _structure(table, where: str) -> Structure:
    v = _read(table, where, {
        "name": ("str", _name),
        "origin": ("vec3", None),
        "size": ("vec3", _sizes),
        "mesh": ("mesh", _counts),
        "attach": ("str", _one_of(FACES)),
        "attach_to": ("str", None),
        "frame": ("str", _one_of(("own", "vessel"))),
        "stiffening": ("str", _one_of(("none", "centrifugal"))),
        "material": ("table", None),
    }, required=("name", "origin", "size", "mesh", "attach", "material"))
    return Structure(material=_material(table["material"], f"{where}.material"), **v)


def _attachments(structures) -> None:
    """A structure tied to another (`attach_to`) needs its attachment face's nodes to coincide with
    nodes of the other's mesh (the interface frame's nodes are shared), and may not tie to itself."""
    from .structure import box_mesh, face_nodes
    by_name = {s.name: s for s in structures}
    for i, s in enumerate(structures):
        if s.attach_to is None:
            continue
        key = f"structures[{i}].attach_to"
        if s.frame == "vessel":
            raise SceneError(key, 'a structure in the vessel\'s frame (frame = "vessel") is held at its face on the '
                                  'vessel; attach_to needs frame = "own"')
        if s.attach_to in by_name and by_name[s.attach_to].frame == "vessel":
            raise SceneError(key, f"{s.attach_to!r} has frame = \"vessel\": attach to a structure with its own frame")
        if s.attach_to == s.name:
            raise SceneError(key, f"structure {s.name!r} cannot be attached to itself")
        if s.attach_to not in by_name:
            raise SceneError(key, f"names no structure ({', '.join(repr(n) for n in by_name if n != s.name) or 'none'}); "
                                  "leave it out to attach to the vessel")
        o = by_name[s.attach_to]
        mine, _ = box_mesh(s.size, s.mesh)
        mine = mine[face_nodes(mine, s.size, s.attach)] + np.asarray(s.origin)
        theirs, _ = box_mesh(o.size, o.mesh)
        theirs = theirs + np.asarray(o.origin)
        tol = 1e-6 * max(max(s.size), max(o.size))
        dist = np.min(np.linalg.norm(mine[:, None, :] - theirs[None, :, :], axis=2), axis=1)
        if dist.max() > tol:
            raise SceneError(key, f"the {s.attach} face of {s.name!r} does not lie on nodes of {o.name!r} "
                                  f"(a node is {dist.max():.3g} m from the nearest): the meshes must match there")


def _probe(table, where: str) -> Probe:
    v = _read(table, where, {
        "name": ("str", _name),
        "tank": ("str", None),
        "structure": ("str", None),
        "point": ("vec3", None),
    }, required=("name", "point"))
    if ("tank" in v) == ("structure" in v):
        which = "both a tank and a structure" if "tank" in v else "neither a tank nor a structure"
        raise SceneError(where, f"probe {v['name']!r} names {which}; set exactly one of tank = or structure =")
    return Probe(**v)


def _unique_names(items, where: str, what: str) -> None:
    seen: dict[str, int] = {}
    for i, item in enumerate(items):
        if item.name in seen:
            raise SceneError(f"{where}[{i}].name", f"two {what}s named {item.name!r} "
                                                   f"(also {where}[{seen[item.name]}].name)")
        seen[item.name] = i


def _place_probe(probe: Probe, where: str, tanks, structures) -> None:
    """The owner exists and the point lies in it (tank-local or structure-local coordinates)."""
    kind, owner_name, owners = (("tank", probe.tank, tanks) if probe.tank is not None
                                else ("structure", probe.structure, structures))
    owner = next((o for o in owners if o.name == owner_name), None)
    if owner is None:
        names = ", ".join(repr(o.name) for o in owners) or "none"
        raise SceneError(f"{where}.{kind}", f"no {kind} named {owner_name!r} ({kind}s: {names})")
    p, size = probe.point, owner.size
    if any(x < -PROBE_TOLERANCE or x > s + PROBE_TOLERANCE for x, s in zip(p, size)):
        raise SceneError(f"{where}.point", (
            f"{_show(list(p))} is outside {kind} {owner_name!r}: {kind}-local coordinates from its "
            f"{'inner corner' if kind == 'tank' else 'origin'} must lie in "
            f"0 <= x <= {_show(size[0])}, 0 <= y <= {_show(size[1])}, 0 <= z <= {_show(size[2])} m"))
    if kind == "tank":
        inside_walls = all(PROBE_TOLERANCE < x < s - PROBE_TOLERANCE for x, s in zip(p[:2], size[:2]))
        if inside_walls and owner.fill_depth + PROBE_TOLERANCE < p[2] < size[2] - PROBE_TOLERANCE:
            raise SceneError(f"{where}.point", (
                f"{_show(list(p))} is in the air above the liquid (fill_depth {_show(owner.fill_depth)} m) and "
                f"on no wall of tank {owner_name!r}: no material point is there to follow"))


def _mass_balance(vessel: Vessel, tanks, environment: Environment, warnings: list[str], structures=()) -> None:
    h = vessel.hydrostatics
    if h is None or environment.gravity == 0:
        return
    liquid = sum(t.liquid_mass for t in tanks)
    total = vessel.mass + liquid        # vessel.mass: the whole ship without its liquid (structures included)
    buoyant = environment.water_density * h.displaced_volume
    if abs(total - buoyant) > MASS_BALANCE_TOLERANCE * buoyant:
        imbalance = (total - buoyant) * environment.gravity
        warnings.append(
            f"vessel.hydrostatics.displaced_volume: the total mass {total:.6g} kg (vessel {vessel.mass:.6g} kg + "
            f"tank liquid {liquid:.6g} kg) differs from water_density * displaced_volume = {buoyant:.6g} kg by "
            f"{100 * (total - buoyant) / buoyant:+.2f} %; the hydrostatic restoring forces are taken about the "
            f"initial position as if it were the equilibrium; the static imbalance of {abs(imbalance):.4g} N "
            f"({'weight' if imbalance > 0 else 'buoyancy'} in excess) is ignored")


# --------------------------------------------------------------------------------------------
# The field reader


def _read(table, where: str, spec: dict[str, tuple[str, Check]], required: Iterable[str] = ()) -> dict:
    """Check a TOML table against `spec` and return `{key: converted value}` for the keys present.

    Kinds: float, int, str, vec3 (3 numbers), mesh (3 ints), inertia (3 diagonal values or 3x3),
    str_or_table (checked by the caller), table and tables (sub-tables: only their type is checked
    here, the caller reads them). `check(value)` returns an error message or None.
    """
    if not isinstance(table, dict):
        raise SceneError(where, f"must be a table, got {_toml_type(table)} {_show(table)}")
    for key in table:
        if key not in spec:
            raise SceneError(_join(where, key), f"unknown key (known: {', '.join(spec)})")
    for key in required:
        if key not in table:
            what = (f"the [{_join(where, key)}] table is required" if spec[key][0] == "table"
                    else "a required key is missing")
            raise SceneError(_join(where, key), what)
    out = {}
    for key, (kind, check) in spec.items():
        if key not in table:
            continue
        name = _join(where, key)
        value = _CONVERT[kind](name, table[key])
        if kind in ("table", "tables", "str_or_table"):
            continue
        if check is not None:
            msg = check(value)
            if msg:
                raise SceneError(name, msg)
        out[key] = value
    return out


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


def _float(name: str, x) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise SceneError(name, f"must be a number, got {_toml_type(x)} {_show(x)}")
    x = float(x)
    if not math.isfinite(x):
        raise SceneError(name, f"must be finite, got {_show(x)}")
    return x


def _int(name: str, x) -> int:
    if isinstance(x, bool) or not isinstance(x, int):
        raise SceneError(name, f"must be an integer, got {_toml_type(x)} {_show(x)}")
    return x


def _bool(name: str, x) -> bool:
    if not isinstance(x, bool):
        raise SceneError(name, f"must be true or false, got {_toml_type(x)} {_show(x)}")
    return x


def _str(name: str, x) -> str:
    if not isinstance(x, str):
        raise SceneError(name, f"must be a string, got {_toml_type(x)} {_show(x)}")
    return x


def _vec3(name: str, x) -> tuple[float, float, float]:
    if not (isinstance(x, list) and len(x) == 3 and all(_is_number(c) for c in x)):
        raise SceneError(name, f"must be a list of 3 numbers, got {_toml_type(x)} {_show(x)}")
    return tuple(_float(f"{name}[{i}]", c) for i, c in enumerate(x))  # type: ignore[return-value]


def _mesh(name: str, x) -> tuple[int, int, int]:
    if not (isinstance(x, list) and len(x) == 3 and all(isinstance(c, int) and not isinstance(c, bool) for c in x)):
        raise SceneError(name, f"must be a list of 3 integers, got {_toml_type(x)} {_show(x)}")
    return tuple(x)  # type: ignore[return-value]


def _inertia(name: str, x):
    """3 diagonal values or a 3x3 list; symmetric (to 1e-9 relative, then symmetrized) and positive definite."""
    if isinstance(x, list) and len(x) == 3 and all(_is_number(c) for c in x):
        d = _vec3(name, x)
        if not all(c > 0 for c in d):
            raise SceneError(name, f"the diagonal values must be positive (positive definite), got {_show(list(d))}")
        return tuple(tuple(d[i] if i == j else 0.0 for j in range(3)) for i in range(3))
    if not (isinstance(x, list) and len(x) == 3
            and all(isinstance(r, list) and len(r) == 3 and all(_is_number(c) for c in r) for r in x)):
        raise SceneError(name, f"must be 3 diagonal values or a 3x3 list of numbers, got {_toml_type(x)} {_show(x)}")
    m = np.array([_vec3(f"{name}[{i}]", r) for i, r in enumerate(x)])
    scale = np.abs(m).max()
    if np.abs(m - m.T).max() > 1e-9 * scale:
        i, j = np.unravel_index(np.argmax(np.abs(m - m.T)), m.shape)
        raise SceneError(name, f"not symmetric: [{i}][{j}] = {_show(float(m[i, j]))} but "
                               f"[{j}][{i}] = {_show(float(m[j, i]))}")
    m = 0.5 * (m + m.T)
    eig = np.linalg.eigvalsh(m)
    if eig.min() <= 0:
        raise SceneError(name, f"not positive definite: its eigenvalues are {', '.join(f'{e:.6g}' for e in eig)}")
    return tuple(tuple(float(c) for c in row) for row in m)


def _table(name: str, x):
    if not isinstance(x, dict):
        raise SceneError(name, f"must be a table, got {_toml_type(x)} {_show(x)}")
    return x


def _tables(name: str, x):
    if not (isinstance(x, list) and all(isinstance(t, dict) for t in x)):
        what = "a table" if isinstance(x, dict) else f"{_toml_type(x)} {_show(x)}"
        raise SceneError(name, f"must be an array of tables ([[{name}]]), got {what}")
    return x


def _str_or_table(name: str, x):
    if not isinstance(x, (str, dict)):
        raise SceneError(name, f'must be "rigid", "elastic" or a [{name.split("[")[0]}.walls] table, '
                               f"got {_toml_type(x)} {_show(x)}")
    return x


def _numbers(name: str, x):
    """A number or a rectangular nested list of numbers (the tables of [vessel.hydrodynamics]), as floats."""
    def conv(e, path):
        if isinstance(e, list):
            return [conv(c, f"{path}[{i}]") for i, c in enumerate(e)]
        return _float(path, e)
    if not (_is_number(x) or isinstance(x, list)):
        raise SceneError(name, f"must be a number or an array of numbers, got {_toml_type(x)} {_show(x)}")
    out = conv(x, name)
    if isinstance(out, list):
        try:
            np.asarray(out, dtype=float)
        except ValueError:
            raise SceneError(name, "must be a rectangular array (every row of the same length)") from None
    return out


_CONVERT = {"bool": _bool, "float": _float, "int": _int, "str": _str, "vec3": _vec3, "mesh": _mesh, "inertia": _inertia,
            "table": _table, "tables": _tables, "str_or_table": _str_or_table, "numbers": _numbers}


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _toml_type(x) -> str:
    if isinstance(x, bool):
        return "boolean"
    if isinstance(x, int):
        return "integer"
    if isinstance(x, float):
        return "float"
    if isinstance(x, str):
        return "string"
    if isinstance(x, list):
        return "array"
    if isinstance(x, dict):
        return "table"
    if isinstance(x, (datetime.date, datetime.time)):
        return "date/time"
    return type(x).__name__


def _show(x) -> str:
    """A value as it reads in TOML, shortened."""
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, str):
        return '"' + x.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(x, (list, tuple)):
        s = "[" + ", ".join(_show(c) for c in x) + "]"
    elif isinstance(x, dict):
        s = "{" + ", ".join(f"{k} = {_show(v)}" for k, v in x.items()) + "}"
    else:
        s = str(x)
    return s if len(s) <= 80 else s[:77] + "..."


# --------------------------------------------------------------------------------------------
# Values by dotted path (simulate(params=...), identify --fit)


def scene_values(scene: Scene) -> dict[str, Any]:
    """Every real-valued quantity of the scene by its dotted TOML path.

    Scalars are floats; vectors (`vessel.initial.velocity`, `tanks.<name>.origin`, ...) are tuples
    of 3 floats and `vessel.inertia` a 3x3 nested tuple. Tanks, structures and probes appear twice,
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
    if scene.waves is not None:   # the wave forces are linear in these (waves.py)
        v["waves.amplitude" if scene.waves.type == "regular" else "waves.hs"] = scene.waves.height

    def material(prefix: str, m: Material) -> dict[str, float]:
        return {f"{prefix}.young": m.young, f"{prefix}.poisson": m.poisson, f"{prefix}.density": m.density}

    for i, t in enumerate(scene.tanks):
        own = {"origin": t.origin, "size": t.size, "fill_depth": t.fill_depth,
               "fluid.density": t.fluid.density, "fluid.sound_speed": t.fluid.sound_speed}
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
    return v


def canonical_key(scene: Scene, key: str) -> str:
    """The name form of a dotted key: `tanks[0].fill_depth` -> `tanks.tank.fill_depth` (others unchanged)."""
    for group, items in (("tanks", scene.tanks), ("structures", scene.structures), ("probes", scene.probes)):
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


# --------------------------------------------------------------------------------------------
# A human summary for `jaxslosh check`


def describe(scene: Scene) -> str:
    """A few lines: title, vessel, tanks, structures, probes and steps (warnings are not included)."""
    ves, sim = scene.vessel, scene.simulation
    lines = [f"{scene.title or '(untitled)'}" + (f"  [{scene.path}]" if scene.path else "")]
    diag = ", ".join(f"{ves.inertia[i][i]:.4g}" for i in range(3))
    h = ves.hydrostatics
    hydro = (f"A_w {h.waterplane_area:g} m^2, V {h.displaced_volume:g} m^3, GM_T {h.gm_t:g} m, GM_L {h.gm_l:g} m"
             if h is not None else "no hydrostatics (free body)")
    lines.append(f"vessel: mass {ves.mass:.4g} kg, inertia diagonal [{diag}] kg m^2; {hydro}")
    for t in scene.tanks:
        nx, ny, nz = t.mesh
        walls = t.walls if t.wall_spec is None else f"elastic, {t.wall_spec.thickness:g} m thick"
        lines.append(f"tank {t.name!r}: {t.size[0]:g} x {t.size[1]:g} x {t.size[2]:g} m filled to "
                     f"{t.fill_depth:g} m, liquid {t.liquid_mass:.4g} kg ({t.liquid_volume:.4g} m^3), "
                     f"mesh {nx} x {ny} x {nz} = {nx * ny * nz} hexahedra, walls {walls}")
    for s in scene.structures:
        nx, ny, nz = s.mesh
        mass = s.material.density * s.size[0] * s.size[1] * s.size[2]
        lines.append(f"structure {s.name!r}: {s.size[0]:g} x {s.size[1]:g} x {s.size[2]:g} m, {mass:.4g} kg, "
                     f"mesh {nx} x {ny} x {nz}, attached at {s.attach}")
    if scene.probes:
        lines.append("probes: " + ", ".join(
            f"{p.name} ({'tank' if p.tank else 'structure'} {p.tank or p.structure!r} at "
            f"[{', '.join(f'{x:g}' for x in p.point)}])" for p in scene.probes))
    damping = {"newmark": ", energy projection" if sim.energy_projection else "", "hht": f", alpha {sim.alpha:g}", "generalized-alpha": f", rho_inf {sim.rho_inf:g}"}
    lines.append(f"simulation: {sim.n_steps} steps of {sim.dt:g} s to t = {sim.n_steps * sim.dt:g} s, "
                 f"scheme {sim.scheme}{damping[sim.scheme]}, saving every {sim.save_every} step(s)")
    return "\n".join(lines)
