"""`vessel.hydrostatics.model = "nonlinear"` at load: the hull it needs (a box with its depth, or a
closed mesh, validated here so that a bad file is an input error) and the linear values of the same
hull (eqs. 33-38), which the scene's other readers (check, the frequency domain) keep using."""
from __future__ import annotations

import numpy as np

from ..hull.hydrostatics import rest_hydrostatics
from ..hull.surface import HullMeshError, hull_triangles, water_height
from ..hydro.box import box_hydrostatics
from .fields import show
from .types import SceneError

#: relative difference of a value given in [vessel.hydrostatics] from the hull's that warns
HULL_VALUE_TOLERANCE = 0.01
#: horizontal distance of the centre of buoyancy from the COG, over the hull's size, that warns
TRIM_TOLERANCE = 1e-3


def nonlinear_hydrostatics(v: dict, hull, environment, warnings: list[str]) -> dict:
    """The `[vessel.hydrostatics]` values of a nonlinear model: the hull's, with a warning where the
    table gives others."""
    where = "vessel.hydrostatics"
    if hull is None:
        raise SceneError(f"{where}.model", '"nonlinear" needs a [vessel.hull] table: a box with its depth, or a '
                                           'closed mesh (type = "mesh")')
    if hull.type == "box":
        if hull.depth is None:
            raise SceneError("vessel.hull.depth", 'a required key is missing (model = "nonlinear" needs the box\'s '
                                                  "keel-to-deck depth)")
        own = box_hydrostatics(hull.length, hull.beam, hull.draft, hull.kg)
    else:
        own = mesh_hydrostatics(hull, environment, warnings)
    out = dict(v)
    for key, closed in own.items():
        if key in v and abs(v[key] - closed) > HULL_VALUE_TOLERANCE * max(abs(closed), 1e-12):
            warnings.append(f"{where}.{key} = {show(v[key])} differs from the hull's {closed:.6g} (vessel.hull); "
                            f'model = "nonlinear" uses the hull')
        out[key] = float(closed)
    return out


def mesh_hydrostatics(hull, environment, warnings: list[str]) -> dict:
    try:
        tris = hull_triangles(hull)
    except HullMeshError as e:
        raise SceneError("vessel.hull.file", str(e)) from None
    h = rest_hydrostatics(tris, water_height(hull), environment.water_density, environment.gravity)
    if h["displaced_volume"] <= 0 or h["waterplane_area"] <= 0:
        raise SceneError("vessel.hull.file", f"{hull.file}: the hull does not cross the water plane z = 0 of its "
                                             "file's coordinates (the waterline at rest)")
    size = float(np.ptp(tris.reshape(-1, 3), axis=0).max())
    xb, yb, _ = h.pop("centre_of_buoyancy")
    if max(abs(xb), abs(yb)) > TRIM_TOLERANCE * size:
        warnings.append(f"vessel.hull.cog: the centre of buoyancy at rest lies {xb:.4g} m forward and {yb:.4g} m to "
                        "port of the COG: the vessel is not in equilibrium at its mesh's waterline and trims or "
                        "heels from the start")
    return h
