"""The `[[bodies]]` and `[[connections]]` tables: rigid floating bodies beside the vessel and the
hawsers, fenders and springs between them (docs/guide/bodies-and-connections.md).

Read and checked here, with what the rest of the scene says about them (the vessel's name, its
waterplane, the tanks' and lines' `body`). No JAX: the terms are built later (physics/bodies.py).
What a body cannot have yet is refused by its key, never silently dropped.
"""
from __future__ import annotations

import dataclasses
import math
import os
from typing import Optional

import numpy as np

from .fields import non_negative, one_of, positive, read, show, valid_name
from .hull import read_hydrostatics
from ..hydro.database import DatabaseError
from ..hydro.multibody import file_bodies, netcdf_centres, read_multibody
from .placement import hull_extent, read_footprint, refuse_overlaps
from .types import Body, Connection, Hydrostatics, Initial, SceneError
from .waves import FileContext, read_hull, read_hydrodynamics

KINDS = ("hawser", "fender", "spring")
#: the vessel's keys a body cannot have yet, refused by name (not as unknown keys)
NOT_YET = {"forced": "prescribed motions"}
#: names a body cannot take: the words that name the vessel and an inertial point in `bodies = [...]`
RESERVED = ("vessel", "fixed")
#: how far a connection point may lie outside its body's hull, relative to the hull's size (round-off:
#: a point on the side, as a fender's face, is inside)
EDGE = 1e-6
#: below this fill depth over length the multimodal method's ordering fails (shallow water, bores)
MULTIMODAL_SHALLOW = 0.1
#: how far (m) a body of a multibody file may be from its place in the scene (a file's own rounding)
PLACE = 1e-3


def tank_carriers(tables, vessel_name: str) -> tuple:
    """The body each `[[tanks]]` table names in `body`, in order: "vessel" (the default, or the
    vessel's name) or a body's name."""
    named = tuple((t.get("body", "vessel") if isinstance(t, dict) else "vessel") for t in tables)
    return tuple("vessel" if n == vessel_name else n for n in named)


def tank_groups(tanks, carriers) -> dict:
    """{carrier: its tanks} (tank_carriers' names), in the scene's order."""
    out: dict = {}
    for t, c in zip(tanks, carriers):
        out[c] = out.get(c, ()) + (t,)
    return out


def multimodal_scene(tanks, carriers, warnings: list[str]) -> None:
    """The tanks one body carries (the vessel, or one of [[bodies]]: `carriers`, tank_carriers') all
    multimodal or none (its stacked liquid is of one kind); the multimodal method's validity."""
    first: dict = {}
    for i, (t, c) in enumerate(zip(tanks, carriers)):
        j = first.setdefault(c, i)
        if t.model != tanks[j].model:
            on = "" if c == "vessel" else f" on the body {c!r}"
            raise SceneError(f"tanks[{i}].model", f'is "{t.model}" but tanks[{j}]{on} is "{tanks[j].model}": all '
                                                  f"tanks of one body take the same model")
        ratio = t.fill_depth / t.size[0]
        if t.model == "multimodal" and ratio < MULTIMODAL_SHALLOW:
            warnings.append(f"tanks[{i}] ({t.name!r}): fill depth / length = {ratio:.3g} is below "
                            f"{MULTIMODAL_SHALLOW}: shallow-water sloshing (bores, hydraulic jumps), outside the "
                            "multimodal method's validity")


def read_bodies(tables, vessel, environment, warnings: list[str], files=None, tanks=(), carriers=()) -> tuple[Body, ...]:
    """The `[[bodies]]` of a scene (`vessel`: the scene's types.Vessel; `files`: waves.FileContext,
    where a body's hydrodynamic `file` is read from), each with the `tanks` whose `carriers` name it."""
    out = []
    for i, table in enumerate(tables):
        where = f"bodies[{i}]"
        if isinstance(table, dict):
            for key, what in NOT_YET.items():
                if key in table and what:
                    raise SceneError(f"{where}.{key}", f"{what} are not available yet for [[bodies]] "
                                                       "(docs/guide/bodies-and-connections.md, what is not yet)")
        v = read(table, where, {
            "name": ("str", valid_name), "position": ("any", None), "heading": ("float", None),
            "cog_height": ("float", None), "mass": ("float", positive), "inertia": ("inertia", None),
            "hydrostatics": ("table", None), "hydrodynamics": ("table", None), "initial": ("table", None),
            "footprint": ("any", None), "hull": ("table", None),
        }, required=("name", "mass", "inertia", "hydrostatics"))
        name = v["name"]
        if name in RESERVED or name == vessel.name:
            raise SceneError(f"{where}.name", f"{show(name)} names the vessel or a fixed point in [[connections]]; "
                                              "give the body another name")
        if name in [b.name for b in out]:
            raise SceneError(f"{where}.name", f"{show(name)} is the name of another body")
        pos = table.get("position", [0.0, 0.0])
        if not (isinstance(pos, list) and len(pos) == 2 and all(isinstance(c, (int, float)) and not isinstance(c, bool)
                                                                  and math.isfinite(c) for c in pos)):
            raise SceneError(f"{where}.position", f"must be a list of 2 numbers [x, y] (m, horizontally from the "
                                                  f"vessel's COG at rest), got {show(pos)}")
        base = (files or FileContext()).base_dir
        hull = read_hull(table["hull"], base, f"{where}.hull") if "hull" in table else None
        hs = _hydrostatics(table["hydrostatics"], where, warnings, hull, environment)
        damping = hydro = None
        if "hydrodynamics" in table:      # the vessel's keys and reader (a file's block of this body)
            ctx = (files or FileContext())._replace(body=name)
            hydro = read_hydrodynamics(table["hydrodynamics"], None, ctx, warnings, hs, where=f"{where}.hydrodynamics")
            hydro = dataclasses.replace(hydro, base_dir=ctx.base_dir)
            if hydro.viscous_damping is not None:
                damping = _matrix6(hydro.viscous_damping, f"{where}.hydrodynamics.viscous_damping")
        initial = Initial(**read(table.get("initial", {}), f"{where}.initial", {
            "position": ("vec3", None), "velocity": ("vec3", None), "angular_velocity": ("vec3", None),
            "roll_pitch_yaw": ("vec3", None),
        }))
        body = Body(name=name, mass=v["mass"], inertia=v["inertia"], hydrostatics=hs,
                    position=(float(pos[0]), float(pos[1])), heading=v.get("heading", 0.0),
                    cog_height=v.get("cog_height", hull.default_cog_height() if hull is not None else 0.0),
                    initial=initial, viscous_damping=damping, hydrodynamics=hydro,
                    footprint=read_footprint(table, where), hull=hull,
                    tanks=tuple(t for t, c in zip(tanks, carriers) if c == name))
        buoyant = environment.water_density * hs.displaced_volume
        # as the vessel's: its mass is the body's without the liquid of its tanks
        total = body.mass + sum(t.liquid_mass for t in body.tanks)
        liquid = f" (body {body.mass:.6g} kg + tank liquid {total - body.mass:.6g} kg)" if body.tanks else ""
        if environment.gravity > 0 and abs(total - buoyant) > 0.01 * buoyant and hs.nonlinear:
            # the restoring is the hull's own: the body is released out of equilibrium, as the vessel is
            warnings.append(f"bodies[{i}].mass: the body's mass {total:.6g} kg{liquid} differs from the water its hull "
                            f"displaces at rest, {buoyant:.6g} kg, by {100 * (total - buoyant) / buoyant:+.2f} %: it "
                            f"starts out of equilibrium and {'sinks' if total > buoyant else 'rises'} to its own "
                            "draft (heaving about it) from t = 0")
        elif environment.gravity > 0 and abs(total - buoyant) > 0.01 * buoyant:
            warnings.append(f"{where}.hydrostatics.displaced_volume: the body's mass {total:.6g} kg{liquid} differs from "
                            f"water_density * displaced_volume = {buoyant:.6g} kg by "
                            f"{100 * (total - buoyant) / buoyant:+.2f} %; its hydrostatic restoring is taken "
                            "about its rest pose as if it were the equilibrium (the imbalance is ignored)")
        out.append(body)
    refuse_overlaps(out, vessel)
    return tuple(out)


def _hydrostatics(table, owner: str, warnings: list[str], hull=None, environment=None) -> Hydrostatics:
    """`[bodies.hydrostatics]` of the body `owner` ("bodies[i]"): with a `[bodies.hull]`, the
    vessel's reader (its nonlinear model, the box's closed forms for what the table leaves out);
    without one, the four linear values."""
    where = f"{owner}.hydrostatics"
    if hull is not None:
        if not hull.closed_form and not (isinstance(table, dict) and table.get("model") == "nonlinear"):
            raise SceneError(f"{owner}.hull.type", 'a "mesh" hull on a body is read by the nonlinear hydrostatics: '
                                                   'add [bodies.hydrostatics] model = "nonlinear" (or use a box)')
        return read_hydrostatics(table, warnings, hull, environment, owner)
    if isinstance(table, dict) and table.get("model") == "nonlinear":
        raise SceneError(f"{where}.model", '"nonlinear" hydrostatics need the body\'s [bodies.hull] table: a box '
                                           'with its depth, or a closed mesh (type = "mesh")')
    v = read(table, where, {
        "waterplane_area": ("float", positive), "displaced_volume": ("float", positive), "gm_t": ("float", None),
        "gm_l": ("float", None), "moment": ("str", one_of(("conservative", "paper"))),
        "model": ("str", one_of(("linear",))),
    }, required=("waterplane_area", "displaced_volume", "gm_t", "gm_l"))
    h = Hydrostatics(**v)
    for key, value, motion in (("gm_t", h.gm_t, "roll"), ("gm_l", h.gm_l, "pitch")):
        if value <= 0:
            warnings.append(f"{where}.{key} = {show(value)} m <= 0: the body is statically unstable in {motion}; "
                            "it will capsize or loll")
    return h


def _matrix6(x, where: str):
    a = np.asarray(x, dtype=float)
    if a.shape not in ((6,), (6, 6)):
        raise SceneError(where, f"must be 6 values or a 6 x 6 array, got shape {a.shape}")
    a = np.diag(a) if a.ndim == 1 else a
    if np.min(np.linalg.eigvalsh(0.5 * (a + a.T))) < -1e-9 * max(np.max(np.abs(a)), 1.0):
        raise SceneError(where, "must be positive semi-definite (damping dissipates)")
    return tuple(tuple(float(c) for c in row) for row in a)


def _wave_headings(bodies, waves, coupled) -> None:
    """A body's own excitation tables must hold the wave heading relative to its x axis (the vessel's
    are checked with the waves; a coupled file's with the vessel's)."""
    if not isinstance(waves, dict) or waves.get("spreading", 0.0) or not isinstance(waves.get("heading", 0.0), (int, float)):
        return
    beta = float(waves.get("heading", 0.0))
    for i, b in enumerate(bodies):
        hd = b.hydrodynamics
        if b.name in coupled or hd is None or hd.headings is None:
            continue
        heads = np.asarray(hd.headings, dtype=float)
        rel = [beta - b.heading + k * 2 * math.pi for k in (-1, 0, 1)]
        inside = [r for r in rel if heads[0] - 1e-6 <= r <= heads[-1] + 1e-6]
        if not inside:
            raise SceneError(f"bodies[{i}].heading", f"the waves' heading {beta:.6g} rad is {rel[1]:.6g} rad from "
                                                     f"{b.name!r}'s x axis, outside its excitation tables' headings "
                                                     f"{np.round(heads, 6).tolist()} rad")


def _points_inside(connections, vessel, bodies) -> None:
    """A connection's point in a body's frame lies within that body's hull (hull_extent; its side and
    its keel themselves included, within EDGE of the hull's size): a hawser's fairlead or a
    fender's face outside it is a typing error (a sign or the other body's frame)."""
    owners = {"vessel": vessel} | {b.name: b for b in bodies}
    keys = {"vessel": "vessel.hull.file"} | {b.name: f"bodies[{i}].hull.file" for i, b in enumerate(bodies)}
    for i, c in enumerate(connections):
        for k, (end, p) in enumerate(zip(c.ends, c.points)):
            box = hull_extent(owners[end], keys[end]) if end in owners else None
            if box is None:
                continue
            lo, hi = np.asarray(box[0]), np.asarray(box[1])
            tol = EDGE * max(float(np.max(hi - lo[:2])), 1.0)
            out = [f"{'xy'[j]} = {p[j]:.6g} m outside [{lo[j]:.6g}, {hi[j]:.6g}]" for j in (0, 1)
                   if not lo[j] - tol <= p[j] <= hi[j] + tol]
            if p[2] < lo[2] - tol:
                out.append(f"z = {p[2]:.6g} m below the keel at {lo[2]:.6g} m")
            if out:
                whose = (("the vessel's" if end == "vessel" else f"{end!r}'s")
                         + (" hull" if owners[end].hull is not None else " footprint"))
                raise SceneError(f"connections[{i}].points", (
                    f"point {k + 1} {list(p)} (in {end!r}'s frame, from its COG) lies outside {whose}: "
                    f"{'; '.join(out)}"))


def read_connections(tables, vessel, bodies) -> tuple[Connection, ...]:
    """The `[[connections]]` of a scene, their ends among "vessel" (or the vessel's name), the
    bodies' names and "fixed", their points within their bodies' hulls where those are known."""
    vessel_name = vessel.name
    names = [b.name for b in bodies]
    out = []
    for i, table in enumerate(tables):
        where = f"connections[{i}]"
        v = read(table, where, {
            "name": ("str", valid_name), "kind": ("str", one_of(KINDS)), "bodies": ("any", None),
            "points": ("any", None), "length": ("float", non_negative), "stiffness": ("float", positive),
            "curve": ("numbers", None), "damping": ("float", non_negative),
        }, required=("kind", "bodies", "points", "length"))
        name = v.get("name", f"connection{i + 1}")
        if name in [c.name for c in out]:
            raise SceneError(f"{where}.name", f"{show(name)} is the name of another connection")
        ends = table["bodies"]
        if not (isinstance(ends, list) and len(ends) == 2 and all(isinstance(e, str) for e in ends)):
            raise SceneError(f"{where}.bodies", f"must be a list of 2 names, got {show(ends)}")
        known = ["vessel", vessel_name, *names]
        for k, e in enumerate(ends):
            if e == "fixed" and k == 0:
                raise SceneError(f"{where}.bodies", '"fixed" may only be the second end (the first is a body: '
                                                    '"vessel" or one of [[bodies]])')
            if e not in known and e != "fixed":
                raise SceneError(f"{where}.bodies", f"{show(e)} is not a body of the scene (bodies: "
                                                    f"{', '.join(repr(n) for n in dict.fromkeys(known))}; or \"fixed\")")
        canon = tuple("vessel" if e == vessel_name else e for e in ends)
        if canon[0] == canon[1]:
            raise SceneError(f"{where}.bodies", f"{show(ends)} ties a body to itself")
        pts = table["points"]
        if not (isinstance(pts, list) and len(pts) == 2 and all(
                isinstance(p, list) and len(p) == 3 and all(isinstance(c, (int, float)) and not isinstance(c, bool)
                                                            and math.isfinite(c) for c in p) for p in pts)):
            raise SceneError(f"{where}.points", f"must be 2 points [[x, y, z], [x, y, z]] (m), one in each body's "
                                                f"frame, got {show(pts)}")
        if ("stiffness" in v) == ("curve" in v):
            raise SceneError(f"{where}.stiffness", "give either stiffness (N/m) or curve = [[deflection, force], ...]")
        if v["length"] <= 0 and v["kind"] == "hawser":
            raise SceneError(f"{where}.length", f"must be positive for a hawser, got {show(v['length'])}")
        curve = _curve(v["curve"], f"{where}.curve") if "curve" in v else ()
        out.append(Connection(name=name, kind=v["kind"], ends=canon,
                              points=tuple(tuple(float(c) for c in p) for p in pts), length=v["length"],
                              stiffness=v.get("stiffness"), curve=curve, damping=v.get("damping", 0.0)))
    _points_inside(out, vessel, bodies)
    return tuple(out)


def _curve(x, where: str) -> tuple:
    """((deflection, force), ...) starting at (0, 0) (prepended when the first deflection is positive),
    both columns increasing."""
    a = np.asarray(x, dtype=float)
    if a.ndim != 2 or a.shape[1] != 2 or a.shape[0] < 1:
        raise SceneError(where, f"must be a list of [deflection m, force N] pairs, got shape {a.shape}")
    if a[0, 0] < 0 or (a[0, 0] == 0 and a[0, 1] != 0):
        raise SceneError(where, f"starts at {a[0].tolist()}: deflections are >= 0 and the force at 0 is 0")
    if a[0, 0] > 0:
        a = np.vstack([[0.0, 0.0], a])
    if np.any(np.diff(a[:, 0]) <= 0) or np.any(np.diff(a[:, 1]) <= 0):
        raise SceneError(where, f"must be increasing in both deflection and force, got {a.tolist()}")
    return tuple((float(d), float(f)) for d, f in a)


def bodies_scene(bodies, vessel, structures, mapping, warnings: list[str], files) -> None:
    """What the scene's other parts cannot do with [[bodies]] yet (docs/guide/bodies-and-connections.md)."""
    for i, t in enumerate(mapping.get("tanks", [])):
        body = t.get("body", "vessel") if isinstance(t, dict) else "vessel"
        if body not in ("vessel", vessel.name, *[b.name for b in bodies]):
            raise SceneError(f"tanks[{i}].body", f"{body!r} is not a body of the scene")
    if not bodies:
        return
    _beside_multimodal(bodies, vessel, structures, mapping.get("tanks", []))
    if any(s.frame == "own" for s in structures):
        raise SceneError("bodies", "[[bodies]] together with [[structures]] in their own frames are not available "
                                   "yet (a model holds one of them)")
    coupled = coupled_file(vessel, bodies, files.base_dir)
    if coupled is not None:       # read once here: its names matched, its checks' warnings shown
        path, inside, key = coupled
        try:
            warnings.extend(read_multibody(path, inside, files.rho, files.g).warnings)
            _file_places(path, vessel, bodies)
        except DatabaseError as e:
            raise SceneError(key, " ".join(str(e).split())) from None
    _wave_headings(bodies, mapping.get("waves"), () if coupled is None else coupled[1])
    # a body's nonlinear hydrostatics take the waves' pressure on its hull (the waves' effect and
    # buoyancy on: without them no hull force acts, and the warning below stays true)
    eff = mapping.get("effects", {}) if isinstance(mapping.get("effects", {}), dict) else {}
    on_hull = eff.get("buoyancy", True) is not False and eff.get("waves", True) is not False
    for i, b in enumerate(bodies):
        if b.hydrodynamics is not None and b.hydrodynamics.excitation == "froude-krylov" and not _box_on_springs(b):
            raise SceneError(f"bodies[{i}].hydrodynamics.excitation", '"froude-krylov" needs a box [bodies.hull] and '
                                                                      "linear hydrostatics (a nonlinear body's hull "
                                                                      "takes the waves' pressure itself)")
    # a box hull on linear springs takes the Froude-Krylov force, as the vessel's (assemble/bodyhydro.py box_waves)
    dry = [b.name for b in bodies if (b.hydrodynamics is None or b.hydrodynamics.excitation_amplitude is None)
           and not (b.hydrostatics.nonlinear and on_hull)
           and not (_box_on_springs(b) and (b.hydrodynamics is None or b.hydrodynamics.excitation != "table"))]
    if "waves" in mapping and dry:
        warnings.append(f"waves: the [[bodies]] {', '.join(repr(n) for n in dry)} have no excitation tables "
                        f"([bodies.hydrodynamics] file or excitation_amplitude) and no box hull on linear "
                        "hydrostatics (Froude-Krylov): the waves exert no force on them")


def _box_on_springs(body) -> bool:
    """Whether a body has a box hull and linear hydrostatics (its waves' Froude-Krylov force in closed form)."""
    return body.hull is not None and body.hull.closed_form and not body.hydrostatics.nonlinear


def _file_places(path: str, vessel, bodies) -> None:
    """Each body of a multibody NetCDF file that stores its bodies' centres (Capytaine's
    `rotation_center`, else `center_of_mass`) is where the scene puts it: horizontally at its
    `position` from the file's origin, the vessel's COG at rest (the vessel at the origin), and at its
    `cog_height` (the point its dofs rotate about), within PLACE m. Files without centres (WAMIT's,
    older Capytaine's) are taken as the scene says."""
    centres = file_centres(path)
    places = {vessel.name: ((0.0, 0.0, vessel.cog_height), "vessel.hydrodynamics.file", "vessel.cog_height")}
    places |= {b.name: ((*b.position, b.cog_height), f"bodies[{i}].position", f"bodies[{i}].cog_height")
               for i, b in enumerate(bodies)}
    for name, centre in centres.items():
        if name not in places:
            continue
        (x, y, z), plan_key, height_key = places[name]
        cx, cy, cz = centre
        if math.hypot(cx - x, cy - y) > PLACE:
            where = "at the origin (the vessel)" if plan_key.startswith("vessel") else f"at {show([x, y])}"
            raise SceneError(plan_key, f"{path} places {name!r} at x, y = {cx:.6g}, {cy:.6g} m (its rotation centre "
                                       f"from the file's origin, the vessel's COG at rest), the scene {where}: its "
                                       f"waves' phases and the coupling would be another layout's")
        if abs(cz - z) > PLACE:
            raise SceneError(height_key, f"{path} has {name!r} rotate about z = {cz:.6g} m, the scene's COG height "
                                         f"{z:.6g} m: give cog_height = {cz:.6g} (the file's tables are about that "
                                         f"point)")


def file_centres(path: str) -> dict:
    try:
        return netcdf_centres(path) if os.path.splitext(path)[1].lower() != ".1" else {}
    except (KeyError, ValueError) as e:
        raise DatabaseError(f"{path}: its bodies' centres do not read ({e})") from None


def _beside_multimodal(bodies, vessel, structures, tables) -> None:
    """A body's multimodal tank joins the Newton matrix's exact block with its few coordinates, and the
    vessel's liquid lies before them there (physics/system.py exact_block): the vessel's tanks must
    then be multimodal too, or none, and no structure share their block."""
    where = next((f"tanks[{i}].model" for i, t in enumerate(tables) if isinstance(t, dict)
                  and t.get("body", "vessel") in [b.name for b in bodies] and t.get("model") == "multimodal"), None)
    if where is None:
        return
    carried = [tank_carriers(tables, vessel.name)[i] == "vessel" and t.get("model", "fem") != "multimodal"
               for i, t in enumerate(tables) if isinstance(t, dict)]
    if any(carried) or any(s.frame == "vessel" for s in structures):
        raise SceneError(where, "a multimodal tank on one of [[bodies]] beside finite-element tanks (or structures) "
                                "on the vessel is not available yet: make the vessel's tanks multimodal too, or the "
                                "body's reduced ([tanks.reduction])")


def resolve(hd, base: str = "") -> str:
    """The path of a `hydrodynamics` table's `file` (relative to the scene's folder: its base_dir,
    else `base`)."""
    return hd.file if os.path.isabs(hd.file) else os.path.join(hd.base_dir or base, hd.file)


def coupled_file(vessel, bodies, base: str = "") -> Optional[tuple]:
    """(path, the bodies' names in the file's order, which key named it) of the scene's multibody
    file, or None. The vessel's file first, else the first body's that is one."""
    cands = [("vessel.hydrodynamics.file", vessel.hydrodynamics)] + \
        [(f"bodies[{i}].hydrodynamics.file", b.hydrodynamics) for i, b in enumerate(bodies)]
    scene_names = [vessel.name] + [b.name for b in bodies]
    for key, hd in cands:
        if hd is None or not hd.file:
            continue
        path = resolve(hd, base)
        have = file_bodies(path)
        if have is None:
            continue
        if isinstance(have, int):              # WAMIT NBODY: the scene's first bodies, in order
            if have > len(scene_names):
                raise SceneError(key, f"{path} holds {have} bodies, the scene {len(scene_names)}")
            return path, tuple(scene_names[:have]), key
        unknown = [n for n in have if n not in scene_names]
        if unknown:
            raise SceneError(key, f"{path} holds the bodies {list(have)}: {unknown} are not bodies of the scene "
                                  f"({scene_names}); the file's bodies are matched by name")
        vh = vessel.hydrodynamics
        if vessel.name in have and (vh is None or not vh.file or
                                    os.path.abspath(resolve(vh, base)) != os.path.abspath(path)):
            raise SceneError("vessel.hydrodynamics.file", f"the vessel {vessel.name!r} is in {path} ({key}): name "
                                                          "that file in [vessel.hydrodynamics] too (its own block "
                                                          "and excitation are read from it)")
        return path, tuple(have), key
    return None
