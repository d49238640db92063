"""Dense inverses and solves that stay safe under `jax.vmap` on the CPU (issue 21).

jaxlib's CPU LAPACK kernels (getrf, trsm, ...) split a batch of matrices into chunks, schedule the
chunks on XLA's intra-op thread pool and block the pool thread that runs the kernel until the
chunks are done (`ParallelBatchMap` in jaxlib/cpu/lapack_kernels.cc: nothing helps while it
waits). When as many such kernels run at once as the pool has threads -- independent inverses that
XLA's thunk executor starts side by side, or one per host device of a sharded batch -- every pool
thread waits for chunks that only a pool thread could run: the program deadlocks inside XLA (the
`jaxslosh sweep` of a tank's density on a 2-core machine, `tests/run/test_sweep.py`). A kernel splits
only a batch of more than one matrix, so here a vmapped batch is never handed to LAPACK as one: the
custom batching rule maps the unbatched kernel over the runs (`lax.map`), each run's factorization
the same as an unbatched call's. A batch of small matrices (the Newton step's 6 x 6 Schur
complement, every step of every run) is handed over in chunks whose work stays below the bound
under which the kernel never splits (`_INLINE_FLOP`): a loop over a large batch of them would slow
the batch down. Gradients are defined around it (`custom_jvp` for the inverse,
`lax.custom_linear_solve` for the solve), so these functions are differentiable like jnp.linalg's.

Matrices that are 2 x 2 or 3 x 3 (element Jacobians) do not need LAPACK at all: `det2`, `det3`
and `inv3` are closed forms.
"""
from __future__ import annotations

import math

import jax
import jax.numpy as jnp

#: FLOP of one LAPACK call (n^3 per matrix, as jaxlib counts them) below which its batch is run
#: inline by the kernel: jaxlib 0.10 splits a batch at 2e5 (GetLapackBatchChunkSize); half of that.
#: One matrix per call is safe whatever the bound.
_INLINE_FLOP = 100_000


@jax.custom_batching.custom_vmap
def _inv(a):
    return jnp.linalg.inv(a)        # a: (..., n, n)


@_inv.def_vmap
def _inv_vmap(axis_size, in_batched, a):
    if not in_batched[0]:
        return _inv(a), False
    per_run = a.shape[-1] ** 3 * math.prod(a.shape[1:-2])
    chunk = max(1, _INLINE_FLOP // per_run)
    if axis_size <= chunk:          # one call that the kernel runs inline; an outer vmap comes back here
        return _inv(a), True
    return jax.lax.map(_inv, a, batch_size=chunk), True


@jax.custom_jvp
def inv(a):
    """jnp.linalg.inv(a) (a: (..., n, n)); under vmap a loop over the batch, in chunks small enough
    that no LAPACK kernel splits them (see the module)."""
    return _inv(a)


@inv.defjvp
def _inv_jvp(primals, tangents):
    (a,), (da,) = primals, tangents
    x = inv(a)
    return x, -x @ da @ x


@jax.custom_batching.custom_vmap
def _solve(a, b):
    return jnp.linalg.solve(a, b)


@_solve.def_vmap
def _solve_vmap(axis_size, in_batched, a, b):
    a_batched, b_batched = in_batched
    if not a_batched:          # one matrix, many right-hand sides: one factorization, no batch
        rhs = jnp.moveaxis(b, 0, -1)                       # (n, B) or (n, k, B)
        x = _solve(a, rhs.reshape(rhs.shape[0], -1)).reshape(rhs.shape)
        return jnp.moveaxis(x, -1, 0), True
    if not b_batched:
        b = jnp.broadcast_to(b, (axis_size,) + b.shape)
    return jax.lax.map(lambda ab: _solve(*ab), (a, b)), True


def solve(a, b):
    """jnp.linalg.solve(a, b) for one matrix a (n x n) and b (n,) or (n, k); under vmap a loop of
    unbatched solves (it serves once-per-run solves: no chunks). Differentiable in a and b
    (`lax.custom_linear_solve`)."""
    return jax.lax.custom_linear_solve(lambda x: a @ x, b, solve=lambda _, r: _solve(a, r),
                                       transpose_solve=lambda _, r: _solve(a.T, r))


def det2(a):
    """The determinant of 2 x 2 matrices (..., 2, 2)."""
    return a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]


def _cofactors3(a):
    """The cofactor matrix of 3 x 3 matrices (..., 3, 3)."""
    c0 = jnp.cross(a[..., 1, :], a[..., 2, :])
    c1 = jnp.cross(a[..., 2, :], a[..., 0, :])
    c2 = jnp.cross(a[..., 0, :], a[..., 1, :])
    return jnp.stack([c0, c1, c2], axis=-2)


def det3(a):
    """The determinant of 3 x 3 matrices (..., 3, 3)."""
    return jnp.sum(a[..., 0, :] * jnp.cross(a[..., 1, :], a[..., 2, :]), axis=-1)


def inv3(a):
    """The inverse of 3 x 3 matrices (..., 3, 3): the adjugate over the determinant."""
    return jnp.swapaxes(_cofactors3(a), -1, -2) / det3(a)[..., None, None]
