"""Large meshes: the liquid's matrices kept sparse, their products and solves in JAX.

A dense liquid block stops fitting long before a mesh is fine: 20 x 20 x 12 hexahedra have 15,666
free unknowns, whose dense stiffness, mass and step-matrix inverses would take 2 GB each. Here:

* `build_liquid(..., sparse=True)` assembles SciPy CSR matrices (liquid.py);
* `HostSparse` holds a symmetric sparse matrix as a JAX BCOO array for the residual's products
  (differentiable, transposable and batchable: the Newton preconditioner and the implicit
  gradients linearise and transpose the residual) and as SciPy CSR for the factors;
* the constant liquid block C = c_a M + K is inverted by fast diagonalization where every tank is
  a box grid it fits (boxsolve.py: pure JAX, small dense transforms instead of a factor's millions
  of entries);
* the products of `HostSparse` go element by element where every tank's layers are uniform (one
  element matrix per layer, boxsolve.Elements), else as grid stencils (boxsolve.Stencil), else
  as BCOO gathers and scatters;
* otherwise (shaped tanks, box meshes the diagonalization does not fit) the block is factored once
  at build time and applied with JAX ops (factored.py: dense inverses per tank, or banded block
  factors for tanks too large for one): the step stays pure JAX, so it exports, caches, vmaps and
  runs on any backend;
* `HostInverse`, a sparse LU factor on the host (SuperLU, symmetric mode, minimum-degree ordering on
  A + A^T) called from the step, only where the scene asks for it (`simulation.linear_solver =
  "sparse-host"`: a mesh whose banded factors would not fit in memory). A host callback is neither
  exported nor kept by XLA's cache (cache/programs.py finds no name for a program that holds the factor:
  it does not pickle), so such a run traces and compiles every time. The Newton iterations only
  need an approximate inverse (lax.custom_root), so a host-side factor is a legitimate
  preconditioner, and the tangent solves of the gradients reach full precision by Richardson sweeps
  around it.

The matrices must be concrete: a tank key traced for gradients or a sweep (fill depth, density,
sound speed, gravity) needs the dense path (`simulation.linear_solver = "dense"`) or a reduced
liquid at a mesh whose dense matrices fit. Callbacks are vmapped by expanding dims: a batch is
solved as one multi-column product or solve.
"""
from __future__ import annotations

import hashlib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
from jax.experimental.sparse import BCOO
from scipy.sparse.linalg import splu

from ...fem.slip import rotate_matrix
from .boxsolve import box_inverse, elements, solve, stencil
from ...solve.factored import cached_factored_inverse

#: `linear_solver = "auto"` goes sparse above this many liquid unknowns (free dofs of all tanks):
#: above it the dense inverses' products cost more than the sparse path and their memory grows as
#: the square (docs/guide/linear-solvers.md has the measurements)
SPARSE_AUTO = 1500

_REGISTRY: dict = {}


class _Handle:
    """A host object (SciPy matrix or factor) named by its content: equal contents share one handle,
    so a static field holding it does not recompile the loop when a scene is built again."""

    def __init__(self, key, obj):
        self.key, self.obj = key, obj

    def __hash__(self):
        return hash(self.key)

    def __eq__(self, other):
        return isinstance(other, _Handle) and other.key == self.key


def _content_key(kind, A, extra=()):
    A = A.tocsr()
    h = hashlib.sha1()
    for arr in (A.indptr, A.indices, A.data):
        h.update(np.ascontiguousarray(arr).tobytes())
    return (kind, A.shape, h.hexdigest()) + tuple(extra)


def _handle(kind, A, make, extra=()):
    key = _content_key(kind, A, extra)
    if key not in _REGISTRY:
        _REGISTRY[key] = _Handle(key, make(A))
    return _REGISTRY[key]


def _host_apply(fn, n):
    """Apply fn (n, k) -> (n, k) to x of shape (n, k) or, under vmap, (B, n, k)."""
    def call(x):
        x = np.asarray(x)
        if x.ndim == 2:
            return np.asarray(fn(x), dtype=np.float64).reshape(x.shape)
        B, _, k = x.shape
        y = fn(np.moveaxis(x, 0, 1).reshape(n, B * k))
        return np.moveaxis(np.asarray(y, dtype=np.float64).reshape(n, B, k), 1, 0)
    return call


def _callback(fn, n, x):
    x2 = x[:, None] if x.ndim == 1 else x
    y = jax.pure_callback(_host_apply(fn, n), jax.ShapeDtypeStruct(x2.shape, jnp.float64), x2,
                          vmap_method="expand_dims")
    return y[:, 0] if x.ndim == 1 else y


class HostSparse(eqx.Module):
    """A constant symmetric sparse matrix for `A @ x` in traced code (x: (n,) or (n, k)): a BCOO
    matrix (differentiable, transposable, batchable), its row sums, and the SciPy matrix it came from
    (for the host-side factors)."""
    bcoo: object
    rowsum: jax.Array
    handle: _Handle = eqx.field(static=True)
    grid: object = None        # box tanks: the same matrix element by element or as a stencil (boxsolve.py), used instead

    @property
    def shape(self):
        return self.handle.obj.shape

    @property
    def matrix(self) -> sp.csr_matrix:
        return self.handle.obj

    def __matmul__(self, x):
        return (self.bcoo if self.grid is None else self.grid) @ x

    def sum(self, axis=None):
        return self.rowsum.sum() if axis is None else self.rowsum


def host_sparse(A, layout=None, layers=None) -> HostSparse:
    """`layout`: the rows' places on box grids (see boxsolve.stencil), for the stencil product;
    `layers`: each tank's element matrices per layer (NodalModel.layers), for the product element
    by element (boxsolve.elements), which is preferred where every tank has them."""
    A = sp.csr_matrix(A)
    A = (0.5 * (A + A.T)).tocsr()
    A.sort_indices()
    grid = None
    if layers is not None and layout is not None:
        grid = elements(A, tuple(lay + (blk,) for lay, blk in zip(layout, layers)))
    if grid is None and layout is not None:
        grid = stencil(A, layout)
    return HostSparse(BCOO.from_scipy_sparse(A) if grid is None else None,
                      jnp.asarray(np.asarray(A.sum(axis=1)).reshape(-1)), _handle("matrix", A, lambda M: M), grid)


class HostInverse(eqx.Module):
    """`Cinv @ r` by a sparse LU factor on the host (a preconditioner; not differentiated)."""
    handle: _Handle = eqx.field(static=True)

    @property
    def shape(self):
        return self.handle.obj.shape

    def __matmul__(self, x):
        lu = self.handle.obj
        return _callback(lu.solve, lu.shape[0], jax.lax.stop_gradient(x))


def host_inverse(A) -> HostInverse:

    def factor(M):
        return splu(M.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                    options=dict(SymmetricMode=True))
    return HostInverse(_handle("lu", sp.csr_matrix(A), factor))


def free_blocks(liquid):
    """(M_ff, K_ff) of a sparse `NodalLiquid` as SciPy matrices on its free dofs."""
    f = np.asarray(liquid.free)
    M = sp.kron(liquid.Ms.matrix, sp.eye(3), format="csr")
    if liquid.frames is not None:
        M = rotate_matrix(np, M, np.asarray(liquid.frames))
    return M.tocsr()[f][:, f], liquid.K.matrix


def sparse_solver_blocks(liquid, c_a_step, c_a_sub=None):
    """(Cinv_step, Cinv_mass, Cinv_sub or None, noise factor) for `integrator.make_solver`."""
    M, K = free_blocks(liquid)

    def inverse(A, with_bending=True):
        box = None
        if liquid.grids is not None:      # box tanks: fast diagonalization (boxsolve.py) where it fits
            key = _content_key("box", sp.csr_matrix(A), (liquid.grids, with_bending))
            if key not in _REGISTRY:
                _REGISTRY[key] = box_inverse(A, liquid.grids, with_bending)
            box = _REGISTRY[key]
        if box is not None:
            return box
        # shaped tanks: dense or banded factors applied in JAX (factored.py); the host's sparse LU
        # only where the scene asks for it (linear_solver = "sparse-host")
        return host_inverse(A) if liquid.host_lu else cached_factored_inverse(A)

    step = inverse(c_a_step * M + K)
    sub = inverse(c_a_sub * M + K) if c_a_sub is not None else None
    return step, inverse(M, with_bending=False), sub, K


def hydrostatic_start(liquid, g_b):
    """K d0 = free_part(m g_b), by three host solves (g_b may be traced: d0 is linear in it)."""
    f = np.asarray(liquid.free)
    m = np.asarray(liquid.Ms.rowsum)
    F = np.zeros((3 * m.size, 3))
    for c in range(3):
        F[c::3, c] = m
    if liquid.frames is not None:              # onto the nodes' frames
        F = np.einsum("nji,njc->nic", np.asarray(liquid.frames), F.reshape(m.size, 3, 3)).reshape(-1, 3)
    K = liquid.K.matrix
    box = None
    if liquid.grids is not None:          # box tanks: K itself diagonalizes (boxsolve.py)
        box = box_inverse(K, liquid.grids)
    D = np.asarray(solve(box, jnp.asarray(F[f]))) if box is not None else splu(K.tocsc()).solve(F[f])
    return jnp.asarray(D) @ g_b
