"""A tank's shape keys (SPEC section 1: `shape`, `chamfers`, `axis`, `file`, `[[tanks.baffles]]`),
read and checked against what fem/shapes.py can mesh."""
from __future__ import annotations

import os

import numpy as np

from ..fem.shapes import Baffle, TankGeometry, check_geometry, read_mesh
from .fields import one_of, positive, read, show
from .types import SceneError


def read_shape(table, v, where: str, base_dir: str, elastic: bool = False) -> dict:
    """The tank's shape keys (fem/shapes.py), checked: {shape, chamfers, axis, file, baffles}."""
    shape = v.get("shape", "box")
    if elastic and (shape != "box" or "baffles" in table):
        raise SceneError(f"{where}.walls", "elastic walls are built for box tanks without baffles only")
    for key, needs in (("chamfers", "prismatic"), ("axis", "cylinder"), ("file", "mesh")):
        if key in table and shape != needs:
            raise SceneError(f"{where}.{key}", f'belongs to shape = "{needs}" tanks; this tank is shape = "{shape}"')
    chamfers = ((0.0, 0.0), (0.0, 0.0))
    if "chamfers" in table:
        c = read(table["chamfers"], f"{where}.chamfers", {"bottom": ("numbers", None), "top": ("numbers", None)})
        pair = []
        for side in ("bottom", "top"):
            w = c.get(side, [0.0, 0.0])
            if not isinstance(w, list) or len(w) != 2 or min(w) < 0:
                raise SceneError(f"{where}.chamfers.{side}", f"must be [width, height] in m (>= 0), got {show(w)}")
            pair.append((float(w[0]), float(w[1])))
        chamfers = tuple(pair)
    path = ""
    if shape == "mesh":
        if "file" not in table:
            raise SceneError(f"{where}.file", 'shape = "mesh" needs the mesh file of the liquid at rest')
        path = v["file"] if os.path.isabs(v["file"]) else os.path.join(base_dir, v["file"])
        if not os.path.isfile(path):
            raise SceneError(f"{where}.file", f"no such file: {path}")
    baffles = []
    for i, b in enumerate(table.get("baffles", [])):
        bw = f"{where}.baffles[{i}]"
        bv = read(b, bw, {"normal": ("str", one_of(("x", "y"))), "at": ("float", None),
                          "mount": ("str", one_of(("bottom", "top"))), "height": ("float", positive)},
                  required=("at", "height"))
        baffles.append(Baffle(normal=bv.get("normal", "x"), at=bv["at"], mount=bv.get("mount", "bottom"),
                              height=bv["height"]))
    out = {"shape": shape, "chamfers": chamfers, "axis": v.get("axis", "x"), "file": path, "baffles": tuple(baffles)}
    geo = TankGeometry(kind=shape, size=tuple(v["size"]), chamfers=chamfers, axis=out["axis"], file=path,
                       baffles=tuple(baffles))
    if shape == "mesh":
        try:
            nodes, _ = read_mesh(path)
        except ValueError as e:
            raise SceneError(f"{where}.file", str(e)) from None
        lo, hi = nodes.min(axis=0), nodes.max(axis=0)
        tol = 1e-6 * max(v["size"])
        if np.any(lo < -tol) or np.any(hi > np.asarray(v["size"]) + tol):
            raise SceneError(f"{where}.file", f"the mesh ({show(list(lo))} to {show(list(hi))} m) does not fit in "
                                              f"the tank's size {show(list(v['size']))} (tank-local coordinates)")
        if abs(hi[2] - v["fill_depth"]) > tol:
            raise SceneError(f"{where}.fill_depth", f"must be the height of the mesh's free surface (its highest "
                                                    f"plane), {hi[2]:.6g} m, got {show(v['fill_depth'])}")
    bad = check_geometry(geo, v["fill_depth"], v["mesh"])
    if bad:
        raise SceneError(f"{where}.{bad[0]}", bad[1])
    return out

