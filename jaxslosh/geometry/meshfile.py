"""The mesh tank (`shape = "mesh"`): the liquid at rest as hexahedra read with meshio from a file (any
format it reads), in tank coordinates; faces on its highest plane are the free surface, every other
boundary face is a wall. Its fill depth and counts come from the file. A mesh that is a box grid is
renumbered as one (it then builds exactly as the box)."""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import ClassVar, final

import numpy as np

from ..fem.mesh import grid_nodes
from ..fem.meshfile import read_mesh_file
from ..fem.shapes import TankMesh, as_grid, finish, grid_counts, hex_volumes, read_mesh
from ..fem.slip import boundary, boundary_faces, face_normals
from ..hull.tanks import mesh_surface
from .base import AbstractShape, Reader


@final
@dataclass(frozen=True)
class MeshFile(AbstractShape):
    """`file`: the mesh file's path (absolute, or as the scene gave it relative to its folder)."""
    name: ClassVar[str] = "mesh"
    keys: ClassVar[tuple] = ("file",)

    size: tuple = (1.0, 1.0, 1.0)
    file: str = ""
    baffles: tuple = ()

    @classmethod
    def read_fill_and_mesh(cls, table, v, where: str, base_dir: str, reader: Reader) -> None:
        """(fill_depth, mesh counts) from the file: the free surface's height, and the box grid's
        counts if the mesh is one, else (elements, 1, 1). docs/guide/tank-meshes.md: neither key is given."""
        show = reader.show
        if "mesh" in table:
            raise reader.error(f"{where}.mesh", 'a shape = "mesh" tank is meshed by its file: leave mesh out')
        if "file" not in table:
            raise reader.error(f"{where}.file", 'shape = "mesh" needs the mesh file of the liquid at rest')
        path = table["file"] if os.path.isabs(str(table["file"])) else os.path.join(base_dir, str(table["file"]))
        if not os.path.isfile(path):
            raise reader.error(f"{where}.file", f"no such file: {path}")
        try:
            nodes, elements = read_mesh(path)
        except ValueError as e:
            raise reader.error(f"{where}.file", str(e)) from None
        lo, hi = nodes.min(axis=0), nodes.max(axis=0)
        tol = 1e-6 * max(v["size"])
        if np.any(lo < -tol) or np.any(hi > np.asarray(v["size"]) + tol):
            raise reader.error(f"{where}.file", f"the mesh ({show(list(lo))} to {show(list(hi))} m) does not fit in "
                                                f"the tank's size {show(list(v['size']))} (tank-local coordinates)")
        depth = float(hi[2])
        if "fill_depth" in v and abs(v["fill_depth"] - depth) > tol:
            raise reader.error(f"{where}.fill_depth", f"a mesh tank's fill depth is its mesh's highest plane, "
                                                      f"{depth:.6g} m (leave fill_depth out), got {show(v['fill_depth'])}")
        grid = grid_counts(nodes, elements)
        v["fill_depth"], v["mesh"] = depth, grid if grid is not None else (len(elements), 1, 1)

    @classmethod
    def read_own(cls, table, v, where: str, base_dir: str, reader: Reader) -> dict:
        if "file" not in table:
            raise reader.error(f"{where}.file", 'shape = "mesh" needs the mesh file of the liquid at rest')
        path = v["file"] if os.path.isabs(v["file"]) else os.path.join(base_dir, v["file"])
        if not os.path.isfile(path):
            raise reader.error(f"{where}.file", f"no such file: {path}")
        return {"file": path}

    @classmethod
    def sketch(cls, table) -> "MeshFile":
        return cls(size=tuple(table["size"]), file=str(table.get("file", "")))

    def volume(self, fill_depth: float) -> float:
        nodes, elements = read_mesh(self.file)
        return float(hex_volumes(nodes, elements).sum())

    def _mesh(self, h: float, counts: tuple, graded: bool = True) -> TankMesh:
        nodes, elements = read_mesh(self.file)
        grid = as_grid(nodes, elements)
        if grid is not None:
            nodes, elements, dims = grid
            return finish(nodes, elements, dims, float(nodes[:, 2].max()))
        return finish(nodes, elements, None, float(nodes[:, 2].max()))

    def box_counts(self, fill_depth: float):
        """The counts of a file that is a uniform box grid over the tank's whole footprint from its min
        corner, filled to `fill_depth` (it then builds as the box); else None."""
        nodes, elements = read_mesh(self.file)
        grid = as_grid(nodes, elements)
        if grid is None:
            return None
        nodes, _, dims = grid
        a, b, _ = self.size
        ref = grid_nodes((a, b, fill_depth), dims)
        if np.abs(nodes - ref).max() > 1e-9 * max(a, b, fill_depth):
            return None
        return dims

    def locks(self, fill_depth: float) -> tuple[bool, str]:
        if self.box_counts(float(fill_depth)) is not None:
            return False, "a mesh file that is a box grid builds as the box"
        return True, "a mesh tank"

    def reentrant(self, fill_depth: float) -> tuple[bool, str]:
        """A mesh is re-entrant where a boundary face is not on the liquid's convex hull: its plane is
        no supporting plane, nodes lie beyond it along its outward normal (a U-tube's duct roof, a
        slit baffle's faces). Features under 0.1 % of the mesh's extent are let pass."""
        if self.box_counts(float(fill_depth)) is not None:
            return False, ""
        from scipy.spatial import ConvexHull, QhullError     # here: the loader's import stays light
        nodes, elements = read_mesh(self.file)
        faces, owner = boundary_faces(elements)
        normal, area = face_normals(nodes, faces)
        centre = nodes[elements[owner]].mean(axis=1)
        normal = np.where((np.einsum("ij,ij->i", normal, nodes[faces].mean(axis=1) - centre) >= 0)[:, None],
                          normal, -normal)
        scale = float(np.ptp(nodes, axis=0).max())
        try:
            corners = nodes[ConvexHull(nodes).vertices]
        except QhullError:               # a flat mesh: nothing to say here (the loader refuses it elsewhere)
            return False, ""
        ok = area > 1e-14 * scale ** 2
        gap = np.zeros(len(faces))
        for i in range(0, len(faces), 4096):           # (faces, hull corners) in slices: bounded memory
            n, own = normal[i:i + 4096], nodes[faces[i:i + 4096]]
            gap[i:i + 4096] = (corners @ n.T).max(axis=0) - np.einsum("fkj,fj->fk", own, n).max(axis=1)
        bad = ok & (gap > 1e-3 * scale)
        if not bad.any():
            return False, ""
        return True, f"a re-entrant mesh: {int(bad.sum())} of its {len(faces)} boundary faces off its convex hull"

    def _outline(self, fill_depth: float, mesh) -> list:
        """The mesh's feature edges (faces meeting at more than 30 degrees)."""
        nodes, elements = ((np.asarray(mesh[0], float), np.asarray(mesh[1])) if mesh is not None
                           else read_mesh(self.file))
        bd = boundary(nodes, elements, float(nodes[:, 2].max()))
        faces = np.concatenate([bd.wall_faces, bd.top_faces])
        X = nodes[faces]
        nrm = np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        edges = np.concatenate([np.sort(faces[:, [i, (i + 1) % 4]], axis=1) for i in range(4)])
        owner = np.tile(np.arange(len(faces)), 4)
        _, inv = np.unique(edges, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        order = np.argsort(inv, kind="stable")
        lines = []
        for k in range(0, len(order) - 1):
            i, j = order[k], order[k + 1]
            if inv[i] == inv[j] and nrm[owner[i]] @ nrm[owner[j]] < np.cos(np.radians(30.0)):
                lines.append(nodes[edges[i]])
        return lines

    def surface(self):
        return mesh_surface(self.file, self.size[2])

    def _describe(self) -> str:
        return f"mesh ({self.file})"

    def _notes(self, fill_depth: float, counts) -> list[str]:
        m = read_mesh_file(self.file)
        if not m.reoriented:
            return []
        return [f"  note: {m.reoriented} of the {len(m.elements)} hexahedra in {os.path.basename(self.file)} are "
                f"numbered left-handed (inverted) in the file; they are re-oriented"]

    def mesh_words(self):
        try:
            nodes, elements = read_mesh(self.file)
        except (OSError, ValueError):
            return None
        if grid_counts(nodes, elements) is not None:
            return None
        return f"mesh file of {len(elements)} hexahedra on {len(nodes)} nodes"
