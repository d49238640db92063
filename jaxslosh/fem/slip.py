"""Slip walls of any shape: the boundary faces of a hexahedral mesh, the wall normals at each node and
the node frames that make the liquid's unknowns tangential; turning matrices onto those frames; the
surface bending measure of any quadrilateral free surface.

Walls constrain the liquid's normal displacement only. Each wall node takes the normals of the
wall faces round it; faces within `FEATURE_ANGLE` of each other count as one smooth wall (their
area-weighted mean normal: a curved wall), more distinct ones are an edge or a corner (two or three
normals); the two faces of a plate meeting at its edge cancel (the liquid goes round it). A node's
frame is an orthonormal basis whose first columns span its normals; the node's unknowns are its
displacement components along the others. Nodes whose normals are coordinate axes keep the
identity frame (then the box's own numbering of unknowns results).

NumPy and SciPy only.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np
import scipy.sparse as sp

#: wall faces whose normals differ by less than this are one smooth (curved) wall at a node
FEATURE_ANGLE = 30.0
#: hex8 faces, outward for a positively oriented element: bottom, top, y-, x+, y+, x-
HEX_FACES = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])


class Boundary(NamedTuple):
    top_faces: np.ndarray        # (F, 4) free-surface faces, counter-clockwise seen from above
    wall_faces: np.ndarray       # (W, 4) wetted wall faces, outward (both faces of a plate included)
    free: np.ndarray             # (N, 3) bool: the node's unknown components in its frame
    frames: Optional[np.ndarray]  # (N, 3, 3) columns: the node's axes; None: every frame is the identity
    flat: np.ndarray             # (E,) bool: elements with two faces on one smooth wall (see node_frames)


def boundary_faces(elements):
    """(faces (B, 4) outward, element of each) of the faces that belong to one element only (faces
    with a repeated node, a collapsed element's, are left out)."""
    F = elements[:, HEX_FACES].reshape(-1, 4)
    owner = np.repeat(np.arange(len(elements)), 6)
    distinct = np.array([len(set(f)) == 4 for f in F])
    F, owner = F[distinct], owner[distinct]
    key = np.sort(F, axis=1)
    _, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    once = counts[inv.reshape(-1)] == 1
    return F[once], owner[once]


def face_normals(nodes, faces):
    """(unit normals (B, 3), areas (B,)) of quadrilateral faces (from their diagonals)."""
    X = nodes[faces]
    n = 0.5 * np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
    area = np.linalg.norm(n, axis=1)
    return n / np.maximum(area, 1e-300)[:, None], area


def boundary(nodes, elements, depth) -> Boundary:
    """The free surface (faces on the plane z = depth facing up) and the walls (every other boundary
    face) of a mesh of the liquid at rest, and the wall nodes' frames."""
    faces, owner = boundary_faces(elements)
    normal, area = face_normals(nodes, faces)
    centre = nodes[elements[owner]].mean(axis=1)
    outward = np.einsum("ij,ij->i", normal, nodes[faces].mean(axis=1) - centre) >= 0
    normal = np.where(outward[:, None], normal, -normal)
    faces = np.where(outward[:, None], faces, faces[:, ::-1])
    scale = float(np.ptp(nodes, axis=0).max())
    on_top = np.all(np.abs(nodes[faces, 2] - depth) <= 1e-9 * scale, axis=1) & (normal[:, 2] > 0.99)
    top, walls = faces[on_top], faces[~on_top & (area > 1e-14 * scale ** 2)]
    wn, wa = normal[~on_top & (area > 1e-14 * scale ** 2)], area[~on_top & (area > 1e-14 * scale ** 2)]
    keep = ~on_top & (area > 1e-14 * scale ** 2)
    free, frames, flat = node_frames(len(nodes), walls, wn, wa, owner[keep], len(elements))
    return Boundary(top, walls, free, frames, flat)


def node_frames(n_nodes, faces, normals, areas, owners, n_elements):
    """(free (N, 3), frames (N, 3, 3) or None) from the wall faces round each node (module docstring).

    Returns also `flat` (E,) bool: the elements with two faces on one smooth wall at a node (a mapped
    mesh's corner on a curved wall), whose node there slides with no energy of the one-point
    element (liquid_element.FLAT_CORNER_PENALTY holds it)."""
    per = [[] for _ in range(n_nodes)]
    for f, nrm, a, e in zip(faces, normals, areas, owners):
        for node in f:
            per[node].append((a / 4.0, nrm, e))
    cos_feature = np.cos(np.radians(FEATURE_ANGLE))
    free = np.ones((n_nodes, 3), dtype=bool)
    flat = np.zeros(n_elements, dtype=bool)
    frames = np.tile(np.eye(3), (n_nodes, 1, 1))
    rotated = False
    for node, items in enumerate(per):
        if not items:
            continue
        clusters, owned = [], []
        for w, nrm, e in sorted(items, key=lambda it: -it[0]):
            best = max(range(len(clusters)), key=lambda c: nrm @ _unit(clusters[c]), default=None)
            if best is not None and nrm @ _unit(clusters[best]) > cos_feature:
                clusters[best] = clusters[best] + w * nrm
                if e in owned[best]:
                    flat[e] = True
                owned[best].add(e)
            else:
                clusters.append(w * nrm)
                owned.append({e})
        units = [_unit(c) for c in clusters]
        weights = [np.linalg.norm(c) for c in clusters]
        cancel = set()
        for i in range(len(units)):
            for j in range(i + 1, len(units)):
                if units[i] @ units[j] < -0.5:        # the two faces of a plate at its edge
                    cancel |= {i, j}
        basis = []
        for i in sorted(range(len(units)), key=lambda i: -weights[i]):
            if i in cancel:
                continue
            v = units[i] - sum((units[i] @ e) * e for e in basis)
            if np.linalg.norm(v) > 0.3 and len(basis) < 3:
                basis.append(v / np.linalg.norm(v))
        if not basis:
            continue
        axis_aligned = all(np.isclose(np.abs(e).max(), 1.0, atol=1e-9) for e in basis)
        if axis_aligned:
            for e in basis:
                free[node, int(np.argmax(np.abs(e)))] = False
            continue
        B = np.array(basis).T                               # (3, r)
        U, _, _ = np.linalg.svd(np.concatenate([B, np.zeros((3, 3 - B.shape[1]))], axis=1))
        comp = U[:, B.shape[1]:]                            # the orthogonal complement
        comp = comp - B @ (B.T @ comp)
        Q = np.concatenate([B, np.linalg.qr(comp)[0][:, :3 - B.shape[1]] if comp.size else comp], axis=1)
        frames[node] = Q
        free[node, :B.shape[1]] = False
        rotated = True
    return free, (frames if rotated else None), flat


def _unit(v):
    return v / max(float(np.linalg.norm(v)), 1e-300)


def rotate_matrix(xp, A, frames):
    """R^T A R for the block-diagonal R of the nodes' frames (A (3N, 3N): NumPy, JAX or SciPy sparse)."""
    n = frames.shape[0]
    if hasattr(A, "tocsr"):
        R = sp.block_diag(list(frames), format="csr")
        return (R.T @ A @ R).tocsr()
    if xp is np:
        R = sp.block_diag(list(frames), format="csr")
        return np.asarray((R.T @ (R.T @ np.asarray(A).T).T))
    A4 = A.reshape(n, 3, n, 3)
    return xp.einsum("iap,iajb,jbq->ipjq", frames, A4, frames).reshape(3 * n, 3 * n)


def rotate_rows(xp, C, frames):
    """R^T C for C (3N, k)."""
    n = frames.shape[0]
    C3 = C.reshape(n, 3, -1)
    return xp.einsum("iap,iak->ipk", frames, C3).reshape(3 * n, -1)


def surface_jump_pattern(nodes, faces):
    """COO (rows, cols, values) of sum over the free surface's inner edges of A (s_AB)^2, with s_AB
    the change of the vertical displacement's slope between the two faces A, B of the edge along the
    line joining their centres, times its length, and A their mean area: the box's second
    differences (`surface_bending_pattern`) for any quadrilateral surface. It is zero on every
    linear field, whatever the faces' shapes, so a tilt stays exact."""
    F = len(faces)
    if F < 2:
        z = np.zeros(0, dtype=int)
        return z, z, np.zeros(0)
    Y = nodes[faces][:, :, :2]                                   # (F, 4, 2)
    dN = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float) / 4.0
    J = np.einsum("fai,ak->fik", Y, dN)                            # (F, 2, 2)
    G = np.einsum("ak,fki->fai", dN, np.linalg.inv(J))             # (F, 4, 2) mean gradient of each node's shape
    area = 4.0 * np.abs(np.linalg.det(J))
    centre = Y.mean(axis=1)
    edges = np.concatenate([np.sort(faces[:, [i, (i + 1) % 4]], axis=1) for i in range(4)])
    owner = np.tile(np.arange(F), 4)
    _, inv, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    order = np.argsort(inv, kind="stable")
    shared = counts[inv[order]] == 2
    pairs = owner[order][shared].reshape(-1, 2)
    fa, fb = pairs[:, 0], pairs[:, 1]
    d = centre[fb] - centre[fa]                                   # (P, 2)
    ca = -np.einsum("pai,pi->pa", G[fa], d)
    cb = np.einsum("pai,pi->pa", G[fb], d)
    P = len(pairs)
    rows = np.repeat(np.arange(P), 8)
    cols = (3 * np.concatenate([faces[fa], faces[fb]], axis=1) + 2).reshape(-1)
    D = sp.csr_matrix((np.concatenate([ca, cb], axis=1).reshape(-1), (rows, cols)), shape=(P, 3 * len(nodes)))
    w = 0.5 * (area[fa] + area[fb])
    B = (D.T @ sp.diags(w) @ D).tocoo()
    return B.row.astype(int), B.col.astype(int), B.data
