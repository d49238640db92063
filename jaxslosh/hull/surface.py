"""The hull as a closed triangulated surface for the large-angle hydrostatics (docs/guide/large-angles.md):
a box with its deck, or a closed mesh file, as triangles (n, 3, 3) in the vessel frame (COG at
the origin), outward normals (counter-clockwise seen from outside).

A mesh is validated when the scene is loaded (`read_hull_mesh`): every edge shared by exactly two
faces, traversed once each way (consistent normals), and a positive enclosed volume (outward
normals). The large-angle restoring integrates over the closed surface, so a hull without a deck
(the wetted part Capytaine meshes) is refused with that fault named.
"""
from __future__ import annotations

import functools
import os

import numpy as np



class HullMeshError(ValueError):
    """A hull mesh that cannot serve the large-angle hydrostatics: the message names the fault."""


def enclosed_volume(tris):
    """1/3 of the surface integral of x . n: the volume a closed surface with outward normals holds."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    return float(np.sum(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0)


def mesh_triangles(points, cells):
    """Triangles (n, 3, 3) of meshio cell blocks: triangles as they are, quads split along a diagonal."""
    tris = []
    for kind, idx in cells:
        idx = np.asarray(idx)
        if kind == "triangle":
            tris.append(idx)
        elif kind == "quad":
            tris += [idx[:, [0, 1, 2]], idx[:, [0, 2, 3]]]
    if not tris:
        return np.zeros((0, 3), dtype=int)
    return np.concatenate(tris)


def check_closed(points, faces, name: str):
    """HullMeshError naming the fault when the triangles `faces` (indices into points) do not bound
    a volume with outward normals: open edges (a hull without a deck named as such), inconsistent
    orientation, a non-positive enclosed volume."""
    if len(faces) == 0:
        raise HullMeshError(f"{name}: holds no triangles or quadrilaterals")
    # merge coincident points: a mesh written face by face repeats its vertices
    scale = float(np.ptp(points, axis=0).max()) or 1.0
    key = np.round(points / (1e-9 * scale)).astype(np.int64)
    _, inverse = np.unique(key, axis=0, return_inverse=True)
    f = inverse.reshape(-1)[faces]
    degenerate = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    f = f[~degenerate]
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    undirected = np.sort(directed, axis=1)
    uniq, count = np.unique(undirected, axis=0, return_counts=True)
    if (count != 2).any():
        bad = uniq[count != 2]
        merged = np.zeros((inverse.max() + 1, 3))
        merged[inverse.reshape(-1)] = points
        open_edges = bad[count[count != 2] == 1]
        if len(open_edges) and len(open_edges) == len(bad):
            ez = merged[open_edges][:, :, 2]
            top = merged[:, 2].max()
            if np.allclose(ez, top, atol=1e-6 * scale) or np.allclose(ez, ez.mean(), atol=1e-6 * scale):
                raise HullMeshError(
                    f"{name}: not closed at the deck: {len(open_edges)} edges bound an opening at "
                    f"z = {ez.mean():.6g} (a hull for large angles needs its deck, to be closed)")
            p = merged[open_edges[0]]
            raise HullMeshError(f"{name}: open mesh: {len(open_edges)} edges belong to one face only "
                                f"(the first from {np.round(p[0], 6).tolist()} to {np.round(p[1], 6).tolist()})")
        p = merged[bad[0]]
        raise HullMeshError(f"{name}: not a closed surface: {len(bad)} edges are shared by more or fewer than two "
                            f"faces (the first from {np.round(p[0], 6).tolist()} to {np.round(p[1], 6).tolist()})")
    _, dcount = np.unique(directed, axis=0, return_counts=True)
    if (dcount > 1).any():
        raise HullMeshError(f"{name}: inconsistent normals: {int((dcount > 1).sum())} edges are traversed the same "
                            f"way by both their faces (neighbouring faces must be ordered alike)")
    tris = points[faces[~degenerate]]
    V = enclosed_volume(tris)
    if V <= 0:
        raise HullMeshError(f"{name}: inverted normals: the faces enclose a negative volume ({V:.6g} m^3); "
                            f"they must point out of the hull (counter-clockwise seen from outside)")
    return tris


def read_hull_mesh(path: str, cog, label: str = ""):
    """The closed hull of a mesh file (any format meshio reads), as triangles (n, 3, 3) about the
    COG `cog` (in the file's coordinates, waterline at z = 0). HullMeshError names the file and the fault."""
    import meshio

    name = label or path
    if not os.path.exists(path):
        raise HullMeshError(f"{name}: no such file")
    try:
        m = meshio.read(path)
    except Exception as e:     # meshio raises many kinds for a file it cannot read
        raise HullMeshError(f"{name}: cannot be read as a mesh ({type(e).__name__}: {e})") from None
    points = np.asarray(m.points, dtype=float)
    if points.shape[1] == 2:
        raise HullMeshError(f"{name}: a 2-D mesh; the hull needs 3-D coordinates")
    faces = mesh_triangles(points, [(c.type, c.data) for c in m.cells])
    tris = check_closed(points[:, :3], faces, name)
    return tris - np.asarray(cog, dtype=float)


def write_hull_mesh(path: str, tris) -> None:
    """Write triangles (n, 3, 3) as a mesh file (format by its extension), vertices merged."""
    import meshio

    pts = tris.reshape(-1, 3)
    key = np.round(pts * 1e9).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    meshio.write(path, meshio.Mesh(pts[first], [("triangle", inverse.reshape(-1, 3))]))


@functools.lru_cache(maxsize=8)
def _mesh_cached(path: str, mtime: float, cog: tuple, label: str):
    tris = read_hull_mesh(path, cog, label)
    tris.setflags(write=False)
    return tris


def hull_mesh_file(path: str, cog, label: str):
    """The closed surface of a hull mesh file in the vessel frame (the COG `cog` of the file's
    coordinates at the origin), read once per file version; HullMeshError names `label`."""
    try:
        mtime = os.path.getmtime(path)
    except OSError:
        raise HullMeshError(f"{label}: no such file") from None
    return _mesh_cached(path, mtime, tuple(cog), label)


def prism_hull(section, length, nx=1, nz=1):
    """A closed prism along x (length centred on x = 0) of a convex section polygon `section` (k, 2):
    (y, z) counter-clockwise in the (y, z) plane; `nx` cells along the length, each side of the
    section cut into `nz` cells (`loft_surface` with one section)."""
    x = np.linspace(-0.5 * length, 0.5 * length, nx + 1)
    return loft_surface(x, np.broadcast_to(refine_outline(section, nz), (nx + 1,) + refine_outline(section, nz).shape))


def refine_outline(section, n):
    """A polygon (k, 2) with each side cut into n pieces: (k n, 2)."""
    S = np.asarray(section, dtype=float)
    return np.array([S[i] + (S[(i + 1) % len(S)] - S[i]) * s for i in range(len(S)) for s in np.arange(n) / n])


def loft_surface(x, sections):
    """A closed hull lofted through stations x (s,) ascending, with the convex sections (s, m, 2)
    ((y, z), counter-clockwise in the (y, z) plane, the same number of points at each station):
    quadrilaterals between stations split into triangles, the end faces fanned from their
    centroids; outward normals. Flared or V-shaped hulls for tests, examples and benchmarks."""
    x = np.asarray(x, dtype=float)
    P = np.asarray(sections, dtype=float)
    s, m = P.shape[:2]
    Q = np.concatenate([np.broadcast_to(x[:, None, None], (s, m, 1)), P], axis=2)    # (s, m, 3)
    j = np.arange(m)
    k = (j + 1) % m
    a, b, c, d = Q[:-1, j], Q[:-1, k], Q[1:, k], Q[1:, j]
    sides = np.concatenate([np.stack([a, c, d], axis=-2), np.stack([a, b, c], axis=-2)]).reshape(-1, 3, 3)
    ends = []
    for i, sign in ((0, -1), (s - 1, 1)):
        o = np.broadcast_to(Q[i].mean(axis=0), (m, 3))
        tri = np.stack([o, Q[i, j], Q[i, k]], axis=1)
        ends.append(tri if sign > 0 else tri[:, ::-1])
    return np.concatenate([sides] + ends)
