"""What a tank's liquid will cost in memory before anything is built, the pieces the models share
(each final liquid's `tank_bytes`, liquid/base.py, asked by assemble/cost.py): the element arrays of
the assembly, the nodal solver's blocks (dense inverses, or the sparse matrices and the
fast-diagonalization blocks), the JAX factors of shaped tanks. An estimate that tells 1 GB from
1 TB, not the process's peak to a few per cent."""
from __future__ import annotations

from ..solve.factored import DENSE_MAX


def assembly_bytes(t) -> float:
    """The element arrays of the tank's assembly: COO rows, columns and values."""
    nx, ny, nz = t.mesh
    E = nx * ny * nz
    return 8.0 * E * (24 * 24) * 3 + 8.0 * E * 64 * 3


def dense_bytes(t, nf: int) -> float:
    """The dense nodal blocks: mass, stiffness, two or three inverses."""
    nx, ny, nz = t.mesh
    N = (nx + 1) * (ny + 1) * (nz + 1)
    return 8.0 * (N * N + 4.0 * nf * nf)


def sparse_bytes(t, nf: int) -> float:
    """The sparse nodal blocks: the sparse products and the box grid's fast-diagonalization blocks."""
    nx, ny, nz = t.mesh
    return 8.0 * 81 * 3 * nf * 2 + 8.0 * nx * ny * (3 * (nz + 1)) ** 2


def factor_bytes(t, nf: int) -> float:
    """The liquid block's JAX factors of a tank the fast diagonalization does not take (solve/
    factored.py): the step's and the mass's, dense inverses or banded block factors, whose RCM
    bandwidth is about twice the dofs of a cross-section across the two shortest node counts."""
    if nf <= DENSE_MAX:
        return 2 * 8.0 * nf * nf
    a, b, _ = sorted(n + 1 for n in t.mesh)
    return 2 * 8.0 * 2 * nf * min(nf, 2 * 3 * a * b)


def nodal_bytes(t, nf: int, sparse: bool, host_lu: bool) -> float:
    """A full-order nodal tank's: dense blocks, or sparse ones with the JAX factors of a shaped tank
    (none where the host's sparse LU solves it, `host_lu`)."""
    if not sparse:
        return max(assembly_bytes(t), dense_bytes(t, nf))
    solver = sparse_bytes(t, nf)
    if not t.geometry.plain_box and not host_lu:
        solver += factor_bytes(t, nf)
    return max(assembly_bytes(t), solver)


def basis_bytes(t, nf: int, sparse: bool) -> float:
    """A reduced tank's (either element): the nodal blocks its modal basis is cut from, with the
    sparse factor of the mesh that the basis needs on the sparse way."""
    if not sparse:
        return max(assembly_bytes(t), dense_bytes(t, nf))
    nx, ny, nz = t.mesh
    solver = max(sparse_bytes(t, nf), 8.0 * nf * 30 * max(nx * ny, ny * nz, nx * nz) ** 0.5)
    return max(assembly_bytes(t), solver)


def face_bytes(t, rt_dense: bool) -> float:
    """A full-order face-normal tank's (liquid/face/build.py): dense M, K and inverses on the ~3E
    faces (`rt_dense`), or dense blocks on the elements and top faces only, ~7 of them while the
    Schur complement's inverses are formed (liquid/face/schur.py)."""
    nx, ny, nz = t.mesh
    E = nx * ny * nz
    return max(assembly_bytes(t), 8.0 * 6 * (3 * E) ** 2 if rt_dense else 8.0 * 7 * (E + nx * ny) ** 2)
