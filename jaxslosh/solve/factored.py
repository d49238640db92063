"""The constant liquid block of shaped tanks, factored once at build time and applied with JAX ops.

A sparse liquid whose tanks are not box grids (prismatic, cylinders, mesh files, baffles) cannot use
the fast diagonalization of boxsolve.py. Its block C = c_a M + K (and M, for the initial
accelerations) is constant through a run, so it is factored here once, in NumPy, and a solve in the
step is a few dense products of the factors, which are arrays among the program's inputs: the step
stays pure JAX, so it exports, is kept by XLA's cache, vmaps, differentiates (the factors only
precondition: `lax.custom_root` drops their tangents) and runs on any backend. No LAPACK call is
left in the step either (solve/linalg.py's batching caveat does not arise).

The block is block diagonal, one block per tank (more where a tank's liquid falls apart), found as
the connected components of its pattern. Each component gets one of two factors:

* `Dense`: its explicit inverse (8 n^2 bytes); a solve is one matrix-vector product, the floor the
  benchmarks compare against;
* `Banded`: after a reverse Cuthill-McKee ordering the component is banded, hence block tridiagonal
  in blocks of its bandwidth b; its block LDL^T factor, C = L D L^T with L's sub-diagonal blocks
  E_i = B_i S_i^-1 and D's blocks the Schur complements S_i, is kept as S_i^-1 and E_i (2 n b
  entries in all). A solve is a forward and a backward `lax.scan` over the n / b blocks, one b x b
  product each way per block.

`Dense` is taken while the component has at most DENSE_MAX unknowns and its inverse is not more than
BANDED_GAIN times larger than the banded factor; a larger component is banded (docs/guide/
linear-solvers.md has the measurements behind both constants).
"""
from __future__ import annotations

import hashlib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, reverse_cuthill_mckee

#: a component with more unknowns is never inverted densely (its inverse: 8 n^2 bytes, 128 MB here)
DENSE_MAX = 4000
#: below DENSE_MAX, the dense inverse is kept unless it holds more than this many times the entries
#: of the banded factor (a matrix-vector product streams its entries once: fewer entries, less time;
#: the banded solve's scans cost more per entry)
BANDED_GAIN = 4.0
#: largest normwise backward error of a built factor on random right-hand sides (a failed check is a
#: bug or a singular block)
CHECK = 1e-10


class Dense(eqx.Module):
    """A component's explicit inverse."""
    inv: jax.Array           # (n, n)

    @property
    def n(self) -> int:
        return self.inv.shape[0]

    def __matmul__(self, x):
        return self.inv @ x


class Banded(eqx.Module):
    """A block tridiagonal component's block LDL^T factor (x: (n,) or (n, m), in the RCM order)."""
    Sinv: jax.Array          # (k, b, b) inverses of the Schur complements (D's blocks)
    E: jax.Array             # (k - 1, b, b) sub-diagonal blocks of L
    n: int = eqx.field(static=True)

    def __matmul__(self, x):
        k, b, _ = self.Sinv.shape
        rest = x.shape[1:]
        r = jnp.concatenate([x, jnp.zeros((k * b - self.n,) + rest, x.dtype)]).reshape((k, b) + rest)

        def forward(y, inp):            # L y = r
            E, ri = inp
            y = ri - E @ y
            return y, y

        _, ys = jax.lax.scan(forward, r[0], (self.E, r[1:]))
        y = jnp.concatenate([r[:1], ys])

        def backward(xn, inp):          # L^T x = D^-1 y
            Sinv, E, yi = inp
            xi = Sinv @ yi - E.T @ xn
            return xi, xi

        last = self.Sinv[-1] @ y[-1]
        _, xs = jax.lax.scan(backward, last, (self.Sinv[:-1], self.E, y[:-1]), reverse=True)
        return jnp.concatenate([xs, last[None]]).reshape((k * b,) + rest)[:self.n]


class FactoredInverse(eqx.Module):
    """`A^-1 @ x` for a constant symmetric positive definite sparse A: its components' factors, in
    the order `perm` of A's unknowns (components one after the other, each banded one in its RCM
    order); x: (n,) or (n, m)."""
    parts: tuple
    perm: jax.Array          # (n,) A's unknown at each place of the factors' order
    iperm: jax.Array         # (n,) its inverse
    n: int = eqx.field(static=True)
    # a hash of A and the form: the factors' values follow from it, so a run's initial state kept on
    # disk is named by it (run/compiled._digest) instead of by hashing the factors' megabytes
    content_key: str = eqx.field(static=True, default="")

    @property
    def shape(self):
        return (self.n, self.n)

    def __matmul__(self, x):
        xp = x[self.perm]
        ys, start = [], 0
        for p in self.parts:
            ys.append(p @ xp[start:start + p.n])
            start += p.n
        return jnp.concatenate(ys)[self.iperm]


def _bandwidth(A) -> int:
    A = A.tocoo()
    return int(np.max(np.abs(A.row - A.col), initial=0))


def _banded(A, b: int) -> Banded:
    """The block LDL^T factor of A (dense-able blocks of size b; A's bandwidth at most b)."""
    n = A.shape[0]
    k = -(-n // b)
    P = sp.block_diag([A, sp.identity(k * b - n)]).tocsr() if k * b > n else A.tocsr()
    Sinv, E = np.empty((k, b, b)), np.empty((max(k - 1, 0), b, b))
    S = P[:b, :b].toarray()
    for i in range(k):
        Sinv[i] = np.linalg.inv(S)
        Sinv[i] = 0.5 * (Sinv[i] + Sinv[i].T)
        if i + 1 < k:
            lo, hi = (i + 1) * b, (i + 2) * b
            B = P[lo:hi, i * b:lo].toarray()
            E[i] = B @ Sinv[i]
            S = P[lo:hi, lo:hi].toarray() - E[i] @ B.T
    return Banded(jnp.asarray(Sinv), jnp.asarray(E), n)


def choose(n: int, b: int) -> str:
    """"dense" or "banded" for a component of n unknowns whose RCM bandwidth is b."""
    k = -(-n // max(b, 1))
    if n <= DENSE_MAX and (k <= 2 or n * n <= BANDED_GAIN * 2 * k * b * b):
        return "dense"
    return "banded"


def factored_inverse(A, form: str = "auto") -> FactoredInverse:
    """FactoredInverse of the SciPy matrix A (symmetrized); `form`: "auto" (by `choose`), "dense"
    or "banded" for every component (tests and benchmarks)."""
    A = sp.csr_matrix(A)
    A = (0.5 * (A + A.T)).tocsr()
    A.sort_indices()
    n = A.shape[0]
    ncomp, labels = connected_components(A, directed=False)
    parts, order = [], []
    for c in range(ncomp):
        idx = np.flatnonzero(labels == c)
        Ac = A[idx][:, idx].tocsr()
        p = reverse_cuthill_mckee(Ac, symmetric_mode=True)
        Ap = Ac[p][:, p]
        b = max(_bandwidth(Ap), 1)
        kind = choose(idx.size, b) if form == "auto" else form
        if kind == "dense":
            parts.append(Dense(jnp.asarray(_sym(np.linalg.inv(Ac.toarray())))))
            order.append(idx)
        else:
            parts.append(_banded(Ap, b))
            order.append(idx[p])
    perm = np.concatenate(order) if order else np.zeros(0, dtype=np.int64)
    iperm = np.empty_like(perm)
    iperm[perm] = np.arange(n)
    F = FactoredInverse(tuple(parts), jnp.asarray(perm.astype(np.int32)), jnp.asarray(iperm.astype(np.int32)), n,
                        _matrix_key(A, form))
    _check(A, F)
    return F


def _sym(X):
    return 0.5 * (X + X.T)


def _check(A, F: FactoredInverse):
    rng = np.random.default_rng(0)
    R = rng.standard_normal((A.shape[0], 2))
    X = _apply_np(F, R)
    # the normwise backward error: round-off gives eps times a modest factor, whatever A's condition
    norm = np.max(np.asarray(abs(A).sum(axis=1)))
    err = np.max(np.abs(A @ X - R)) / (norm * np.max(np.abs(X)) + np.max(np.abs(R)))
    if not err < CHECK:
        raise ArithmeticError(f"the liquid block's factor solves with a backward error of {err:.1e} (a singular block?)")


def _apply_np(F: FactoredInverse, R):
    """F @ R in NumPy (the build's check: no JAX program compiled for it)."""
    Rp, out, start = R[np.asarray(F.perm)], [], 0
    for p in F.parts:
        r = Rp[start:start + p.n]
        start += p.n
        if isinstance(p, Dense):
            out.append(np.asarray(p.inv) @ r)
            continue
        Sinv, E = np.asarray(p.Sinv), np.asarray(p.E)
        k, b, _ = Sinv.shape
        y = np.concatenate([r, np.zeros((k * b - p.n,) + r.shape[1:])]).reshape((k, b) + r.shape[1:])
        for i in range(1, k):
            y[i] -= E[i - 1] @ y[i - 1]
        x = np.empty_like(y)
        x[-1] = Sinv[-1] @ y[-1]
        for i in range(k - 2, -1, -1):
            x[i] = Sinv[i] @ y[i] - E[i].T @ x[i + 1]
        out.append(x.reshape((k * b,) + r.shape[1:])[:p.n])
    return np.concatenate(out)[np.asarray(F.iperm)]


_CACHE: dict = {}
#: factors kept in the process (a script that builds the same scene again reuses them)
KEEP = 8


def _matrix_key(A, form: str) -> str:
    A = sp.csr_matrix(A)
    A.sort_indices()
    h = hashlib.sha256(repr((A.shape, form, DENSE_MAX, BANDED_GAIN)).encode())
    for arr in (A.indptr, A.indices, A.data):
        h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()


def cached_factored_inverse(A, form: str = "auto") -> FactoredInverse:
    """factored_inverse, reused for a matrix of the same content (the same scene built again)."""
    key = _matrix_key(A, form)
    if key not in _CACHE:
        _CACHE[key] = factored_inverse(A, form)
        while len(_CACHE) > KEEP:
            _CACHE.pop(next(iter(_CACHE)))
    return _CACHE[key]
