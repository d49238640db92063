"""The `[[mooring]]` tables: lines from the seabed to the vessel or a body of `[[bodies]]`
(docs/guide/moorings.md).

Read and checked here, with the `[environment] depth` they need and the vessel's `name` and
`cog_height` (the COG's height above the still-water level, which places the fairleads). No JAX:
the line's solution is built later (jaxslosh/mooring/).
"""
from __future__ import annotations

import math

from .fields import non_negative, one_of, positive, read, show, valid_name
from .lumped_keys import read_lumped
from .types import FloatingBody, MooringLine, SceneError, Vessel

MODELS = ("catenary", "lumped")
#: m: how far below the seabed an anchor may be given (rounding of the depth in a scene file)
SEABED_TOLERANCE = 1e-6


def read_mooring(tables, depth, vessel: Vessel, warnings: list[str], bodies: tuple = ()) -> tuple[MooringLine, ...]:
    """The lines of a scene; `depth` is `[environment] depth` (None when absent), `vessel` the
    scene's, `bodies` its [[bodies]] (scene.types.Body)."""
    held = {b.name: b for b in bodies}
    vessel_name = vessel.name
    owners: dict[str, FloatingBody] = {"vessel": vessel, vessel.name: vessel, **held}
    lines = []
    for i, table in enumerate(tables):
        where = f"mooring[{i}]"
        lumped = ()
        if isinstance(table, dict) and table.get("model") == "lumped":
            if "seabed_friction" in table:
                raise SceneError(f"{where}.seabed_friction", "applies to catenary lines only (a lumped line's "
                                                              "seabed has no friction)")
            table, lumped = read_lumped(table, where)
        v = read(table, where, {
            "name": ("str", valid_name), "body": ("str", None), "fairlead": ("vec3", None), "anchor": ("vec3", None),
            "length": ("float", positive), "weight": ("float", None), "ea": ("float", positive),
            "model": ("str", one_of(MODELS)), "seabed_friction": ("float", non_negative),
        }, required=("fairlead", "anchor", "length", "weight", "ea"))
        if depth is None:
            raise SceneError("environment.depth", f"is required by the mooring lines ({where}): the water depth "
                                                  "in m, which places the seabed")
        body = v.get("body", "vessel")
        if body not in owners:
            raise SceneError(f"{where}.body", f"{show(body)} is not a body of the scene (the vessel is "
                                              f"{show(vessel_name)}; \"vessel\" names it too"
                                              + (f"; the [[bodies]] are {', '.join(map(show, held))})" if held else ")"))
        ax, ay, az = v["anchor"]
        if az < -depth - SEABED_TOLERANCE:
            raise SceneError(f"{where}.anchor", f"z = {show(az)} m is below the seabed at -{show(depth)} m "
                                                "(z is measured from the still-water level)")
        if az > 0:
            raise SceneError(f"{where}.anchor", f"z = {show(az)} m is above the still-water level; anchors lie on "
                                                f"or above the seabed at -{show(depth)} m, under water")
        rest = owners[body].rest_point(v["fairlead"])    # the fairlead, in its body's frame, at rest
        span = math.dist(rest, (ax, ay, az))
        if v["weight"] == 0 and span <= v["length"]:
            raise SceneError(f"{where}.weight", f"0 N/m with a slack line (the anchor is {span:.6g} m from the "
                                                f"fairlead at rest, the line {show(v['length'])} m long): a "
                                                "weightless slack line has no shape; give its submerged weight")
        name = v.get("name", f"line{i + 1}")
        if span > v["length"]:
            strain = span / v["length"] - 1.0
            warnings.append(f"{where}.length: {show(v['length'])} m is shorter than the {span:.6g} m from the "
                            f"fairlead to the anchor at rest: line {name!r} starts stretched as a taut bar "
                            f"(strain {100 * strain:.3g} %, about {v['ea'] * strain:.4g} N)")
        lines.append(MooringLine(name=name, body=body, fairlead=v["fairlead"], anchor=v["anchor"], length=v["length"],
                                 weight=v["weight"], ea=v["ea"], model=v.get("model", "catenary"),
                                 seabed_friction=v.get("seabed_friction", 0.0), anchor_height=max(az + depth, 0.0),
                                 lumped=lumped))
    names = [line.name for line in lines]
    for i, n in enumerate(names):
        if n in names[:i]:
            raise SceneError(f"mooring[{i}].name", f"{show(n)} is the name of another line")
    return tuple(lines)
