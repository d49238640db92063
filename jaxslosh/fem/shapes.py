"""Tanks of other shapes than the box: their liquid at rest as a hexahedral mesh, and the slip walls'
node frames.

Every shape is placed by its bounding box (the tank's ``size``, tank-local coordinates from its inner
min corner) and meshed by the tank's ``mesh`` counts mapped onto it:

* ``"prismatic"``: a box whose y-z section has its bottom and top corners cut by chamfers (width
  along y, height along z; membrane LNG tanks' hopper and top-side tanks). Layer k of the mesh sits
  at a height chosen so that every kink of the section (the chamfers' ends) lies on a layer; across,
  the nodes of a layer are spread evenly between the section's walls at that height. Chamfers that
  meet at the centre line give a V bottom: the bottom row of nodes of each x station then merges
  into one node (those elements are wedges, hexahedra with a collapsed face);
* ``"cylinder"`` with ``axis = "z"`` (vertical): the x-y disk (an ellipse if the breadths differ)
  from the square by the elliptical grid mapping, layers evenly spaced in z;
* ``"cylinder"`` with ``axis = "x"`` or ``"y"`` (horizontal): the liquid's circular segment below
  the fill depth by a transfinite (Coons) map of the square, whose bottom edge runs along the
  bottom of the arc, its sides up the arc to the waterline, and its top along the free surface;
* ``"mesh"``: a hexahedral mesh read with meshio (any format it reads); faces on its highest
  plane are the free surface, every other boundary face is a wall. A mesh that is a box grid is
  renumbered as one (it then builds exactly as the box);
* baffles (box and prismatic tanks): thin plates across the tank on a plane of the mesh, standing
  on the bottom or hanging from the roof. The mesh's nodes on the plate are doubled, one for each
  side, so the liquid slides along both faces and flows round the plate's free edge.

The walls' slip conditions (node frames) are fem/slip.py's.

NumPy only (the scene loader uses it to check shapes and to compute their volume).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import NamedTuple, Optional

import numpy as np

from .mesh import HEX_CORNERS, box_elements, grid_index, grid_nodes
from .meshfile import read_mesh_file
from .slip import boundary

SHAPES = ("box", "prismatic", "cylinder", "mesh")
AXES = ("x", "y", "z")


@dataclass(frozen=True)
class Baffle:
    normal: str            # "x" | "y": the plate is the plane normal to this axis
    at: float              # its position along that axis, tank-local, m
    mount: str             # "bottom" (standing) | "top" (hanging from the roof)
    height: float          # the plate's extent from the bottom up, or from the roof down, m


@dataclass(frozen=True)
class TankGeometry:
    """What the liquid's mesh depends on besides the counts: hashable (meshes are cached by it)."""
    kind: str = "box"
    size: tuple = (1.0, 1.0, 1.0)
    chamfers: tuple = ((0.0, 0.0), (0.0, 0.0))    # prismatic: (width, height) of the bottom and top cuts
    axis: str = "x"                                # cylinder
    file: str = ""                                 # mesh: path of the mesh file
    baffles: tuple = ()

    @property
    def plain_box(self) -> bool:
        return self.kind == "box" and not self.baffles


class TankMesh(NamedTuple):
    nodes: np.ndarray            # (N, 3) tank-local, the liquid at rest
    elements: np.ndarray         # (E, 8) hex8, positively oriented (a collapsed face allowed)
    top_faces: np.ndarray        # (F, 4) free-surface faces, counter-clockwise seen from above
    wall_faces: np.ndarray       # (W, 4) wetted wall faces (both faces of a plate included)
    free: np.ndarray             # (N, 3) bool: the node's unknown components in its frame
    frames: Optional[np.ndarray]  # (N, 3, 3) columns: the node's axes; None: every frame is the identity
    grid: Optional[tuple]        # (nx, ny, nz) when the elements are numbered as the box grid's
    depth: float                 # the free surface's height (the fill depth)
    flat: np.ndarray             # (E,) bool: elements with two faces on one smooth wall (fem/slip.py)
    pairs: tuple = ()            # (e0, e1, k): curl rows k of two elements penalised on their difference


# ----------------------------------------------------------------------------------------------- checks

def check_geometry(geo: TankGeometry, fill_depth: float, mesh) -> Optional[tuple]:
    """(key, message) where the geometry's numbers cannot describe it, else None."""
    a, b, H = geo.size
    h = fill_depth
    if geo.kind == "prismatic":
        (cw, ch), (tw, th) = geo.chamfers
        if min(cw, ch, tw, th) < 0:
            return "chamfers", "chamfer widths and heights must be >= 0"
        if (cw > 0) != (ch > 0) or (tw > 0) != (th > 0):
            return "chamfers", "a chamfer needs both its width and its height > 0 (or both 0)"
        if cw > b / 2 + 1e-12 * b or tw > b / 2 + 1e-12 * b:
            return "chamfers", f"a chamfer is wider than half the breadth {b:g} m"
        if ch + th > H + 1e-12 * H:
            return "chamfers", f"the bottom and top chamfers ({ch:g} + {th:g} m) are taller than the tank ({H:g} m)"
        if abs(tw - b / 2) <= 1e-12 * b and h > H - th:
            return "fill_depth", "the liquid reaches the ridge where the top chamfers meet"
    elif geo.kind == "cylinder":
        if geo.axis not in AXES:
            return "axis", f"must be one of {AXES}, got {geo.axis!r}"
        if geo.axis != "z" and h >= H * (1 - 1e-9):
            return "fill_depth", "a horizontal cylinder's liquid needs a free surface below the top (fill_depth < height)"
        if geo.axis == "z" and min(mesh[0], mesh[1]) < 2:
            return "mesh", "a vertical cylinder needs at least 2 elements along x and y"
    for i, bf in enumerate(geo.baffles):
        where = f"baffles[{i}]"
        if geo.kind not in ("box", "prismatic"):
            return where, f"baffles go into box and prismatic tanks; give a {geo.kind} tank with baffles as a mesh"
        if bf.normal not in ("x", "y"):
            return f"{where}.normal", f'must be "x" or "y" (the plate stands across that axis), got {bf.normal!r}'
        if bf.mount not in ("bottom", "top"):
            return f"{where}.from", f'must be "bottom" or "top", got {bf.mount!r}'
        ext = a if bf.normal == "x" else b
        if not 0 < bf.at < ext:
            return f"{where}.position", f"must lie inside the tank (0 < position < {ext:g} m along {bf.normal}), got {bf.at:g}"
        if geo.kind == "prismatic" and bf.normal == "y":
            return f"{where}.normal", "a prismatic tank's baffles stand across its length (normal = \"x\")"
        if not 0 < bf.height <= H:
            return f"{where}.height", f"must be in (0, {H:g}] m, got {bf.height:g}"
        if bf.mount == "top" and H - bf.height >= h:
            return f"{where}.height", "this hanging baffle does not reach the liquid"
    return None


def liquid_volume(geo: TankGeometry, fill_depth: float) -> float:
    """The liquid's volume at rest, exactly for the shape (a mesh: its elements' volume)."""
    a, b, H = geo.size
    h = fill_depth
    if geo.kind == "prismatic":
        zs = np.unique(np.clip(np.array([0.0, geo.chamfers[0][1], H - geo.chamfers[1][1], h]), 0, h))
        w = [_prism_walls(geo, z) for z in zs]
        return float(a * sum(0.5 * ((w[i][1] - w[i][0]) + (w[i + 1][1] - w[i + 1][0])) * (zs[i + 1] - zs[i])
                             for i in range(len(zs) - 1)))
    if geo.kind == "cylinder":
        if geo.axis == "z":
            return float(np.pi * a * b / 4.0 * h)
        L = a if geo.axis == "x" else b
        B = b if geo.axis == "x" else a
        R = H / 2.0
        t = (h - R) / R                                  # circular segment of the unit circle, scaled to the ellipse
        seg = np.arccos(-t) - (-t) * np.sqrt(max(0.0, 1 - t * t))
        return float(L * seg * (B / 2.0) * R)
    if geo.kind == "mesh":
        m = read_mesh(geo.file)
        return float(hex_volumes(m[0], m[1]).sum())
    return float(a * b * h)


def hex_volumes(nodes, elements) -> np.ndarray:
    """(E,) volumes of hexahedra (2x2x2 Gauss)."""
    g = 1.0 / np.sqrt(3.0)
    out = np.zeros(len(elements))
    X = nodes[elements]
    for p in np.array([[sx, sy, sz] for sx in (-g, g) for sy in (-g, g) for sz in (-g, g)]):
        out += _jacobian_det(X, p)
    return out


def _jacobian_det(X, xi):
    dN = np.stack([HEX_CORNERS[:, k] * np.prod(np.where(np.arange(3) == k, 1.0, 1.0 + HEX_CORNERS * xi), axis=1)
                   for k in range(3)], axis=1) / 8.0
    J = np.einsum("eai,ak->eik", X, dN)
    return np.linalg.det(J)


# ------------------------------------------------------------------------------------------ the meshes

def tank_mesh(geo: TankGeometry, fill_depth: float, mesh) -> TankMesh:
    """The liquid at rest of a tank of this geometry filled to `fill_depth`, on `mesh` = (nx, ny, nz).
    Built once per geometry, fill and counts (`jaxslosh check` counts its unknowns, the build uses it);
    its arrays are shared: read them, do not write them."""
    return _tank_mesh(geo, float(fill_depth), tuple(int(m) for m in mesh))


@functools.lru_cache(maxsize=16)
def _tank_mesh(geo: TankGeometry, h: float, mesh: tuple) -> TankMesh:
    nx, ny, nz = mesh
    if geo.kind == "mesh":
        nodes, elements = read_mesh(geo.file)
        grid = _as_grid(nodes, elements)
        if grid is not None:
            nodes, elements, dims = grid
            return _finish(nodes, elements, dims, float(nodes[:, 2].max()))
        return _finish(nodes, elements, None, float(nodes[:, 2].max()))
    if geo.kind == "cylinder" and geo.axis == "z":
        nodes = _vertical_cylinder(geo.size, h, (nx, ny, nz))
        elements = box_elements(nx, ny, nz)
    elif geo.kind == "cylinder":
        nodes = _horizontal_cylinder(geo.size, h, (nx, ny, nz), geo.axis)
        elements = box_elements(nx, ny, nz)
    else:                                                  # box with baffles, prismatic
        nodes = _prismatic(geo, h, (nx, ny, nz))
        elements = box_elements(nx, ny, nz)
        pairs = _extra_pairs(geo, h, (nx, ny, nz), nodes)
        nodes, elements = _baffles(geo, h, (nx, ny, nz), nodes, elements)
        nodes, elements = _merge_coincident(nodes, elements, (nx + 1) * (ny + 1) * (nz + 1))
        return _finish(nodes, elements, (nx, ny, nz), h, pairs)
    nodes, elements = _merge_coincident(nodes, elements, (nx + 1) * (ny + 1) * (nz + 1))
    return _finish(nodes, elements, (nx, ny, nz), h)


def _breaks(lo, hi, points, n, where="mesh"):
    """n + 1 coordinates from lo to hi with every point of `points` (inside) among them: each
    interval between them gets a share of the n elements proportional to its length (at least one)."""
    cuts = sorted({float(p) for p in points if lo + 1e-9 * (hi - lo) < p < hi - 1e-9 * (hi - lo)})
    ends = [lo] + cuts + [hi]
    lengths = np.diff(ends)
    k = len(lengths)
    if n < k:
        raise ValueError(f"{where}: {n} elements cannot put a node at each of the shape's {k - 1} breaks "
                         f"({', '.join(f'{c:g}' for c in cuts)} m); use at least {k}")
    counts = np.maximum(1, np.floor(lengths / lengths.sum() * n).astype(int))
    while counts.sum() > n:
        counts[np.argmax(counts)] -= 1
    while counts.sum() < n:
        counts[np.argmax(lengths / counts)] += 1
    out = [lo]
    for (s, e), c in zip(zip(ends[:-1], ends[1:]), counts):
        out += list(np.linspace(s, e, c + 1)[1:])
    return np.array(out)


def _prism_walls(geo, z):
    """(y_lo, y_hi) of the section at height z (a box: (0, b))."""
    a, b, H = geo.size
    (cw, ch), (tw, th) = geo.chamfers if geo.kind == "prismatic" else ((0, 0), (0, 0))
    lo = 0.0
    if ch > 0 and z < ch:
        lo = cw * (1.0 - z / ch)
    if th > 0 and z > H - th:
        lo = max(lo, tw * (z - (H - th)) / th)
    return lo, b - lo


def _prismatic(geo, h, mesh):
    nx, ny, nz = mesh
    a, b, H = geo.size
    zb = []
    if geo.kind == "prismatic":
        zb = [geo.chamfers[0][1], H - geo.chamfers[1][1]]
    xb = [bf.at for bf in geo.baffles if bf.normal == "x"]
    yb = [bf.at for bf in geo.baffles if bf.normal == "y"]
    for bf in geo.baffles:
        zb.append(bf.height if bf.mount == "bottom" else H - bf.height)
    xs = _breaks(0.0, a, xb, nx, "mesh[0]")
    zs = _breaks(0.0, h, zb, nz, "mesh[2]")
    # across: a node on every y-baffle's plane (box tanks only), the same counts on every layer
    ys_rest = _breaks(0.0, b, yb, ny, "mesh[1]")
    g = grid_index(nx, ny, nz)
    lo_hi = np.array([_prism_walls(geo, z) for z in zs])       # (nz + 1, 2)
    lo, hi = lo_hi[g[:, 2], 0], lo_hi[g[:, 2], 1]
    t = ys_rest[g[:, 1]] / b
    if yb:                                                 # box: the walls are at 0 and b on every layer
        y = ys_rest[g[:, 1]]
    else:
        y = lo + t * (hi - lo)
    return np.stack([xs[g[:, 0]], y, zs[g[:, 2]]], axis=1)


def _vertical_cylinder(size, h, mesh):
    """The x-y disk (ellipse) from the square by the elliptical grid mapping, layers even in z."""
    nx, ny, nz = mesh
    a, b, _ = size
    g = grid_index(nx, ny, nz)
    u = 2.0 * g[:, 0] / nx - 1.0
    v = 2.0 * g[:, 1] / ny - 1.0
    X = u * np.sqrt(1.0 - 0.5 * v * v)
    Y = v * np.sqrt(1.0 - 0.5 * u * u)
    return np.stack([a / 2 * (1 + X), b / 2 * (1 + Y), h * g[:, 2] / nz], axis=1)


def _horizontal_cylinder(size, h, mesh, axis):
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


def _baffles(geo, h, mesh, nodes, elements):
    """Double the nodes on each plate (below its free edge), the copies for the elements on its far side."""
    nx, ny, nz = mesh
    if not geo.baffles:
        return nodes, elements
    g = grid_index(nx, ny, nz)
    H = geo.size[2]
    ei = np.stack(np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"), -1).reshape(-1, 3)
    nodes = list(nodes)
    elements = elements.copy()
    scale = max(geo.size)
    for bf in geo.baffles:
        ax = 0 if bf.normal == "x" else 1
        coord = np.asarray(nodes)[:len(g), ax]
        z = np.asarray(nodes)[:len(g), 2]
        if bf.mount == "bottom":
            on = (np.abs(coord - bf.at) < 1e-9 * scale) & (z < bf.height - 1e-9 * scale)
        else:
            on = (np.abs(coord - bf.at) < 1e-9 * scale) & (z > H - bf.height + 1e-9 * scale)
        idx = np.flatnonzero(on)
        plane = g[idx[0], ax] if idx.size else None
        copy = {}
        for n in idx:
            copy[n] = len(nodes)
            nodes.append(np.asarray(nodes[n]))
        if plane is None:
            continue
        far = np.flatnonzero(ei[:, ax] == plane)
        for e in far:
            elements[e] = [copy.get(n, n) for n in elements[e]]
    return np.asarray(nodes), elements


def _merge_coincident(nodes, elements, n_grid=None):
    """Merge nodes at the same place (a V bottom's collapsed row); None merged: unchanged. Nodes from
    `n_grid` on (a baffle's second side) are never merged with the grid's."""
    scale = max(float(np.ptp(nodes, axis=0).max()), 1e-300)
    key = np.round(nodes / scale, 10)
    if n_grid is not None:
        key = np.column_stack([key, np.arange(len(nodes)) >= n_grid])
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    if len(first) == len(nodes):
        return nodes, elements
    inv = inv.reshape(-1)
    # keep the first occurrence's numbering order
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    new = rank[inv]
    return nodes[np.sort(first)], new[elements]


def read_mesh(path):
    """(nodes, elements) of the hexahedra of a mesh file (meshio), checked and oriented positively
    (fem/meshfile.py); shared arrays: read only."""
    m = read_mesh_file(path)
    return m.nodes, m.elements


def grid_counts(nodes, elements):
    """(nx, ny, nz) if the mesh is a box grid, else None."""
    g = _as_grid(nodes, elements)
    return None if g is None else tuple(int(d) for d in g[2])


def _as_grid(nodes, elements):
    """The mesh renumbered as a box grid (nodes, elements, (nx, ny, nz)) if it is one, else None."""
    scale = float(np.ptp(nodes, axis=0).max())
    axes = [np.unique(np.round(nodes[:, k] / scale, 9)) for k in range(3)]
    dims = tuple(len(x) - 1 for x in axes)
    if np.prod([d + 1 for d in dims]) != len(nodes) or len(elements) != np.prod(dims) or min(dims) < 1:
        return None
    ijk = np.stack([np.searchsorted(axes[k], np.round(nodes[:, k] / scale, 9)) for k in range(3)], axis=1)
    nx, ny, nz = dims
    index = (ijk[:, 0] * (ny + 1) + ijk[:, 1]) * (nz + 1) + ijk[:, 2]
    if len(np.unique(index)) != len(nodes):
        return None
    box = box_elements(nx, ny, nz)
    mine = np.sort(index[elements], axis=1)
    if not np.array_equal(np.unique(mine, axis=0), np.unique(np.sort(box, axis=1), axis=0)):
        return None
    out = np.empty_like(nodes)
    out[index] = nodes
    return out, box, dims


def _finish(nodes, elements, grid, depth, pairs=()) -> TankMesh:
    bd = boundary(nodes, elements, depth)
    for a in (nodes, elements, bd.free):            # cached and shared (tank_mesh): read only
        a.flags.writeable = False
    return TankMesh(nodes, elements, bd.top_faces, bd.wall_faces, bd.free, bd.frames, grid, depth, bd.flat,
                    tuple(pairs))


def _extra_pairs(geo, h, mesh, nodes):
    """The box scheme's count of constraints, kept (fem/liquid.py `_rotation_pairs`): the one-point
    divergence and the axial curl leave exactly as many free fields as the box has sloshing modes,
    so every wall constraint beyond the box's removes a whole mode (a pinned line of nodes inside
    the liquid locks it: measured, a 5 m tank's first mode went from 2.29 to 3.43 rad/s). Each line
    of nodes that a shape pins once more than the box does -- the foot of a standing baffle, the kink
    where a bottom (hopper) chamfer meets the vertical wall -- gets, for each element along it, the
    curl rows about the line's direction of the two elements across it replaced by their difference
    (one constraint less), as `_rotation_pairs` does for odd rows. (The kink of a top chamfer needs
    none: with one there, a spurious mode enters below the first; tests/fem/test_shapes.py.)"""
    nx, ny, nz = mesh
    eid = lambda i, j, k: (i * ny + j) * nz + k           # noqa: E731
    pairs = []
    for bf in geo.baffles:
        if bf.mount != "bottom":
            continue                                   # a hanging plate pins nothing more than it doubles
        ax = 0 if bf.normal == "x" else 1
        coords = nodes[: (nx + 1) * (ny + 1) * (nz + 1)].reshape(nx + 1, ny + 1, nz + 1, 3)
        line = coords[:, 0, 0, 0] if ax == 0 else coords[0, :, 0, 1]
        p = int(np.argmin(np.abs(line - bf.at)))
        if ax == 0:
            pairs += [(eid(p - 1, j, 0), eid(p, j, 0), 1) for j in range(ny)]
        else:
            pairs += [(eid(i, p - 1, 0), eid(i, p, 0), 0) for i in range(nx)]
    if geo.kind == "prismatic":
        a, b, H = geo.size
        (cw, ch), (tw, th) = geo.chamfers
        zs = nodes[: nz + 1, 2]
        kinks = [ch] if 0 < cw < b / 2 * (1 - 1e-12) and ch < h else []
        for z in kinks:
            k = int(np.argmin(np.abs(zs - z)))
            if 0 < k < nz:
                pairs += [(eid(i, j, k - 1), eid(i, j, k), 0) for i in range(nx) for j in (0, ny - 1)]
    return pairs


def box_equivalent(geo: TankGeometry, fill_depth: float):
    """The mesh counts of a `"mesh"` tank whose file is a uniform box grid over the tank's whole
    footprint from its min corner, filled to `fill_depth` (it then builds as the box); else None."""
    if geo.kind != "mesh":
        return None
    nodes, elements = read_mesh(geo.file)
    grid = _as_grid(nodes, elements)
    if grid is None:
        return None
    nodes, _, dims = grid
    a, b, _ = geo.size
    ref = grid_nodes((a, b, fill_depth), dims)
    if np.abs(nodes - ref).max() > 1e-9 * max(a, b, fill_depth):
        return None
    return dims


def free_count(geo: TankGeometry, fill_depth: float, mesh) -> int:
    """The liquid's unknowns in a tank of this shape."""
    return int(tank_mesh(geo, fill_depth, mesh).free.sum())
