"""The liquid at rest of a tank as a hexahedral mesh (`TankMesh`), and what every shape's mesher
(jaxslosh/geometry) shares: the volume of hexahedra, breaks of an edge at a shape's kinks, merged
coincident nodes, a mesh file read and recognised as a box grid, and the free surface and slip walls
found on the finished mesh (fem/slip.py).

The shapes themselves (box, prismatic, cylinder, mesh file) are jaxslosh/geometry's classes: each
meshes itself with these. NumPy only (the scene loader checks shapes and computes their volume).
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np

from .mesh import HEX_CORNERS, box_elements
from .meshfile import read_mesh_file
from .slip import boundary


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


def breaks(lo, hi, points, n, where="mesh", least=1):
    """n + 1 coordinates from lo to hi with every point of `points` (inside) among them: each
    interval between them gets a share of the n elements proportional to its length (at least
    `least`, one where n is too small for that)."""
    cuts = sorted({float(p) for p in points if lo + 1e-9 * (hi - lo) < p < hi - 1e-9 * (hi - lo)})
    ends = [lo] + cuts + [hi]
    lengths = np.diff(ends)
    k = len(lengths)
    if n < k:
        raise ValueError(f"{where}: {n} elements cannot put a node at each of the shape's {k - 1} breaks "
                         f"({', '.join(f'{c:g}' for c in cuts)} m); use at least {k}")
    least = least if n >= least * k else 1
    counts = np.maximum(least, np.floor(lengths / lengths.sum() * n).astype(int))
    while counts.sum() > n:
        counts[np.argmax(np.where(counts > least, counts, 0))] -= 1
    while counts.sum() < n:
        counts[np.argmax(lengths / counts)] += 1
    out = [lo]
    for (s, e), c in zip(zip(ends[:-1], ends[1:]), counts):
        out += list(np.linspace(s, e, c + 1)[1:])
    return np.array(out)


#: the surface layers' thickness scale over the free surface's width (`surface_layers`)
SURFACE_GRADING = 0.1
#: the weight of the band under the surface where its walls slope (`surface_layers`)
SLOPED_SURFACE_BAND = 2.0
#: the fewest layers of a band between two kinks, or between a kink and the surface or the bottom
BAND_LAYERS = 2


def surface_layers(h, points, n, width, sloped=False, where="mesh[2]"):
    """n + 1 heights from 0 to the surface h with every kink of `points` (inside) among them, the
    layers thinner toward the surface: for the face-normal element (liquid/face/element.py), whose
    horizontal displacements are constant through a layer, while a sloshing mode decays from the
    surface down (as exp(-k d)). The layers are spread by the density 1 / (1 + d / l) at the depth
    d, l = SURFACE_GRADING x the surface's `width` (so they thicken linearly with depth); each band
    between kinks takes its share of that density, the band under the surface twice it where its
    walls slope (a surface in the top chamfers: RT0's error on that band's trapezoids is several
    times a box's on layers of the same thickness), and at least BAND_LAYERS layers (one where n is
    too small for that). Proportional layers leave one row of trapezoids under a surface in the top
    chamfers, and the modes low (docs/design/liquid-element.md, "Layers")."""
    cuts = sorted({float(p) for p in points if 1e-9 * h < p < h * (1 - 1e-9)})
    ends = np.array([0.0] + cuts + [h])
    k = len(ends) - 1
    if n < k:
        raise ValueError(f"{where}: {n} elements cannot put a node at each of the shape's {k - 1} breaks "
                         f"({', '.join(f'{c:g}' for c in cuts)} m); use at least {k}")
    ell = SURFACE_GRADING * width

    def depth_count(z):                   # the layers' density integrated from the surface down to z
        return ell * np.log1p((h - z) / ell)

    share = -np.diff(depth_count(ends))
    if sloped:
        share[-1] *= SLOPED_SURFACE_BAND
    share = share / share.sum() * n
    least = np.full(k, BAND_LAYERS if n >= BAND_LAYERS * k else 1)
    counts = np.maximum(least, np.floor(share).astype(int))
    while counts.sum() > n:               # borrow from the band with the most layers for its share
        counts[np.argmin(np.where(counts > least, share / counts, np.inf))] -= 1
    while counts.sum() < n:
        counts[np.argmax(share / counts)] += 1
    out = [0.0]
    for s, e, c in zip(ends[:-1], ends[1:], counts):
        u = np.linspace(depth_count(s), depth_count(e), c + 1)[1:]
        out += list(h - ell * np.expm1(u / ell))
    out[-1] = h
    return np.array(out)


def merge_coincident(nodes, elements, n_grid=None):
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
    g = as_grid(nodes, elements)
    return None if g is None else tuple(int(d) for d in g[2])


def as_grid(nodes, elements):
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


def finish(nodes, elements, grid, depth, pairs=()) -> TankMesh:
    bd = boundary(nodes, elements, depth)
    for a in (nodes, elements, bd.free):            # cached and shared (tank_mesh): read only
        a.flags.writeable = False
    return TankMesh(nodes, elements, bd.top_faces, bd.wall_faces, bd.free, bd.frames, grid, depth, bd.flat,
                    tuple(pairs))
