"""The liquid block of a box tank inverted by fast diagonalization, in JAX (large meshes).

A Newton iteration on a large mesh solves with the constant liquid block C = c_a M + K (and the
initial accelerations with M). A sparse LU factor of the 20 x 20 x 12 mesh holds 24 million
entries, which every solve streams; here a solve is a few small dense transforms (docs/guide/linear-solvers.md
has the timings).

Why it works. The tank is a box on a uniform grid, and every term of the liquid's energy is the same
in every column of elements (it may change from layer to layer). The slip walls at x = 0, a and
y = 0, b hold the wall-normal displacement at zero and leave the tangential ones free: that is the
even (tangential) and odd (normal) reflection of the grid about each wall, so the cosine series
cos(p pi i / nx) (tangential components) and the sine series sin(p pi i / nx) (normal component)
diagonalize every term along x, and likewise along y (Lynch, Rice & Thomas' fast diagonalization).
With Phi the product of these 1-D bases, Phi^T C Phi is block diagonal: one block per wave pair
(p, q), coupling the three components over all the layers of the column (3 (nz + 1) unknowns; the
free surface and the bottom are not reflections, so the vertical direction stays coupled). The
blocks are found by probing C with 3 (nz + 1) vectors, one per (layer, component) with every wave
pair's coefficient equal to one, and inverted once; a solve is then two small transforms per axis
and a batched block product.

One term is not the same in every column: the weak surface bending of the stabilized element
(liquid.py), whose second differences stop one node short of the walls. It acts on the surface's
vertical displacement only, B_s, and is put back exactly by the Sherman-Morrison-Woodbury formula:
with S the inverse without it and U the surface's vertical dofs,

    (C_sep + U B_s U^T)^-1 = S - S U H U^T S,   H = B_s (I + (U^T S U) B_s)^-1,

which costs one extra transform of the surface layer. Each inverse is checked when it is built
(residual of random right-hand sides below 1e-8 relative); a mesh it does not fit (an odd number
of elements along x or y, where the stabilized element pairs its wall elements) is factored instead
(factored.py).

Pure JAX: the solve is batched by vmap like everything else and runs wherever the loop runs.

The residual's products with the stiffness and the mass on the same grids are here too: `Elements`
(element by element, one element matrix per layer) where the layers are uniform, else `Stencil`
(per-node coefficients of any assembled matrix whose entries stay near the diagonal of the grid).
"""
from __future__ import annotations

from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp

from .model import surface_bending_pattern, topology
from ...fem.mesh import HEX_CORNERS

#: largest relative residual of the built inverse on random right-hand sides
CHECK = 1e-8


def _bases(m: int, normal: bool) -> np.ndarray:
    """(m + 1, m + 1) 1-D basis along an axis with m elements: sines for the wall-normal component
    (zero at both walls; the columns p = 0 and p = m are zero), cosines for the tangential ones."""
    i = np.arange(m + 1)[:, None] * np.arange(m + 1)[None, :] * np.pi / m
    return np.sin(i) if normal else np.cos(i)


class BoxTank(eqx.Module):
    """The inverse of one tank's block (free dofs start:stop of the liquid's unknowns)."""
    Px: jax.Array          # (3, X, X) x basis of each component
    Py: jax.Array          # (3, Y, Y)
    Binv: jax.Array        # (X, Y, nb, nb) inverse blocks, nb = 3 (nz + 1), (layer, component) order
    live: jax.Array        # (X, Y, nb) 1 where the basis vector is not zero
    pos: jax.Array         # (3 X Y Z,) grid dof -> index into [x; 0] (the tank's free dofs, then zero)
    free: jax.Array        # (nf_t,) free dof -> grid dof
    H: jax.Array | None    # (X Y, X Y) Woodbury matrix of the surface bending, or None
    start: int = eqx.field(static=True)
    stop: int = eqx.field(static=True)
    shape: tuple = eqx.field(static=True)      # (X, Y, Z) nodes

    def apply(self, x):
        """C^-1 x for x of shape (nf_t, m)."""
        X, Y, Z = self.shape
        m = x.shape[1]
        g = jnp.concatenate([x, jnp.zeros((1, m), x.dtype)])[self.pos].reshape(X, Y, Z, 3, m)
        a = jnp.einsum("cip,ijkcm->pjkcm", self.Px, g)
        a = jnp.einsum("cjq,pjkcm->pqkcm", self.Py, a).reshape(X, Y, 3 * Z, m) * self.live[..., None]
        b = jnp.einsum("pqab,pqbm->pqam", self.Binv, a)
        if self.H is not None:
            s = 3 * (Z - 1) + 2                                           # surface layer, vertical
            u = jnp.einsum("ip,jq,pqm->ijm", self.Px[2], self.Py[2], b[:, :, s])
            y = (self.H @ u.reshape(X * Y, m)).reshape(X, Y, m)
            e = jnp.einsum("ip,jq,ijm->pqm", self.Px[2], self.Py[2], y)
            b = b - self.Binv[:, :, :, s, None] * e[:, :, None, :]
        b = (b * self.live[..., None]).reshape(X, Y, Z, 3, m)
        u = jnp.einsum("cjq,pqkcm->pjkcm", self.Py, b)
        u = jnp.einsum("cip,pjkcm->ijkcm", self.Px, u)
        return u.reshape(3 * X * Y * Z, m)[self.free]


class BoxInverse(eqx.Module):
    """`Cinv @ r` for the stacked tanks' liquid block; r: (nf,) or (nf, k). Not differentiated (a
    preconditioner, as the sparse LU it replaces)."""
    tanks: tuple
    n: int = eqx.field(static=True)

    @property
    def shape(self):
        return (self.n, self.n)

    def __matmul__(self, r):
        r = jax.lax.stop_gradient(r)
        x = r[:, None] if r.ndim == 1 else r
        y = jnp.concatenate([t.apply(x[t.start:t.stop]) for t in self.tanks])
        return y[:, 0] if r.ndim == 1 else y


@jax.jit
def _apply(op, x):
    """op.apply(x) or op @ x compiled (outside the loop: the build's check, the hydrostatic start)."""
    return op.apply(x) if isinstance(op, BoxTank) else op @ x


def solve(op, x):
    """`op @ x` for a BoxInverse outside traced code, compiled once per shape."""
    return _apply(op, x)


def _tank(A, bending, mesh, start, stop, free_grid):
    """A BoxTank for the tank block A (SciPy, free dofs) or None when A is not of the box form."""
    nx, ny, nz = mesh
    X, Y, Z = nx + 1, ny + 1, nz + 1
    nf, n3 = A.shape[0], 3 * X * Y * Z
    Px = np.stack([_bases(nx, c == 0) for c in range(3)])
    Py = np.stack([_bases(ny, c == 1) for c in range(3)])

    def analysis(g):           # Phi^T g, g: (X, Y, Z, 3, m)
        return np.einsum("cjq,pjkcm->pqkcm", Py, np.einsum("cip,ijkcm->pjkcm", Px, g))

    def synthesis(b):
        return np.einsum("cip,pjkcm->ijkcm", Px, np.einsum("cjq,pqkcm->pjkcm", Py, b))

    def to_grid(v):
        g = np.zeros((n3, v.shape[1]))
        g[free_grid] = v
        return g.reshape(X, Y, Z, 3, -1)

    Asep = (A - bending) if bending is not None else A
    nb = 3 * Z
    probes = np.zeros((X, Y, Z, 3, nb))
    for k in range(Z):
        probes[:, :, k, :, 3 * k:3 * k + 3] = np.eye(3)
    P = synthesis(probes).reshape(n3, nb)[free_grid]
    B = analysis(to_grid(np.asarray(Asep @ P))).reshape(X, Y, nb, nb)
    live = np.ones((X, Y, Z, 3), dtype=bool)
    live[[0, -1], :, :, 0] = False                   # sine columns p = 0, nx
    live[:, [0, -1], :, 1] = False
    free_mask = np.zeros(n3, dtype=bool)
    free_mask[free_grid] = True
    live[:, :, ~free_mask.reshape(X, Y, Z, 3).any(axis=(0, 1))] = False   # layers without free dofs
    live = live.reshape(X, Y, nb)
    B = 0.5 * (B + np.swapaxes(B, 2, 3))
    B = np.where(live[:, :, :, None] & live[:, :, None, :], B, 0.0)
    B = B + np.where(live, 0.0, 1.0)[:, :, :, None] * np.eye(nb)
    Binv = np.linalg.inv(B)
    pos = np.full(n3, nf)
    pos[free_grid] = np.arange(nf)
    H = None
    if bending is not None:
        s = 3 * (Z - 1) + 2
        surf = 3 * (np.arange(X * Y) * Z + Z - 1) + 2           # grid dofs of the surface's u_z
        loc = pos[surf]
        if np.any(loc == nf):
            return None
        Bs = np.asarray(bending[loc][:, loc].todense())
        b = Binv[:, :, s, s]
        T = np.einsum("ip,kp,pq->ikq", Px[2], Px[2], b)
        G = np.einsum("ikq,jq,lq->ijkl", T, Py[2], Py[2]).reshape(X * Y, X * Y)
        H = Bs @ np.linalg.inv(np.eye(X * Y) + G @ Bs)
    tank = BoxTank(jnp.asarray(Px), jnp.asarray(Py), jnp.asarray(Binv), jnp.asarray(live, dtype=float),
                   jnp.asarray(pos), jnp.asarray(free_grid), None if H is None else jnp.asarray(H),
                   start, stop, (X, Y, Z))
    r = np.random.default_rng(0).standard_normal((nf, 2))
    u = np.asarray(_apply(tank, jnp.asarray(r)))
    if not np.linalg.norm(A @ u - r) <= CHECK * np.linalg.norm(r):
        return None
    return tank


def box_inverse(A, grids, with_bending=True):
    """BoxInverse of the stacked liquid block A (SciPy, free dofs) for tanks on the box grids
    `grids` = ((nx, ny, nz, bending scale), ...) in the liquid's order, or None where a tank's block
    is not of the box form (then the caller factors it: factored.py). `with_bending=False`: A has no
    surface bending (the mass matrix)."""
    A = sp.csr_matrix(A)
    tanks, start = [], 0
    with jax.enable_x64(True):
        for nx, ny, nz, bend, form in grids:
            free = np.flatnonzero(topology(nx, ny, nz, form).free.reshape(-1))
            stop = start + free.size
            block = A[start:stop][:, start:stop]
            Bm = None
            if with_bending and bend != 0.0:
                n3 = 3 * (nx + 1) * (ny + 1) * (nz + 1)
                r, c, v = surface_bending_pattern(nx, ny, nz)
                Bm = (bend * sp.coo_matrix((v, (r, c)), shape=(n3, n3)).tocsr())[free][:, free].tocsr()
            t = _tank(block, Bm, (nx, ny, nz), start, stop, free)
            if t is None:
                return None
            tanks.append(t)
            start = stop
    if start != A.shape[0]:
        return None
    return BoxInverse(tuple(tanks), A.shape[0])


class StencilTank(eqx.Module):
    """One tank's block of a sparse matrix as a stencil over its node grid (rows start:stop)."""
    coef: jax.Array        # (O, k, k, X, Y, Z): row (node, component a) against (node + offset, b)
    pos: jax.Array         # (X Y Z k,) grid dof -> index into [x; 0]
    free: jax.Array        # (n_t,) row -> grid dof
    offsets: tuple = eqx.field(static=True)
    pad: tuple = eqx.field(static=True)
    start: int = eqx.field(static=True)
    stop: int = eqx.field(static=True)
    shape: tuple = eqx.field(static=True)      # (X, Y, Z, k)

    def apply(self, x):
        """A x for x of shape (n_t, m): one elementwise sum over the shifted grids, which XLA fuses
        into a single loop (no gathered copy of the neighbours)."""
        X, Y, Z, k = self.shape
        m = x.shape[1]
        g = jnp.concatenate([x, jnp.zeros((1, m), x.dtype)])[self.pos].reshape(X, Y, Z, k, m)
        px, py, pz = self.pad
        g = jnp.pad(g, [(px, px), (py, py), (pz, pz), (0, 0), (0, 0)])
        y = [0.0] * k
        for o, (a, b, c) in enumerate(self.offsets):
            w = g[px + a:px + a + X, py + b:py + b + Y, pz + c:pz + c + Z]
            for i in range(k):
                for j in range(k):
                    y[i] = y[i] + self.coef[o, i, j][..., None] * w[:, :, :, j]
        return jnp.stack(y, axis=3).reshape(X * Y * Z * k, m)[self.free]


def _stacked_apply(tanks, x):
    """The block-diagonal product: each tank's `apply` on its rows of x ((n,) or (n, m))."""
    x2 = x[:, None] if x.ndim == 1 else x
    y = jnp.concatenate([t.apply(x2[t.start:t.stop]) for t in tanks])
    return y[:, 0] if x.ndim == 1 else y


class Stencil(eqx.Module):
    """`A @ x` for a block-diagonal sparse matrix whose blocks live on box grids: each row a fixed
    pattern of neighbours (27 for hexahedra, a few more for the surface bending), so the product is
    a sum of shifted copies of the grid field times per-node coefficients, where a general sparse
    product gathers and scatters every entry (linear, so differentiable and transposable). x: (n,) or (n, m); rows of width k (3 for the stiffness
    on the free dofs, 1 for the scalar mass on the nodes)."""
    tanks: tuple
    n: int = eqx.field(static=True)

    def __matmul__(self, x):
        return _stacked_apply(self.tanks, x)


def stencil(A, layout):
    """Stencil of the block-diagonal SciPy matrix A, `layout` = ((mesh (nx, ny, nz), k, rows), ...)
    per block: rows (n_t,) the grid dof (node k + component) of each row; None when a block has
    entries outside its grid's pattern budget (then the caller keeps the general product)."""
    A = sp.csr_matrix(A)
    tanks, start = [], 0
    for (nx, ny, nz), k, rows in layout:
        G = (nx + 1, ny + 1, nz + 1)
        N = G[0] * G[1] * G[2]
        stop = start + rows.size
        B = A[start:stop][:, start:stop].tocoo()
        ri, ci = rows[B.row], rows[B.col]
        gi = np.stack(np.unravel_index(ri // k, G), 1)
        gj = np.stack(np.unravel_index(ci // k, G), 1)
        offs, inv = np.unique(gj - gi, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        if len(offs) > 64:
            return None
        coef = np.zeros((len(offs), k, k, N))
        np.add.at(coef, (inv, ri % k, ci % k, ri // k), B.data)
        pos = np.full(N * k, rows.size)
        pos[rows] = np.arange(rows.size)
        tanks.append(StencilTank(jnp.asarray(coef.reshape((len(offs), k, k) + G)), jnp.asarray(pos), jnp.asarray(rows),
                                 tuple(tuple(int(v) for v in o) for o in offs),
                                 tuple(int(v) for v in np.abs(offs).max(axis=0)), start, stop, G + (k,)))
        start = stop
    return Stencil(tuple(tanks), A.shape[0])


#: (8, 3) grid offsets of the hexahedron's nodes in the element's node order, and the (4, 2) offsets
#: of a top face's nodes (its nodes 4-7)
_CORNERS = tuple(tuple(int(x) for x in c) for c in (HEX_CORNERS + 1) // 2)
_FACE = tuple(c[:2] for c in _CORNERS[4:])


def _gather(g, n, offsets):
    """The element-local copies of a grid field: g (X, Y, Z, ...) -> (nx, ny, nz, corners, ...)."""
    nx, ny, nz = n
    return jnp.stack([g[a:a + nx, b:b + ny, c:c + nz] for a, b, c in offsets], axis=3)


def _scatter_add(fe, offsets):
    """The transpose of _gather: (nx, ny, nz, corners, ...) -> (X, Y, Z, ...), as one sum of padded
    copies (a single fused loop, no scatter)."""
    rest = [(0, 0)] * (fe.ndim - 4)
    return sum(jnp.pad(fe[:, :, :, i], [(a, 1 - a), (b, 1 - b), (c, 1 - c)] + rest) for i, (a, b, c) in enumerate(offsets))


def _second_difference_energy(u, w):
    """D^T diag(w) D u along the first axis of u (X, Y, m), D the interior second differences
    (u[i-1] - 2 u[i] + u[i+1], i = 1 .. X-2), w (Y,) the weight of each line."""
    if u.shape[0] < 3:
        return jnp.zeros_like(u)
    v = (u[:-2] - 2.0 * u[1:-1] + u[2:]) * w[None, :, None]
    return jnp.pad(v, [(0, 2), (0, 0), (0, 0)]) - 2.0 * jnp.pad(v, [(1, 1), (0, 0), (0, 0)]) + \
        jnp.pad(v, [(2, 0), (0, 0), (0, 0)])


class ElementTank(eqx.Module):
    """One tank's block of the liquid's stiffness (k = 3, free dofs) or scalar mass (k = 1, nodes)
    applied element by element: gather each element's nodal values from shifted copies of the grid,
    one batched product with its layer's element matrix (every element of a layer has the same one),
    and the sum back onto the nodes as shifted copies again. The matrices held are a few per layer
    (where a stencil holds coefficients for every node) and the products are small dense matrix
    products, which stream far less memory than the stencil. The top
    faces' free-surface term and the surface bending act on the surface's vertical dofs."""
    Ke: jax.Array              # (nz, 8k, 8k) element matrix of each layer
    Kf: Optional[jax.Array]    # (4, 4) top-face matrix on the vertical dofs, or None
    bend: Optional[jax.Array]  # (2, X) or None: scale times the line weights of the surface bending
    pos: jax.Array             # (X Y Z k,) grid dof -> index into [x; 0]
    free: jax.Array            # (n_t,) row -> grid dof
    start: int = eqx.field(static=True)
    stop: int = eqx.field(static=True)
    shape: tuple = eqx.field(static=True)      # (X, Y, Z, k)

    def apply(self, x):
        X, Y, Z, k = self.shape
        n = (X - 1, Y - 1, Z - 1)
        m = x.shape[1]
        g = jnp.concatenate([x, jnp.zeros((1, m), x.dtype)])[self.pos].reshape(X, Y, Z, k, m)
        ue = _gather(g, n, _CORNERS).reshape(n + (8 * k, m))
        fe = jnp.moveaxis(jnp.einsum("xyzam,zab->zxybm", ue, self.Ke), 0, 2).reshape(n + (8, k, m))
        f = _scatter_add(fe, _CORNERS)
        if self.Kf is not None or self.bend is not None:
            top = g[:, :, -1, 2]                                             # (X, Y, m)
            ft = jnp.zeros_like(top)
            if self.Kf is not None:
                uf = jnp.stack([top[a:a + n[0], b:b + n[1]] for a, b in _FACE], axis=2)
                ff = jnp.einsum("xyam,ab->xybm", uf, self.Kf)
                ft = ft + sum(jnp.pad(ff[:, :, i], [(a, 1 - a), (b, 1 - b), (0, 0)]) for i, (a, b) in enumerate(_FACE))
            if self.bend is not None:
                wx, wy = self.bend[0, :X], self.bend[1, :Y]
                ft = ft + _second_difference_energy(top, wy)
                ft = ft + jnp.swapaxes(_second_difference_energy(jnp.swapaxes(top, 0, 1), wx), 0, 1)
            f = f.at[:, :, -1, 2].add(ft)
        return f.reshape(X * Y * Z * k, m)[self.free]


class Elements(eqx.Module):
    """`A @ x` for the stacked tanks' block-diagonal stiffness or mass, element by element (see
    ElementTank); x: (n,) or (n, m). Linear: differentiable and transposable."""
    tanks: tuple
    n: int = eqx.field(static=True)

    def __matmul__(self, x):
        return _stacked_apply(self.tanks, x)


def elements(A, layout, check=1e-12):
    """Elements operator of the block-diagonal SciPy matrix A for `layout` = ((mesh, k, rows,
    blocks), ...) per tank, `blocks` the tank's `NodalModel.layers` (None: not uniform by layers),
    or None where a tank has none or the operator does not reproduce A (checked on random vectors
    to `check` relative: then the caller keeps the stencil)."""
    A = sp.csr_matrix(A)
    tanks, start = [], 0
    for (nx, ny, nz), k, rows, blocks in layout:
        if blocks is None:
            return None
        X, Y, Z = nx + 1, ny + 1, nz + 1
        stop = start + rows.size
        pos = np.full(X * Y * Z * k, rows.size)
        pos[rows] = np.arange(rows.size)
        Kf = bend = None
        if k == 3:
            Ke = blocks["stiffness"]
            if blocks["surface"] is not None:
                Kf = jnp.asarray(blocks["surface"])
            if blocks["bending"]:
                w = np.zeros((2, max(X, Y)))
                w[0, :X], w[1, :Y] = 1.0, 1.0
                w[0, [0, X - 1]], w[1, [0, Y - 1]] = 0.5, 0.5
                bend = jnp.asarray(blocks["bending"] * w)
        else:
            Ke = blocks["mass"]
        tanks.append(ElementTank(jnp.asarray(Ke), Kf, bend, jnp.asarray(pos), jnp.asarray(rows), start, stop,
                                 (X, Y, Z, k)))
        start = stop
    op = Elements(tuple(tanks), A.shape[0])
    x = np.random.default_rng(0).standard_normal((A.shape[0], 2))
    y = np.asarray(_apply(op, jnp.asarray(x)))
    if not np.linalg.norm(y - A @ x) <= check * np.linalg.norm(A @ x):
        return None
    return op
