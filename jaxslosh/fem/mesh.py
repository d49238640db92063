"""Structured hexahedral meshes of boxes: the reference hexahedron, node and element numbering.

Every block of the package (a tank's liquid, a structure, the walls of an elastic tank) is meshed
here, so the numbering is the same everywhere:

* node (i, j, k) of an (nx, ny, nz) grid has index ``(i*(ny+1) + j)*(nz+1) + k``;
* elements use the standard hex8 ordering: the bottom face counter-clockwise seen from above,
  then the top face (`HEX_CORNERS`, reference coordinates in [-1, 1]^3);
* degrees of freedom are node-major: dof ``3*n + c`` is component c of node n.

NumPy only (the scene loader uses it to check that structures' meshes meet).
"""
from __future__ import annotations

import numpy as np

#: the liquid's element forms on these meshes, here below the scene loader that reads them from
#: `tanks.fluid.element`: the nodal forms (liquid/nodal/element.py) and the face-normal ones
#: (liquid/face/element.py)
ELEMENT_FORMS = ("stabilized", "paper")
FACE_FORMS = ("rt",)
#: reference coordinates of the eight corners of the hex8 element
HEX_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                        [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
#: the 2-point Gauss abscissa and the 2 x 2 x 2 rule (weights 1)
GAUSS_1D = 1.0 / np.sqrt(3.0)
GAUSS8 = np.array([[sx, sy, sz] for sx in (-GAUSS_1D, GAUSS_1D) for sy in (-GAUSS_1D, GAUSS_1D)
                   for sz in (-GAUSS_1D, GAUSS_1D)])


def grid_index(nx: int, ny: int, nz: int) -> np.ndarray:
    """(N, 3) integer (i, j, k) of every node of the grid, in node order."""
    gi, gj, gk = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), np.arange(nz + 1), indexing="ij")
    return np.stack([gi.ravel(), gj.ravel(), gk.ravel()], axis=1)


def grid_nodes(size, mesh) -> np.ndarray:
    """(N, 3) node coordinates of a uniform grid of the box [0, size_x] x [0, size_y] x [0, size_z]."""
    axes = [np.linspace(0.0, float(s), int(m) + 1) for s, m in zip(size, mesh)]
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    return np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)


def box_elements(nx: int, ny: int, nz: int) -> np.ndarray:
    """(E, 8) node indices of the hexahedra, element (i, j, k) at row (i*ny + j)*nz + k."""
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    corner = ((HEX_CORNERS + 1) / 2).astype(int)
    ii = i.reshape(-1, 1) + corner[:, 0]
    jj = j.reshape(-1, 1) + corner[:, 1]
    kk = k.reshape(-1, 1) + corner[:, 2]
    return (ii * (ny + 1) + jj) * (nz + 1) + kk


def box_mesh(size, mesh):
    """Nodes (N, 3) from the block's min corner and hex8 elements (E, 8) of a uniform box mesh."""
    nx, ny, nz = (int(m) for m in mesh)
    return grid_nodes(size, (nx, ny, nz)), box_elements(nx, ny, nz)


def face_nodes(nodes, size, face: str, tol=1e-9) -> np.ndarray:
    """Indices of the nodes on a face of the block ("x-" is x = 0, "z+" is z = size_z, ...)."""
    axis = "xyz".index(face[0])
    target = 0.0 if face[1] == "-" else float(size[axis])
    return np.flatnonzero(np.abs(nodes[:, axis] - target) <= tol * max(size))


def count_nodes(mesh) -> int:
    nx, ny, nz = mesh
    return (nx + 1) * (ny + 1) * (nz + 1)


def box_gauss_points(nodes, elements, density, slot_of):
    """Box hexahedra as particles at their 2 x 2 x 2 Gauss points, which carry their consistent
    (trilinear) mass exactly: (x (G, 3), m (G,), N (G, 8) the corners' shape values, slots (G, 8, 3)
    the unknown of each corner dof, `slot_of` (3 N,) by node-major dof)."""
    X = nodes[elements]                                                   # (E, 8, 3) boxes
    h = X.max(axis=1) - X.min(axis=1)
    N = np.prod(1.0 + HEX_CORNERS[None] * GAUSS8[:, None, :], axis=2) / 8.0       # (P, 8)
    x = np.einsum("pa,eai->epi", N, X).reshape(-1, 3)
    m = np.repeat(density * np.prod(h, axis=1) / 8.0, 8)
    dofs = 3 * elements[:, :, None] + np.arange(3)                        # (E, 8, 3)
    slots = np.repeat(np.asarray(slot_of)[dofs][:, None], 8, axis=1).reshape(-1, 8, 3)
    return x, m, np.tile(N, (len(X), 1)), slots
