"""The face-normal liquid's faces (liquid/face/element.py): the hexahedra's faces, each once, with the
signs that make the unknown each element's outward flux, and which faces are unknown (the interior
ones and the free surface's; walls, plates and collapsed faces are held)."""
from __future__ import annotations

import numpy as np

from ...fem.slip import HEX_FACES


def face_topology(elements):
    """(faces (F, 4), element_faces (E, 6), signs (E, 6), boundary (F,) bool, collapsed (F,) bool)."""
    E = len(elements)
    local = elements[:, HEX_FACES].reshape(-1, 4)
    key = np.sort(local, axis=1)
    uniq, first, inv, counts = np.unique(key, axis=0, return_index=True, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    faces = local[first]
    collapsed = np.array([len(set(f)) < 3 for f in uniq])
    owner = np.repeat(np.arange(E), 6)
    # the unknown is the outward flux of the face's first element (lowest index) -- np.unique's
    # `first` is the first occurrence, which is that element's
    signs = np.where(owner == owner[first][inv], 1.0, -1.0).reshape(E, 6)
    if np.any((counts > 2) & ~collapsed):
        raise ValueError("the mesh has a face shared by more than two elements")
    return faces, inv.reshape(E, 6), signs, counts == 1, collapsed


def free_faces(nodes, faces, on_boundary, collapsed, depth):
    """(free (F,) bool, top (T,)): the interior faces and the free surface's."""
    scale = float(np.ptp(nodes, axis=0).max())
    flat_top = np.all(np.abs(nodes[faces][:, :, 2] - depth) < 1e-9 * scale, axis=1)
    # a top face must open upwards: its element lies below it
    top = np.flatnonzero(on_boundary & flat_top & ~collapsed)
    free = ~on_boundary & ~collapsed
    free[top] = True
    return free, top


def free_face_count(nodes, elements, depth) -> int:
    """The unknowns of the face-normal liquid on this mesh (its free faces), from the topology only."""
    faces, _, _, on_boundary, collapsed = face_topology(np.asarray(elements, dtype=int))
    return int(free_faces(np.asarray(nodes, dtype=float), faces, on_boundary, collapsed, depth)[0].sum())
