"""The cylinder tank (`shape = "cylinder"`), its axis along x, y (horizontal) or z (vertical); the two
sizes across the axis are its diameter.

* vertical (`axis = "z"`): the x-y disk from the square by the elliptical grid mapping, layers evenly
  spaced in z;
* horizontal (`axis = "x"` or `"y"`): the liquid's circular segment below the fill depth by a
  transfinite (Coons) map of the square, whose bottom edge runs along the bottom of the arc, its
  sides up the arc to the waterline, and its top along the free surface; extruded along the axis.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, final

import numpy as np

from ..fem.mesh import box_elements, count_nodes, grid_index
from ..fem.shapes import TankMesh, finish, merge_coincident
from ..hull.tanks import circle, cyclic, prism_surface
from .base import AXES, AbstractShape, Reader

#: a horizontal cylinder's surface elements this many times taller than wide (a nearly full tank:
#: its free surface a narrow strip) carry no sloshing mode the mesh resolves: `check` says so
SLIVER_ASPECT = 8.0


@final
@dataclass(frozen=True)
class Cylinder(AbstractShape):
    name: ClassVar[str] = "cylinder"
    rt_on_modes: ClassVar[bool] = True
    keys: ClassVar[tuple] = ("axis",)
    modal: ClassVar[bool] = True
    modal_flow: ClassVar[str] = "3d"

    size: tuple = (1.0, 1.0, 1.0)
    axis: str = "x"
    baffles: tuple = ()

    def sloped(self, fill_depth: float) -> bool:
        return True

    @classmethod
    def read_own(cls, table, v, where: str, base_dir: str, reader: Reader) -> dict:
        return {"axis": v.get("axis", "x")}

    @classmethod
    def sketch(cls, table) -> "Cylinder":
        return cls(size=tuple(table["size"]), axis=table.get("axis", "x"))

    @classmethod
    def read_multimodal(cls, table, where: str, reader: Reader) -> None:
        if table.get("axis", "x") != "z":
            raise reader.error(f"{where}.axis", 'a model = "multimodal" cylinder stands upright: axis = "z"')
        if table.get("flow", "3d") != "3d":
            raise reader.error(f"{where}.flow", 'a model = "multimodal" cylinder\'s waves are three-dimensional: '
                                                'leave flow out or write flow = "3d"')

    def check_read(self, v, where: str, reader: Reader) -> None:
        across = [k for k in range(3) if "xyz"[k] != self.axis]
        d1, d2 = (v["size"][k] for k in across)
        if abs(d1 - d2) > 1e-9 * max(d1, d2):
            raise reader.error(f"{where}.size", f"a cylinder's two sizes across its axis are its diameter and must "
                                                f"be equal, got {reader.show(d1)} and {reader.show(d2)} m")

    def _check(self, h: float, counts):
        H = self.size[2]
        if self.axis not in AXES:
            return "axis", f"must be one of {AXES}, got {self.axis!r}"
        if self.axis != "z" and h >= H * (1 - 1e-9):
            return "fill_depth", "a horizontal cylinder's liquid needs a free surface below the top (fill_depth < height)"
        if self.axis == "z" and min(counts[0], counts[1]) < 2:
            return "mesh", "a vertical cylinder needs at least 2 elements along x and y"
        return None

    def volume(self, fill_depth: float) -> float:
        a, b, H = self.size
        h = fill_depth
        if self.axis == "z":
            return float(np.pi * a * b / 4.0 * h)
        L = a if self.axis == "x" else b
        B = b if self.axis == "x" else a
        R = H / 2.0
        t = (h - R) / R                                  # circular segment of the unit circle, scaled to the ellipse
        seg = np.arccos(-t) - (-t) * np.sqrt(max(0.0, 1 - t * t))
        return float(L * seg * (B / 2.0) * R)

    def _mesh(self, h: float, counts: tuple, graded: bool = True) -> TankMesh:
        if self.axis == "z":
            nodes = _vertical(self.size, h, counts)
        else:
            nodes = _horizontal(self.size, h, counts, self.axis)
        nodes, elements = merge_coincident(nodes, box_elements(*counts), count_nodes(counts))
        return finish(nodes, elements, counts, h)

    def _outline(self, fill_depth: float, mesh) -> list:
        a, b, H = self.size
        lines = []
        t = np.linspace(0, 2 * np.pi, 73)
        if self.axis == "z":
            ring = np.column_stack([a / 2 * (1 + np.cos(t)), b / 2 * (1 + np.sin(t))])
            lines += [np.column_stack([ring, np.full(len(t), z)]) for z in (0.0, H)]
            lines += [np.array([[x, y, 0.0], [x, y, H]]) for x, y in ring[:-1:18]]
            return lines
        L, B = (a, b) if self.axis == "x" else (b, a)
        ring = np.column_stack([B / 2 * (1 + np.cos(t)), H / 2 * (1 + np.sin(t))])
        for u in (0.0, L):
            pts = np.column_stack([np.full(len(t), u), ring])
            lines.append(pts if self.axis == "x" else pts[:, [1, 0, 2]])
        for s_, z in ring[:-1:18]:
            seg = np.array([[0.0, s_, z], [L, s_, z]])
            lines.append(seg if self.axis == "x" else seg[:, [1, 0, 2]])
        return lines

    def modal_base(self, rectangle, disk):
        return disk(0.5 * float(self.size[0]))

    def surface(self):
        a, b, H = self.size
        if self.axis == "x":
            return prism_surface(circle((b / 2, H / 2), H / 2), a)
        if self.axis == "y":         # the polygon in (z, x): centre (H/2, a/2)
            return cyclic(prism_surface(circle((H / 2, a / 2), H / 2), b), "y")
        return cyclic(prism_surface(circle((a / 2, b / 2), a / 2), H), "z")

    def _describe(self) -> str:
        return "cylinder (vertical)" if self.axis == "z" else f"cylinder (horizontal, along {self.axis})"

    def _notes(self, fill_depth: float, counts) -> list[str]:
        """A horizontal cylinder filled so near its top that its mesh resolves no sloshing."""
        if self.axis == "z":
            return []
        tm = self.mesh(fill_depth, counts)
        top = np.isclose(tm.nodes[:, 2], tm.depth)
        E = tm.elements[top[tm.elements].sum(axis=1) >= 4]             # the elements under the free surface
        if not len(E):
            return []
        across = 1 if self.axis == "x" else 0
        X = tm.nodes[E]
        height = np.ptp(X[:, :, 2], axis=1)
        width = np.array([np.ptp(x[np.isclose(x[:, 2], tm.depth), across]) for x in X])
        aspect = float(np.max(height / np.maximum(width, 1e-300)))
        if aspect <= SLIVER_ASPECT:
            return []
        D = self.size[2]
        w = float(np.ptp(tm.nodes[top, across]))
        return [f"  note: the horizontal cylinder is nearly full ({fill_depth:g} of {D:g} m): its free surface is a "
                f"strip {w:.3g} m wide ({100 * w / D:.2g} % of the diameter), over elements {aspect:.0f} times "
                f"taller than wide, which resolve no sloshing mode: the lowest modes found there "
                f"(`jaxslosh modes`) are spurious"]


def _vertical(size, h, mesh):
    """The x-y disk (ellipse) from the square by the elliptical grid mapping, layers even in z."""
    nx, ny, nz = mesh
    a, b, _ = size
    g = grid_index(nx, ny, nz)
    u = 2.0 * g[:, 0] / nx - 1.0
    v = 2.0 * g[:, 1] / ny - 1.0
    X = u * np.sqrt(1.0 - 0.5 * v * v)
    Y = v * np.sqrt(1.0 - 0.5 * u * u)
    return np.stack([a / 2 * (1 + X), b / 2 * (1 + Y), h * g[:, 2] / nz], axis=1)


def _horizontal(size, h, mesh, axis):
    """The circular segment (ellipse: scaled) below z = h, Coons-mapped from the square; extruded
    along the axis."""
    nx, ny, nz = mesh
    a, b, H = size
    L, B = (a, b) if axis == "x" else (b, a)
    n_along, n_across = (nx, ny) if axis == "x" else (ny, nx)
    R = H / 2.0
    c = (h - R) / R
    th_r = np.arcsin(np.clip(c, -1, 1))                   # right waterline angle (from the horizontal)
    th_l = np.pi - th_r
    # the arc from the left waterline down round the bottom to the right one: n_z + n_across + n_z pieces
    total = np.pi + 2.0 * th_r
    per = total / (2 * nz + n_across)

    def arc(theta):
        return np.stack([B / 2 * (1 + np.cos(theta)), R * (1 + np.sin(theta))], axis=-1)

    # angles from the left waterline on, going down round the bottom (theta grows through 3 pi / 2)
    k = np.arange(nz + 1)
    j = np.arange(n_across + 1)
    left = arc(th_l + (nz - k) * per)                      # j = 0 side, k from the bottom corner up
    bottom = arc(th_l + (nz + j) * per)                     # k = 0
    right = arc(th_l + (nz + n_across + k) * per)           # j = n side, k from the bottom up
    top = np.stack([np.linspace(left[-1, 0], right[-1, 0], n_across + 1), np.full(n_across + 1, h)], axis=-1)
    s = (j / n_across)[:, None, None]
    t = (k / nz)[None, :, None]
    P = ((1 - t) * bottom[:, None] + t * top[:, None] + (1 - s) * left[None] + s * right[None]
         - ((1 - s) * (1 - t) * bottom[0] + s * (1 - t) * bottom[-1] + (1 - s) * t * top[0] + s * t * top[-1]))
    xs = np.linspace(0.0, L, n_along + 1)
    g = grid_index(nx, ny, nz)
    if axis == "x":
        sec = P[g[:, 1], g[:, 2]]
        return np.stack([xs[g[:, 0]], sec[:, 0], sec[:, 1]], axis=1)
    sec = P[g[:, 0], g[:, 2]]
    return np.stack([sec[:, 0], xs[g[:, 1]], sec[:, 1]], axis=1)
