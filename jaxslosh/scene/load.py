"""Scene loader: a TOML file (docs/reference/scene.md) to a validated, immutable `Scene`.

Every input error is raised as one `SceneError` whose message starts with the dotted key of the
offending value (`tanks[0].fill_depth: 4.5 m is above the tank height 4.0 m`); nothing is built
from a scene that fails. Physically doubtful but legal choices (GM <= 0, a displacement that does
not carry the mass) load, with a sentence in `Scene.warnings` that says what they mean.

The field reader is fields.py; rules that involve several values (dt <= duration, fill_depth <=
height, probes inside their owner, unique names) follow per table here. No JAX here: loading a
scene is plain Python (and NumPy for the inertia's eigenvalues).
"""
from __future__ import annotations

import dataclasses
import os
import re
from pathlib import Path
from typing import Any, Mapping

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from ..fem.mesh import box_mesh, face_nodes
from ..geometry import AXES, SHAPES
from .campaign import read_campaign
from .fields import (at_least, counts, flat_list, non_negative, one_of, poisson_ratio, positive, read, show, sizes,
                     valid_name)
from .bodies import (bodies_scene, multimodal_scene, read_bodies, read_connections, tank_carriers,
                     tank_groups)
from .mooring import read_mooring
from .placement import read_footprint
from .record import forced_span, read_forced
from .rules import conservative as _conservative, locking_elements as _locking_elements
from .hull import read_hydrostatics
from .shape import default_element, fill_and_mesh, read_multimodal_shape, read_shape
from .types import (EFFECTS, ELEMENT_FORMS, FACE_FORMS, FACES, Damping, Effects, Environment, Fluid,
                    Initial, Material, Probe, Reduction, Scene, SceneError, Simulation, Structure, Tank,
                    Vessel, Walls)
from ..solve.schemes import SCHEMES
from .waves import FileContext, check_waves, hull_hydrostatics, read_hull, read_hydrodynamics, read_waves

LINEAR_SOLVERS = ("auto", "dense", "sparse", "sparse-host")      # [simulation] linear_solver (sparse.py)
WALLS = ("rigid", "elastic")
TANK_MODELS = ("fem", "multimodal")
MULTIMODAL_FLOWS = ("2d", "3d")         # a multimodal box's waves along its length, or across its whole base
MULTIMODAL_EXPANSIONS = ("exact", "third-order")    # the integrals exact, or their third-order polynomial
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
    """A hint for the one TOML error a natural wording invites: `walls = "elastic"` plus `[tanks.walls]`."""
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
    top = read(mapping, "", {
        "title": ("str", None), "environment": ("table", None), "simulation": ("table", None),
        "vessel": ("table", None), "tanks": ("tables", None), "structures": ("tables", None),
        "probes": ("tables", None), "effects": ("table", None), "waves": ("table", None),
        "campaign": ("table", None), "mooring": ("tables", None), "bodies": ("tables", None),
        "connections": ("tables", None),
    }, required=("simulation", "vessel"))
    warnings: list[str] = []
    title = top.get("title", Path(path).stem if path else "")
    environment = _environment(mapping.get("environment", {}))
    simulation = _simulation(mapping["simulation"], warnings)
    raw_waves = mapping.get("waves")
    depth = raw_waves.get("depth") if isinstance(raw_waves, dict) else None
    files = FileContext(os.path.dirname(os.path.abspath(path)) if path else os.getcwd(), environment.water_density,
                        environment.gravity, depth if isinstance(depth, (int, float)) and depth > 0 else None)
    vessel = _vessel(mapping["vessel"], environment, warnings, files)
    forced_span(vessel, simulation)
    tanks = tuple(_tank(t, f"tanks[{i}]", files.base_dir) for i, t in enumerate(mapping.get("tanks", [])))
    structures = tuple(_structure(s, f"structures[{i}]") for i, s in enumerate(mapping.get("structures", [])))
    probes = tuple(_probe(p, f"probes[{i}]") for i, p in enumerate(mapping.get("probes", [])))
    _unique_names(tanks, "tanks", "tank")
    carriers = tank_carriers(mapping.get("tanks", []), vessel.name)      # "vessel" or a body's name, per tank
    multimodal_scene(tanks, carriers, warnings)
    for group in tank_groups(tanks, carriers).values():                    # tanks overlap within one body
        _overlapping_tanks(group, warnings)
    _locking_elements(tanks, warnings)
    _unique_names(structures, "structures", "structure")
    _attachments(structures)
    _beside_vessel_multimodal(tanks, carriers, structures)
    _unique_names(probes, "probes", "probe")
    for i, probe in enumerate(probes):
        _place_probe(probe, f"probes[{i}]", tanks, structures)
    bodies = read_bodies(mapping.get("bodies", []), vessel, environment, warnings, files, tanks, carriers)
    connections = read_connections(mapping.get("connections", []), vessel, bodies)
    bodies_scene(bodies, vessel, structures, mapping, warnings, files)
    tanks = tank_groups(tanks, carriers).get("vessel", ())      # the vessel's; a body's are in its Body
    mooring = read_mooring(mapping.get("mooring", []), environment.depth, vessel, warnings,
                           tuple(bodies))
    _mass_balance(vessel, tanks, environment, warnings, structures,     # the vessel's own lines
                  tuple(m for m in mooring if m.body in ("vessel", vessel.name)))
    effects = Effects(**read(mapping.get("effects", {}), "effects", {k: ("bool", None) for k in EFFECTS}))
    waves = None
    if "waves" in mapping:   # incident waves (waves.py)
        waves = read_waves(mapping["waves"], warnings)
    campaign = None
    if "campaign" in mapping:   # a campaign's limits and defaults (campaign.py)
        campaign = read_campaign(mapping["campaign"], probes, waves, simulation.dt, warnings, mooring,
                                 bodies, connections)
    scene = Scene(title=title, environment=environment, simulation=simulation, vessel=vessel, tanks=tanks,
                  structures=structures, probes=probes, effects=effects, text=text, path=path,
                  warnings=tuple(warnings), waves=waves, campaign=campaign, mooring=mooring, bodies=bodies,
                  connections=connections)
    if waves is not None or vessel.hull is not None or vessel.hydrodynamics is not None:
        scene = check_waves(scene, path, warnings)
        scene = dataclasses.replace(scene, warnings=tuple(warnings))
    if simulation.energy_projection:
        _conservative(scene)
    return scene


# --------------------------------------------------------------------------------------------
# Tables
def _environment(table) -> Environment:
    v = read(table, "environment", {
        "gravity": ("float", non_negative), "water_density": ("float", positive), "depth": ("float", positive),
    })
    return Environment(**v)


def _simulation(table, warnings: list[str]) -> Simulation:
    v = read(table, "simulation", {
        "duration": ("float", positive), "dt": ("float", positive), "scheme": ("str", one_of(SCHEMES)),
        "alpha": ("float", None), "rho_inf": ("float", None), "save_every": ("int", at_least(1)),
        "tolerance": ("float", positive), "max_iterations": ("int", at_least(1)), "chunk": ("int", non_negative),
        "substeps": ("int", non_negative), "linear_solver": ("str", one_of(LINEAR_SOLVERS)),
        "energy_projection": ("bool", None),
    }, required=("duration", "dt"))
    sim = Simulation(**v)
    if sim.dt > sim.duration:
        raise SceneError("simulation.dt", f"{show(sim.dt)} s is longer than the duration {show(sim.duration)} s")
    if sim.scheme == "newmark" and sim.alpha != 0.0:
        raise SceneError("simulation.alpha", (
            f'{show(sim.alpha)} with scheme = "newmark": newmark is the trapezoidal rule (gamma = 1/2, '
            f"beta = 1/4), and with alpha != 0 those coefficients amplify the response instead of damping it; "
            f'use scheme = "hht" (gamma = 1/2 + alpha, beta = (1 + alpha)^2 / 4) or remove alpha'))
    if sim.energy_projection and sim.scheme != "newmark":
        raise SceneError("simulation.energy_projection", (
            f'needs scheme = "newmark" (the trapezoidal rule), got "{sim.scheme}": it holds the total energy at '
            f"its initial value, which contradicts the numerical damping of {sim.scheme}"))
    if not 0.0 <= sim.alpha <= HHT_ALPHA_MAX + 1e-12:
        raise SceneError("simulation.alpha", f"must lie in [0, 1/3], got {show(sim.alpha)}")
    if not 0.0 <= sim.rho_inf <= 1.0:
        raise SceneError("simulation.rho_inf", f"must lie in [0, 1], got {show(sim.rho_inf)}")
    if "rho_inf" in v and sim.scheme != "generalized-alpha":
        warnings.append(f'simulation.rho_inf = {show(sim.rho_inf)} is ignored with scheme = "{sim.scheme}" '
                        f'(it only sets scheme = "generalized-alpha")')
    if sim.alpha != 0.0 and sim.scheme == "generalized-alpha":
        warnings.append(f'simulation.alpha = {show(sim.alpha)} is ignored with scheme = "generalized-alpha" '
                        f"(its damping is set by rho_inf)")
    warnings += step_warnings(sim)
    return sim


def step_warnings(sim: Simulation) -> list[str]:
    """The steps and saved frames a duration, step and save_every give: SceneError when nothing
    would be saved; warnings for a duration that is not a whole number of steps or of saved frames."""
    out = []
    steps = sim.duration / sim.dt
    if abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
        out.append(f"simulation.duration = {show(sim.duration)} s is not a whole number of steps of "
                   f"{show(sim.dt)} s; the run takes {sim.n_steps} steps, to t = {sim.n_steps * sim.dt:.6g} s")
    if sim.save_every > max(sim.n_steps, 1):
        raise SceneError("simulation.save_every", f"{sim.save_every} is more than the run's {sim.n_steps} steps: "
                                                  f"nothing after t = 0 would be saved")
    kept = (sim.n_steps // sim.save_every) * sim.save_every
    if kept != sim.n_steps:
        out.append(f"simulation.save_every = {sim.save_every} does not divide the run's {sim.n_steps} steps: the "
                   f"run stops at the last saved frame, step {kept} (t = {kept * sim.dt:.6g} s)")
    return out


def _overlapping_tanks(tanks, warnings: list[str]) -> None:
    """Two tanks' boxes that share volume are a scene error the model cannot see (each liquid is
    meshed on its own): warn."""
    for i, a in enumerate(tanks):
        for j in range(i + 1, len(tanks)):
            b = tanks[j]
            lo = [max(a.origin[k], b.origin[k]) for k in range(3)]
            hi = [min(a.origin[k] + a.size[k], b.origin[k] + b.size[k]) for k in range(3)]
            if all(h - l > 1e-9 * max(max(a.size), max(b.size)) for l, h in zip(lo, hi)):
                warnings.append(f"tanks[{j}] ({b.name!r}) overlaps tanks[{i}] ({a.name!r}): their liquids are "
                                f"simulated apart, as if each had the shared space to itself")


def _vessel(table, environment: Environment, warnings: list[str], files=None) -> Vessel:
    v = read(table, "vessel", {
        "mass": ("float", positive), "inertia": ("inertia", None), "hydrostatics": ("table", None),
        "initial": ("table", None), "forced": ("table", None), "hull": ("table", None), "footprint": ("any", None),
        "hydrodynamics": ("table", None), "name": ("str", valid_name), "cog_height": ("float", None),
    }, required=("mass", "inertia"))
    inertia = v["inertia"]
    _inertia_warnings(inertia, warnings)
    hull = read_hull(table["hull"], files.base_dir if files is not None else "") if "hull" in table else None
    hydrostatics = read_hydrostatics(table["hydrostatics"], warnings, hull, environment) if "hydrostatics" in table else None
    hydrodynamics = None
    if "hull" in table or "hydrodynamics" in table:   # hull and its hydrodynamics (waves.py)
        if hull is not None and not (hydrostatics is not None and hydrostatics.nonlinear):
            hydrostatics = hull_hydrostatics(hull, hydrostatics, warnings)
        named = files._replace(body=v.get("name", "vessel")) if files is not None else None
        hydrodynamics = read_hydrodynamics(table["hydrodynamics"], hull, named, warnings, hydrostatics) \
            if "hydrodynamics" in table else None
    # a prescribed motion ([vessel.forced]) holds all six dofs, so then nothing falls
    if hydrostatics is None and environment.gravity > 0 and "forced" not in table:
        warnings.append(f"vessel: no [vessel.hydrostatics] table, so nothing holds the vessel up: it falls "
                        f"freely under gravity {show(environment.gravity)} m/s^2")
    initial = Initial(**read(table.get("initial", {}), "vessel.initial", {
        "position": ("vec3", None), "velocity": ("vec3", None), "angular_velocity": ("vec3", None),
        "roll_pitch_yaw": ("vec3", None),
    }))
    forced = read_forced(table["forced"], files.base_dir if files is not None else os.getcwd()) \
        if "forced" in table else None
    # the COG's height above the still-water level (it places mooring fairleads): given, or a box
    # hull's kg - draft, else 0
    cog = v.get("cog_height", hull.default_cog_height() if hull is not None else 0.0)
    return Vessel(mass=v["mass"], inertia=inertia, hydrostatics=hydrostatics, initial=initial, forced=forced, hull=hull,
                  hydrodynamics=hydrodynamics, name=v.get("name", "vessel"), cog_height=cog, footprint=read_footprint(table, "vessel"))


def _inertia_warnings(inertia, warnings: list[str]) -> None:
    i1, i2, i3 = sorted(np.linalg.eigvalsh(np.asarray(inertia)))
    if i1 + i2 < i3 * (1 - 1e-9):
        warnings.append(f"vessel.inertia: the principal moments {i1:.6g}, {i2:.6g}, {i3:.6g} kg m^2 break the "
                        f"triangle inequality I1 + I2 >= I3 that every rigid body's inertia keeps")


def _material(table, where: str) -> Material:
    return Material(**read(table, where, {
        "young": ("float", positive), "poisson": ("float", poisson_ratio), "density": ("float", positive),
    }, required=("young", "poisson", "density")))


def _tank(table, where: str, base_dir: str = "") -> Tank:
    v = read(table, where, {
        "name": ("str", valid_name), "origin": ("vec3", None), "size": ("vec3", sizes), "body": ("str", None),
        "fill_depth": ("float", None), "mesh": ("mesh", counts), "walls": ("str_or_table", None),
        "fluid": ("table", None), "reduction": ("table", None), "damping": ("table", None),
        "shape": ("str", one_of(SHAPES)), "chamfers": ("any", None), "axis": ("str", one_of(AXES)),
        "file": ("str", None), "baffles": ("tables", None), "model": ("str", one_of(TANK_MODELS)),
        "modes": ("int", at_least(1)), "flow": ("str", one_of(MULTIMODAL_FLOWS)),
        "expansion": ("str", one_of(MULTIMODAL_EXPANSIONS)),
    }, required=("name", "origin", "size"))
    model = v.get("model", "fem")
    if model == "multimodal":
        _multimodal_tank(table, where)
        v.setdefault("mesh", (2, 2, 1))          # the multimodal tank has no mesh
    else:
        for key in ("modes", "flow", "expansion"):
            if key in table:
                raise SceneError(f"{where}.{key}", 'is the multimodal tank\'s: it needs model = "multimodal"')
    fill_and_mesh(table, v, where, base_dir)
    # one would write `walls = "elastic"` and a `[tanks.walls]` table, but TOML cannot hold both under
    # one key: `walls` is either the string "rigid" or the table, which makes the walls elastic.
    raw_walls = table.get("walls", "rigid")
    if isinstance(raw_walls, dict):
        walls, wall_spec = "elastic", _walls(raw_walls, f"{where}.walls")
    else:
        walls, wall_spec = raw_walls, None
        msg = one_of(WALLS)(walls)
        if msg:
            raise SceneError(f"{where}.walls", msg)
    if walls == "elastic" and wall_spec is None:
        raise SceneError(f"{where}.walls", 'elastic walls need a [tanks.walls] table (thickness, material, '
                                           'optional mesh) instead of walls = "elastic"')
    height = v["size"][2]
    depth = v["fill_depth"]
    if depth <= 0:
        raise SceneError(f"{where}.fill_depth", f"must be positive, got {show(depth)}")
    if depth > height:
        raise SceneError(f"{where}.fill_depth", f"{show(depth)} m is above the tank height {show(height)} m")
    fluid = Fluid(**read(table.get("fluid", {}), f"{where}.fluid", {
        "density": ("float", positive), "sound_speed": ("float", positive),
        "element": ("str", one_of(ELEMENT_FORMS + FACE_FORMS)),
    }))
    reduction = None
    if "reduction" in table:
        reduction = Reduction(**read(table["reduction"], f"{where}.reduction", {
            "modes": ("int", at_least(1)), "static_correction": ("bool", None),
        }, required=("modes",)))
    damping = _damping(table["damping"], f"{where}.damping") if "damping" in table else None
    shape, geo = read_shape(table, v, where, base_dir, elastic=wall_spec is not None)
    if "element" not in table.get("fluid", {}):
        element, why = default_element(geo, depth, v["mesh"], reduction is not None)
        fluid = dataclasses.replace(fluid, element=element, element_default=why)
    return Tank(name=v["name"], origin=v["origin"], size=v["size"], fill_depth=depth, mesh=v["mesh"],
                walls=walls, fluid=fluid, wall_spec=wall_spec, reduction=reduction, damping=damping,
                model=model, modes=v.get("modes", 6), expansion=v.get("expansion", "exact"),
                flow=v.get("flow", geo.modal_flow), geometry=geo, **shape)


def _multimodal_tank(table, where: str) -> None:
    """A multimodal tank is a plain box (liquid/multimodal/term.py, or multimodal3d.py with flow = "3d") or
    an upright circular cylinder (multimodal3d.py) with rigid walls."""
    read_multimodal_shape(table, where)
    if "shape" in table and not SHAPES[table["shape"]].modal:
        allowed = " or ".join(f'shape = "{name}"' + {"box": " (the default)", "cylinder": ' with axis = "z"'}.get(name, "")
                              for name, cls in SHAPES.items() if cls.modal)
        raise SceneError(f"{where}.shape", f'a model = "multimodal" tank is a box or an upright cylinder: {allowed}, '
                                           f'not shape = "{table["shape"]}"')
    for key, why in (("baffles", "a tank without baffles"),
                     ("walls", "rigid walls"), ("reduction", "its own modes"), ("file", "a box or a cylinder")):
        if key in table and not (key == "walls" and table[key] == "rigid"):
            raise SceneError(f"{where}.{key}", f'a model = "multimodal" tank is {why}: leave {key} out')
    visc = table.get("damping", {}).get("viscosity", 0.0) if isinstance(table.get("damping"), dict) else 0.0
    if visc:
        raise SceneError(f"{where}.damping.viscosity", 'the boundary-layer damping needs the finite-element modes: '
                                                      'give the multimodal tank damping ratios')


def _damping(table, where: str) -> Damping:
    """`[tanks.damping]`: `ratio` a number in [0, 1) or a non-empty list of them (the lowest sloshing
    modes'; whether the mesh has that many modes is checked when the liquid is built), `viscosity` >= 0."""
    v = read(table, where, {"ratio": ("numbers", _ratio), "viscosity": ("float", non_negative)})
    ratio = v.get("ratio", 0.0)
    return Damping(ratio=tuple(ratio) if isinstance(ratio, list) else ratio, viscosity=v.get("viscosity", 0.0))


def _ratio(v):
    values, msg = flat_list(v, "a number")
    if msg:
        return msg
    bad = [x for x in values if not 0.0 <= x < 1.0]
    if bad:
        return f"a damping ratio must be in [0, 1) (1: critical damping, no oscillation left), got {show(bad[0])}"
    return None


def _walls(table, where: str) -> Walls:
    v = read(table, where, {
        "thickness": ("float", positive), "material": ("table", None), "mesh": ("mesh", counts),
    }, required=("thickness", "material"))
    return Walls(thickness=v["thickness"], material=_material(table["material"], f"{where}.material"),
                 mesh=v.get("mesh"))


def _structure(table, where: str) -> Structure:
    v = read(table, where, {
        "name": ("str", valid_name), "origin": ("vec3", None), "size": ("vec3", sizes), "mesh": ("mesh", counts),
        "attach": ("str", one_of(FACES)), "attach_to": ("str", None), "frame": ("str", one_of(("own", "vessel"))),
        "stiffening": ("str", one_of(("none", "centrifugal"))), "material": ("table", None),
    }, required=("name", "origin", "size", "mesh", "attach", "material"))
    return Structure(material=_material(table["material"], f"{where}.material"), **v)


def _beside_vessel_multimodal(tanks, carriers, structures) -> None:
    """The vessel's multimodal liquid is a block of its modal coordinates alone (liquid/multimodal):
    a structure in the vessel's frame has no place in it (it would be left out of the run)."""
    i = next((i for i, s in enumerate(structures) if s.frame == "vessel"), None)
    if i is not None and any(t.form.multimodal for t, c in zip(tanks, carriers) if c == "vessel"):
        raise SceneError(f"structures[{i}].frame", 'a structure in the vessel\'s frame (frame = "vessel") is not '
                                                   'available beside the vessel\'s multimodal tanks: give it frame = '
                                                   '"own", or the tanks model = "fem"')


def _attachments(structures) -> None:
    """A structure tied to another (`attach_to`) needs its attachment face's nodes to coincide with
    nodes of the other's mesh (the interface frame's nodes are shared), and may not tie to itself."""
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
    v = read(table, where, {
        "name": ("str", valid_name), "tank": ("str", None), "structure": ("str", None), "point": ("vec3", None),
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
            f"{show(list(p))} is outside {kind} {owner_name!r}: {kind}-local coordinates from its "
            f"{'inner corner' if kind == 'tank' else 'origin'} must lie in "
            f"0 <= x <= {show(size[0])}, 0 <= y <= {show(size[1])}, 0 <= z <= {show(size[2])} m"))
    if kind == "tank":
        inside_walls = all(PROBE_TOLERANCE < x < s - PROBE_TOLERANCE for x, s in zip(p[:2], size[:2]))
        if inside_walls and owner.fill_depth + PROBE_TOLERANCE < p[2] < size[2] - PROBE_TOLERANCE:
            raise SceneError(f"{where}.point", (
                f"{show(list(p))} is in the air above the liquid (fill_depth {show(owner.fill_depth)} m) and "
                f"on no wall of tank {owner_name!r}: no material point is there to follow"))


def _mass_balance(vessel: Vessel, tanks, environment: Environment, warnings: list[str], structures=(),
                  mooring=()) -> None:
    h = vessel.hydrostatics
    if h is None or environment.gravity == 0:
        return
    liquid = sum(t.liquid_mass for t in tanks)
    total = vessel.mass + liquid        # vessel.mass: the whole ship without its liquid (structures included)
    buoyant = environment.water_density * h.displaced_volume
    if abs(total - buoyant) > MASS_BALANCE_TOLERANCE * buoyant and h.nonlinear:
        # the restoring is the hull's own: the vessel is simply released out of equilibrium
        warnings.append(
            f"vessel.mass: the total mass {total:.6g} kg (vessel {vessel.mass:.6g} kg + tank liquid {liquid:.6g} kg) "
            f"differs from the water the hull displaces at rest, {buoyant:.6g} kg, by "
            f"{100 * (total - buoyant) / buoyant:+.2f} %: the vessel starts out of equilibrium and "
            f"{'sinks' if total > buoyant else 'rises'} to its own draft (heaving about it) from t = 0")
    elif mooring and 0.0 <= (buoyant - total) * environment.gravity <= sum(max(m.weight, 0.0) * m.length
                                                                          for m in mooring) * (1 + MASS_BALANCE_TOLERANCE):
        return      # the buoyancy in excess may carry the lines' weight (docs/guide/moorings.md)
    elif abs(total - buoyant) > MASS_BALANCE_TOLERANCE * buoyant:
        imbalance = (total - buoyant) * environment.gravity
        warnings.append(
            f"vessel.hydrostatics.displaced_volume: the total mass {total:.6g} kg (vessel {vessel.mass:.6g} kg + "
            f"tank liquid {liquid:.6g} kg) differs from water_density * displaced_volume = {buoyant:.6g} kg by "
            f"{100 * (total - buoyant) / buoyant:+.2f} %; the hydrostatic restoring forces are taken about the "
            f"initial position as if it were the equilibrium; the static imbalance of {abs(imbalance):.4g} N "
            f"({'weight' if imbalance > 0 else 'buoyancy'} in excess) is ignored")
