"""`vessel.hydrostatics.model = "nonlinear"` at load: the hull it needs (a box with its depth, or a
closed mesh, validated here so that a bad file is an input error) and the linear values of the same
hull (eqs. 33-38), which the scene's other readers (check, the frequency domain) keep using."""
from __future__ import annotations

from importlib import import_module

import numpy as np

from ..hull.surface import HullMeshError
from .fields import one_of, positive, read, show
from .types import Environment, Hydrostatics, SceneError

MOMENTS = ("paper", "conservative")
HYDROSTATIC_MODELS = ("linear", "nonlinear")

#: relative difference of a value given in [vessel.hydrostatics] from the hull's that warns
HULL_VALUE_TOLERANCE = 0.01
#: horizontal distance of the centre of buoyancy from the COG, over the hull's size, that warns
TRIM_TOLERANCE = 1e-3


def nonlinear_hydrostatics(v: dict, hull, environment, warnings: list[str], owner: str = "vessel") -> dict:
    """The `[vessel.hydrostatics]` values of a nonlinear model (or a body's: `owner` "bodies[i]"
    names its keys): the hull's, with a warning where the table gives others."""
    where = f"{owner}.hydrostatics"
    table = "[vessel.hull]" if owner == "vessel" else "[bodies.hull]"
    if hull is None:
        raise SceneError(f"{where}.model", f'"nonlinear" needs a {table} table: a box with its depth, or a '
                                           'closed mesh (type = "mesh")')
    if hull.closed_form:
        if hull.depth is None:
            raise SceneError(f"{owner}.hull.depth", 'a required key is missing (model = "nonlinear" needs the box\'s '
                                                    "keel-to-deck depth)")
        own = hull.closed_hydrostatics()
    else:
        own = mesh_hydrostatics(hull, environment, warnings, owner)
    out = dict(v)
    for key, closed in own.items():
        if key in v and abs(v[key] - closed) > HULL_VALUE_TOLERANCE * max(abs(closed), 1e-12):
            warnings.append(f"{where}.{key} = {show(v[key])} differs from the hull's {closed:.6g} ({owner}.hull); "
                            f'model = "nonlinear" uses the hull')
        out[key] = float(closed)
    return out


def mesh_hydrostatics(hull, environment, warnings: list[str], owner: str = "vessel") -> dict:
    # imported here: it integrates with JAX, and the loader must not import JAX for other scenes (the
    # command line reads and checks a scene before it imports JAX: docs/guide/exit-status-and-warnings.md)
    rest_hydrostatics = import_module("..hull.hydrostatics", __package__).rest_hydrostatics

    try:
        tris = hull.triangles()
    except HullMeshError as e:
        raise SceneError(f"{owner}.hull.file", str(e)) from None
    h = rest_hydrostatics(tris, hull.water_height(), environment.water_density, environment.gravity)
    if h["displaced_volume"] <= 0 or h["waterplane_area"] <= 0:
        raise SceneError(f"{owner}.hull.file", f"{hull.file}: the hull does not cross the water plane z = 0 of its "
                                             "file's coordinates (the waterline at rest)")
    size = float(np.ptp(tris.reshape(-1, 3), axis=0).max())
    xb, yb, _ = h.pop("centre_of_buoyancy")
    if max(abs(xb), abs(yb)) > TRIM_TOLERANCE * size:
        what = "vessel" if owner == "vessel" else "body"
        warnings.append(f"{owner}.hull.cog: the centre of buoyancy at rest lies {xb:.4g} m forward and {yb:.4g} m to "
                        f"port of the COG: the {what} is not in equilibrium at its mesh's waterline and trims or "
                        "heels from the start")
    return h


def read_hydrostatics(table, warnings: list[str], hull=None, environment: Environment = Environment(),
                      owner: str = "vessel") -> Hydrostatics:
    """`[vessel.hydrostatics]` (or a body's, `owner` "bodies[i]"): the GM springs' values, or the
    hull's own for the nonlinear model."""
    where = f"{owner}.hydrostatics"
    v = read(table, where, {
        "waterplane_area": ("float", positive), "displaced_volume": ("float", positive), "gm_t": ("float", None),
        "gm_l": ("float", None), "moment": ("str", one_of(MOMENTS)), "model": ("str", one_of(HYDROSTATIC_MODELS)),
    })
    if v.get("model", "linear") == "nonlinear":   # the values are the hull's (scene/hull.py)
        v = nonlinear_hydrostatics(v, hull, environment, warnings, owner)
    elif hull is not None and hull.closed_form:   # what the table leaves out is the box's (as with no table)
        v = hull.closed_hydrostatics() | v
    for k in ("waterplane_area", "displaced_volume", "gm_t", "gm_l"):
        if k not in v:
            raise SceneError(f"{where}.{k}", "a required key is missing")
    h = Hydrostatics(**v)
    for key, value, motion in (("gm_t", h.gm_t, "roll"), ("gm_l", h.gm_l, "pitch")):
        if value <= 0:
            warnings.append(f"{where}.{key} = {show(value)} m <= 0: the {'vessel' if owner == 'vessel' else 'body'} is statically unstable in "
                            f"{motion}; it will capsize or loll")
    return h
