"""A tank's shape keys (SPEC section 5: `shape`, `chamfers`, `axis`, `file`, `[[tanks.baffles]]`),
read and checked against what fem/shapes.py can mesh."""
from __future__ import annotations

import os

import numpy as np

from ..fem.shapes import Baffle, TankGeometry, box_equivalent, check_geometry, grid_counts, read_mesh
from .fields import one_of, read, show
from .types import RT_FULL_FACES, SceneError


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
        chamfers = _chamfers(table["chamfers"], f"{where}.chamfers")
    path = ""
    if shape == "mesh":
        if "file" not in table:
            raise SceneError(f"{where}.file", 'shape = "mesh" needs the mesh file of the liquid at rest')
        path = v["file"] if os.path.isabs(v["file"]) else os.path.join(base_dir, v["file"])
        if not os.path.isfile(path):
            raise SceneError(f"{where}.file", f"no such file: {path}")
    H = v["size"][2]
    baffles = []
    for i, b in enumerate(table.get("baffles", [])):
        bw = f"{where}.baffles[{i}]"
        _old_baffle_keys(b, bw, H)
        bv = read(b, bw, {"normal": ("str", one_of(("x", "y"))), "position": ("float", None),
                          "from": ("str", one_of(("bottom", "top"))), "height": ("float", None)},
                  required=("position", "height"))
        mount, edge = bv.get("from", "bottom"), bv["height"]
        if mount == "bottom" and not 0 < edge <= H:
            raise SceneError(f"{bw}.height", f"a standing plate's upper edge must be in (0, {show(H)}] m above the "
                                             f"tank bottom, got {show(edge)}")
        if mount == "top" and not 0 <= edge < v["fill_depth"]:
            raise SceneError(f"{bw}.height", f"a hanging plate's lower edge must be below the free surface "
                                             f"({show(v['fill_depth'])} m above the bottom) and >= 0, got {show(edge)}")
        # fem/shapes.Baffle holds the plate's extent from the bottom up or from the roof down
        baffles.append(Baffle(normal=bv.get("normal", "x"), at=bv["position"], mount=mount,
                              height=edge if mount == "bottom" else H - edge))
    out = {"shape": shape, "chamfers": chamfers, "axis": v.get("axis", "x"), "file": path, "baffles": tuple(baffles)}
    geo = TankGeometry(kind=shape, size=tuple(v["size"]), chamfers=chamfers, axis=out["axis"], file=path,
                       baffles=tuple(baffles))
    if shape == "cylinder":
        across = [k for k in range(3) if "xyz"[k] != out["axis"]]
        d1, d2 = (v["size"][k] for k in across)
        if abs(d1 - d2) > 1e-9 * max(d1, d2):
            raise SceneError(f"{where}.size", f"a cylinder's two sizes across its axis are its diameter and must be "
                                              f"equal, got {show(d1)} and {show(d2)} m")
    bad = check_geometry(geo, v["fill_depth"], v["mesh"])
    if bad:
        raise SceneError(f"{where}.{bad[0]}", bad[1])
    return out


def _old_baffle_keys(b, bw: str, H: float) -> None:
    """An earlier form (`at`, `mount`, `height` as the plate's extent from the bottom or the roof) is
    refused with its translation to SPEC's keys: its `height` means another length, so reading it
    silently either way would put the edge where the user did not mean it."""
    if not isinstance(b, dict) or not ({"at", "mount"} & set(b)):
        return
    key = "at" if "at" in b else "mount"
    mount = b.get("mount", b.get("from", "bottom"))
    parts = []
    if "at" in b:
        parts.append(f"position = {show(b['at'])} (for at)")
    if "mount" in b:
        parts.append(f'from = "{mount}" (for mount)')
    extent = b.get("height")
    if isinstance(extent, (int, float)) and not isinstance(extent, bool) and mount in ("bottom", "top"):
        edge = extent if mount == "bottom" else H - extent
        which = "upper" if mount == "bottom" else "lower"
        parts.append(f"height = {edge:g} (the plate's {which} edge above the tank bottom; the old height "
                     f"{show(extent)} was the plate's extent from the {'bottom' if mount == 'bottom' else 'roof'})")
    else:
        parts.append("height = the edge's height above the tank bottom (the old height was the plate's extent)")
    raise SceneError(f"{bw}.{key}", "an old form of the baffle keys; write " + ", ".join(parts))


def fill_and_mesh(table, v, where: str, base_dir: str) -> None:
    """Set v["fill_depth"] and v["mesh"]: required keys, except for a mesh tank (SPEC section 5: its
    file gives both)."""
    if v.get("shape") == "mesh":
        v["fill_depth"], v["mesh"] = mesh_tank(table, v, where, base_dir)
    for key in ("fill_depth", "mesh"):
        if key not in v:
            raise SceneError(f"{where}.{key}", "a required key is missing")


def mesh_tank(table, v, where: str, base_dir: str):
    """(fill_depth, mesh counts) of a `shape = "mesh"` tank, from its file: the free surface's height,
    and the box grid's counts if the mesh is one, else (elements, 1, 1). SPEC: neither key is given."""
    if "mesh" in table:
        raise SceneError(f"{where}.mesh", 'a shape = "mesh" tank is meshed by its file: leave mesh out')
    if "file" not in table:
        raise SceneError(f"{where}.file", 'shape = "mesh" needs the mesh file of the liquid at rest')
    path = table["file"] if os.path.isabs(str(table["file"])) else os.path.join(base_dir, str(table["file"]))
    if not os.path.isfile(path):
        raise SceneError(f"{where}.file", f"no such file: {path}")
    try:
        nodes, elements = read_mesh(path)
    except ValueError as e:
        raise SceneError(f"{where}.file", str(e)) from None
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    tol = 1e-6 * max(v["size"])
    if np.any(lo < -tol) or np.any(hi > np.asarray(v["size"]) + tol):
        raise SceneError(f"{where}.file", f"the mesh ({show(list(lo))} to {show(list(hi))} m) does not fit in "
                                          f"the tank's size {show(list(v['size']))} (tank-local coordinates)")
    depth = float(hi[2])
    if "fill_depth" in v and abs(v["fill_depth"] - depth) > tol:
        raise SceneError(f"{where}.fill_depth", f"a mesh tank's fill depth is its mesh's highest plane, {depth:.6g} m "
                                                f"(leave fill_depth out), got {show(v['fill_depth'])}")
    grid = grid_counts(nodes, elements)
    return depth, grid if grid is not None else (len(elements), 1, 1)


def _chamfers(value, where):
    """SPEC's [[bottom width, height], [top width, height]], or {bottom = [w, h], top = [w, h]}."""
    if isinstance(value, dict):
        c = read(value, where, {"bottom": ("numbers", None), "top": ("numbers", None)})
        pairs = [(f"{where}.{k}", c.get(k, [0.0, 0.0])) for k in ("bottom", "top")]
    elif isinstance(value, list) and len(value) == 2:
        pairs = [(f"{where}[{i}]", w) for i, w in enumerate(value)]
    else:
        raise SceneError(where, f"must be [[bottom width, height], [top width, height]] in m, got {show(value)}")
    out = []
    for key, w in pairs:
        ok = isinstance(w, list) and len(w) == 2 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                          for x in w)
        if not ok or min(w) < 0:
            raise SceneError(key, f"must be [width, height] in m (>= 0), got {show(w)}")
        out.append((float(w[0]), float(w[1])))
    return tuple(out)



def default_element(shape: dict, size, fill_depth, mesh, reduced: bool) -> tuple[str, str]:
    """(element, why) for a tank whose [tanks.fluid] leaves `element` out: the face-normal "rt" where
    the stabilized element locks (a mesh file that is not a box grid, a tank with baffles: issue 30),
    unless the tank runs at full order on a mesh too large for rt's dense full-order blocks; "rt" for
    prismatic and cylindrical tanks on modes ([tanks.reduction]); else "stabilized" (boxes keep
    their fast diagonalization; shapes at full order their quicker steps)."""
    if shape["shape"] == "mesh":
        geo = TankGeometry(kind="mesh", size=tuple(size), file=shape["file"])
        if box_equivalent(geo, float(fill_depth)) is not None:
            return "stabilized", "a mesh file that is a box grid builds as the box"
        why = "a mesh tank"
    elif shape["baffles"]:
        why = "a tank with baffles"
    elif shape["shape"] in ("prismatic", "cylinder") and reduced:
        # on modes "rt" costs about what the stabilized element does and holds the higher modes at
        # sloping and curved walls better; at full order its dense blocks step several times slower
        # (docs/guide/liquid-element.md, "Prismatic and cylindrical tanks")
        return "rt", f"a {shape['shape']} tank on modes: its higher modes are more accurate with \"rt\""
    else:
        return "stabilized", ""
    if not reduced and 3 * int(np.prod(mesh)) > RT_FULL_FACES:
        return "stabilized", (f"{why} too large for the full-order face-normal element (about "
                              f"{3 * int(np.prod(mesh))} faces): give it a [tanks.reduction] table for \"rt\"")
    return "rt", f"{why}: the stabilized element locks there"
