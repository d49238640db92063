"""A result file as ParaView reads it: XDMF 3 time series over one HDF5 file (`jaxslosh export`).

Each mesh is its own XDMF file (one temporal collection each, so meshio's TimeSeriesReader reads
every one; ParaView opens them together), all over one HDF5 file `STEM_paraview.h5`:

* `STEM.xdmf`: the liquid of every tank (without tanks: the vessel), hexahedra in the inertial frame (the tank moved with the
  vessel, plus the liquid's displacement), point data `displacement` (the result's deformational
  displacement, tank frame, m) and `elevation` (its vertical part); a multimodal tank's is one
  layer of hexahedra over its base, its top at the free surface the modal coordinates give;
* `STEM_surface.xdmf`: the free surfaces (the top faces of the liquid meshes), quadrilaterals,
  `elevation`;
* `STEM_vessel.xdmf`: the hull as its wetted box (a `[vessel.hull]` box: keel to waterline), or
  the vessel's frame as three lines along its axes from the COG;
* `STEM_structures.xdmf`: flexible structures as their undeformed blocks carried by the vessel
  (a result file keeps no structure fields: their probes carry their deformation);
* `STEM_body_<name>.xdmf`: each [[bodies]] body as its wetted box (a `[bodies.hull]` box), else its
  frame (three lines along its axes from its COG, half the side of a square of its waterplane
  area long), and
  `STEM_<name>_liquid.xdmf`, `STEM_<name>_surface.xdmf` the tanks it carries;
* `STEM_probes.xdmf`: the probes' material points, `displacement` (the result's, inertial).

Every step has its own geometry (the meshes move) and attributes, one HDF5 dataset each; the
topology is written once. The scene's tanks, hull, structures and bodies come from the TOML text the
result keeps (tomllib: io sits below the scene loader).
"""
from __future__ import annotations

import os
from typing import NamedTuple

import h5py
import numpy as np

from ..fem.mesh import box_mesh
from .result import Result

try:
    import tomllib
except ModuleNotFoundError:        # Python 3.10
    import tomli as tomllib

#: XDMF topology names and nodes per cell
TOPOLOGY = {"hexahedron": ("Hexahedron", 8), "quad": ("Quadrilateral", 4), "line": ("Polyline", 2),
            "vertex": ("Polyvertex", 1)}


class Series(NamedTuple):
    """One mesh over time: cells (E, c) of `kind`, points (k, N, 3) per frame, point data
    {name: (k, N) or (k, N, 3)}."""
    name: str
    kind: str
    cells: np.ndarray
    points: np.ndarray
    data: dict


def rotation_matrices(q):
    """A(q) (k, 3, 3), body to inertial, of Euler parameters (k, 4) scalar first."""
    q0, q1, q2, q3 = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    return np.stack([
        np.stack([q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)], -1),
        np.stack([2 * (q1 * q2 + q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 - q0 * q1)], -1),
        np.stack([2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3], -1),
    ], -2)


def carried(X0, A, body_points):
    """Inertial positions (k, N, 3) of points fixed in the vessel frame, or moving in it ((k, N, 3))."""
    p = np.asarray(body_points, dtype=float)
    if p.ndim == 2:
        return X0[:, None, :] + np.einsum("kij,nj->kni", A, p)
    return X0[:, None, :] + np.einsum("kij,knj->kni", A, p)


def _scene(text: str) -> dict:
    try:
        return tomllib.loads(text or "")
    except (tomllib.TOMLDecodeError, TypeError, ValueError):
        return {}


def no_fields_why(r: Result) -> str:
    """Why a result keeps no liquid fields, as far as its scene says (what `plot --surface` and
    `export --paraview` tell a user who expected them)."""
    tanks = _scene(r.scene_text).get("tanks", [])
    if not tanks:
        return "its scene has no tanks"
    why = "it was run with --no-fields, or its fields would have passed 200 MB (`jaxslosh run` then leaves them out)"
    if any(t.get("model") == "multimodal" for t in tanks):
        why += ", or it is a multimodal run made before jaxslosh kept the multimodal free surface: run it again"
    return why


def _tank_origins(scene: dict) -> dict:
    return {t.get("name"): np.asarray(t.get("origin", (0.0, 0.0, 0.0)), dtype=float) for t in scene.get("tanks", [])}


def series_of(r: Result, every: int = 1) -> list:
    """The meshes of a result over its frames (every `every`-th), in the inertial frame."""
    scene = _scene(r.scene_text)
    sl = slice(None, None, every)
    X0 = np.asarray(r.vessel.position, dtype=float)[sl]
    A = rotation_matrices(np.asarray(r.vessel.quaternion)[sl])
    out = []
    origins = _tank_origins(scene)
    vessel = scene.get("vessel", {})
    mine = ("vessel", vessel.get("name", "vessel"))
    on_bodies = {t.get("name") for t in scene.get("tanks", []) if t.get("body", "vessel") not in mine}
    out += _liquid(r, [n for n in r.tanks if n not in on_bodies], X0, A, origins, sl, "")
    size = max([max(t.get("size", (1.0,))) for t in scene.get("tanks", [])] + [1.0])
    out.append(_hull("vessel", vessel, X0, A, size))
    blocks = []
    for st in scene.get("structures", []):
        pts, el = box_mesh(st["size"], st["mesh"])
        blocks.append((pts + np.asarray(st["origin"], dtype=float), el))
    if blocks:
        offs = np.cumsum([0] + [p.shape[0] for p, _ in blocks])
        out.append(Series("structures", "hexahedron", np.concatenate([e + o for (_, e), o in zip(blocks, offs)]),
                          carried(X0, A, np.concatenate([p for p, _ in blocks])), {}))
    out += _bodies(r, scene, origins, sl)
    if r.probes:
        names = list(r.probes)
        pos = np.stack([np.asarray(r.probes[k].position, dtype=float)[sl] for k in names], axis=1)
        dis = np.stack([np.asarray(r.probes[k].displacement, dtype=float)[sl] for k in names], axis=1)
        out.append(Series("probes", "vertex", np.arange(len(names))[:, None], pos, {"displacement": dis}))
    return out


def _liquid(r: Result, names, X, A, origins: dict, sl, prefix: str) -> list:
    """The liquid and free-surface meshes of the tanks `names` (those the result keeps fields of),
    carried by the frame (X, A) that holds them: the vessel's, or a body's (`prefix` "<body>_")."""
    nodes, cells, disp, surf_cells, offset = [], [], [], [], 0
    for name in names:
        if name not in r.tanks:
            continue
        t = r.tanks[name]
        n = np.asarray(t.nodes, dtype=float)
        d = np.asarray(t.displacement, dtype=float)[sl]
        nodes.append(n + origins.get(name, np.zeros(3)))
        cells.append(np.asarray(t.elements) + offset)
        disp.append(d)
        el = np.asarray(t.elements)
        top = np.isclose(n[:, 2], n[:, 2].max())
        faces = el[:, 4:8]                                 # hex8: the top face is the last four corners
        surf_cells.append(faces[top[faces].all(axis=1)] + offset)
        offset += n.shape[0]
    if not nodes:
        return []
    D = np.concatenate(disp, axis=1)
    P = carried(X, A, np.concatenate(nodes)[None] + D)
    data = {"displacement": D, "elevation": D[..., 2]}
    return [Series(f"{prefix}liquid", "hexahedron", np.concatenate(cells), P, data),
            Series(f"{prefix}surface", "quad", np.concatenate(surf_cells), P, {"elevation": D[..., 2]})]


def _axes(name: str, X, A, size: float) -> Series:
    """A frame as three lines `size` long along its axes from its origin (a vessel or body without a hull)."""
    pts = np.array([[0.0, 0.0, 0.0], [size, 0, 0], [0, size, 0], [0, 0, size]])
    return Series(name, "line", np.array([[0, 1], [0, 2], [0, 3]]), carried(X, A, pts), {})


def _hull(name: str, table: dict, X, A, size: float) -> Series:
    """The vessel's or a body's hull (its `table`) carried by its frame: a box hull as its wetted box
    (keel to waterline), else its frame's axes `size` long."""
    hull = table.get("hull") or {}
    if hull.get("type", "box") == "box" and all(k in hull for k in ("length", "beam", "draft", "kg")):
        L, B, T, kg = (float(hull[k]) for k in ("length", "beam", "draft", "kg"))
        pts, el = box_mesh((L, B, T), (1, 1, 1))
        return Series(name, "hexahedron", el, carried(X, A, pts + np.array([-L / 2, -B / 2, -kg])), {})
    return _axes(name, X, A, size)


def _cog_height(vessel: dict) -> float:
    """The vessel's COG height above the still water at rest, as the loader gives it: its
    `cog_height`, else kg - draft for a box hull, else 0."""
    if "cog_height" in vessel:
        return float(vessel["cog_height"])
    hull = vessel.get("hull") or {}
    if hull and hull.get("type", "box") == "box" and "kg" in hull and "draft" in hull:
        return float(hull["kg"]) - float(hull["draft"])
    return 0.0


def _bodies(r: Result, scene: dict, origins: dict, sl) -> list:
    """Each [[bodies]] body's meshes, carried by its own frame: its box hull as the vessel's, else its
    axes, sized by its waterplane (half the side of a square of its area), and the liquid of the
    tanks it carries; `body_<name>` and `<name>_liquid`, `<name>_surface`."""
    out = []
    cog = _cog_height(scene.get("vessel", {}))
    tables = {b.get("name"): b for b in scene.get("bodies", [])}
    for name, b in (r.bodies or {}).items():
        table = tables.get(name, {})
        px, py = (list(table.get("position", (0.0, 0.0))) + [0.0, 0.0])[:2]
        rest = np.array([px, py, _cog_height(table) - cog])      # its height as the loader gives it
        X = rest + np.asarray(b.position, dtype=float)[sl]      # the result keeps its offset from rest
        A = rotation_matrices(np.asarray(b.quaternion)[sl])
        area = float(table.get("hydrostatics", {}).get("waterplane_area", 4.0))
        out.append(_hull(f"body_{name}", table, X, A, 0.5 * np.sqrt(max(area, 1e-12))))
        out += _liquid(r, [t.get("name") for t in scene.get("tanks", []) if t.get("body") == name], X, A, origins,
                       sl, f"{name}_")
    return out


def _item(h5name: str, path: str, shape, kind="Float") -> str:
    dims = " ".join(str(s) for s in shape)
    return f'<DataItem DataType="{kind}" Dimensions="{dims}" Format="HDF" Precision="8">{h5name}:{path}</DataItem>'


def write_series(xdmf: str, h5: h5py.File, h5name: str, s: Series, times) -> None:
    """One mesh's XDMF file; its arrays into the open HDF5 file `h5` under /<name>."""
    g = h5.create_group(s.name)
    g.create_dataset("topology", data=np.asarray(s.cells, dtype=np.int64))
    topo, per = TOPOLOGY[s.kind]
    ne, nn = s.cells.shape[0], s.points.shape[1]
    extra = f' NodesPerElement="{per}"' if s.kind in ("line", "vertex") else ""
    topology = (f'<Topology TopologyType="{topo}" NumberOfElements="{ne}"{extra}>'
                f'{_item(h5name, f"/{s.name}/topology", s.cells.shape, "Int")}</Topology>')
    geo = g.create_group("geometry")
    groups = {k: g.create_group(k) for k in s.data}
    lines = ['<?xml version="1.0"?>', '<Xdmf Version="3.0">', "<Domain>",
             f'<Grid Name="{s.name}" GridType="Collection" CollectionType="Temporal">']
    for k, t in enumerate(times):
        geo.create_dataset(str(k), data=s.points[k])
        lines += [f'<Grid Name="{s.name}" GridType="Uniform">', f'<Time Value="{float(t)!r}"/>', topology,
                  f'<Geometry GeometryType="XYZ">{_item(h5name, f"/{s.name}/geometry/{k}", (nn, 3))}</Geometry>']
        for name, v in s.data.items():
            groups[name].create_dataset(str(k), data=v[k])
            kind = "Vector" if v.ndim == 3 else "Scalar"
            lines.append(f'<Attribute Name="{name}" AttributeType="{kind}" Center="Node">'
                         f'{_item(h5name, f"/{s.name}/{name}/{k}", v.shape[1:])}</Attribute>')
        lines.append("</Grid>")
    lines += ["</Grid>", "</Domain>", "</Xdmf>", ""]
    with open(xdmf, "w") as f:
        f.write("\n".join(lines))


def export_paraview(r: Result, xdmf: str, every: int = 1) -> list:
    """Write the result's meshes (series_of) as XDMF files beside `xdmf` (see the module's
    docstring); returns the files written, the HDF5 file last."""
    stem = os.path.splitext(xdmf)[0]
    h5path = stem + "_paraview.h5"
    h5name = os.path.basename(h5path)
    times = np.asarray(r.time, dtype=float)[::every]
    written = []
    meshes = series_of(r, every)
    main = "liquid" if any(s.name == "liquid" for s in meshes) else "vessel"     # no tanks: the vessel's
    with h5py.File(h5path, "w") as h5:
        h5.attrs["format"] = "jaxslosh.paraview"
        for s in meshes:
            path = xdmf if s.name == main else f"{stem}_{s.name}.xdmf"
            write_series(path, h5, h5name, s, times)
            written.append(path)
    return written + [h5path]
