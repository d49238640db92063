"""The face-normal liquid's Newton blocks at full order without dense matrices on the faces.

The liquid's stiffness is K = kappa M + B^T Y B (liquid/face/blocks.py); the step's block
C = c M + K inverts as C^-1 r = M^-1 (r / (c + kappa) - B^T H_c B M^-1 r), H_c dense on each tank's
elements and top faces (liquid/face/schur.py). M^-1 is applied by a Chebyshev iteration of a fixed
number of steps on the Jacobi-scaled mass: the consistent RT0 mass is spectrally close to its
diagonal (D^-1 M within [0.3, 2.4] on every mesh of tests/shape_cases.py, a condition number of 3
to 8), so a fixed polynomial reaches round-off in 25 to 50 element-by-element products. A fixed
polynomial is a constant, symmetric linear map: no inner products, nothing data dependent, so
the solve vmaps, exports and differentiates as a matrix product does.
"""
from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg
import numpy as np

from .schur import schur_inverse
from .blocks import FaceOps

#: the Chebyshev iteration's bound on the relative error of M^-1 (round-off: the full-order runs
#: then equal the dense path's to the Newton tolerance, iteration for iteration)
MASS_TOL = 1e-15
#: the spectral bounds of D^-1 M are widened by this factor (they come from a Lanczos run to 1e-6)
WIDEN = 0.02
#: free faces up to which the step block's inverse is stored as the dense matrix of the operator below
#: (formed once per run by applying it to the identity): one product of n^2 entries against two
#: Chebyshev solves of 25-50 gathers and scatters each. On the prismatic 4x12x8 tank (1,024 faces)
#: the preconditioner's application fell from 590 to 150 us and the step from 3,240 to about 1,900
#: us (docs/benchmarks.md, "The shaped tanks against their floor"); the product grows as n^2 and the
#: solves as n, so they cross near 4,000 faces, where the matrix holds 128 MB
DENSE_STEP_FACES = 3000


def chebyshev_steps(lo: float, hi: float, tol: float = MASS_TOL) -> int:
    """Steps for the error bound 2 q^k <= tol, q = (sqrt(kappa) - 1) / (sqrt(kappa) + 1)."""
    s = math.sqrt(hi / lo)
    q = (s - 1.0) / (s + 1.0)
    return max(1, int(math.ceil(math.log(tol / 2.0) / math.log(q)))) if q > 0 else 1


class MassInverse(eqx.Module):
    """M^-1 x by the Chebyshev iteration (Saad, Iterative Methods, alg. 12.1) with Jacobi scaling,
    a fixed number of steps on fixed coefficients; x: (n,) or (n, k)."""
    ops: FaceOps
    Me: jax.Array        # (E, 6, 6)
    dinv: jax.Array      # (n,) 1 / diag M
    first: jax.Array     # 1 / theta
    a: jax.Array         # (k - 1,) rho_{j+1} rho_j
    b: jax.Array         # (k - 1,) 2 rho_{j+1} / delta

    @property
    def shape(self):
        return (self.ops.n, self.ops.n)

    def __matmul__(self, x):
        dinv = self.dinv.reshape(self.dinv.shape + (1,) * (x.ndim - 1))
        d = self.first * dinv * x

        def one(carry, ab):
            x_, r_, d_ = carry
            x_ = x_ + d_
            r_ = r_ - self.ops.elementwise(self.Me, d_)
            d_ = ab[0] * d_ + ab[1] * dinv * r_
            return (x_, r_, d_), None

        (out, _, d), _ = jax.lax.scan(one, (jnp.zeros_like(x), x, d), (self.a, self.b))
        return out + d


def mass_inverse(ops: FaceOps, Me, diag, lo: float, hi: float, tol: float = MASS_TOL) -> MassInverse:
    lo, hi = lo * (1.0 - WIDEN), hi * (1.0 + WIDEN)
    k = chebyshev_steps(lo, hi, tol)
    theta, delta = 0.5 * (hi + lo), 0.5 * (hi - lo)
    sigma = theta / delta
    rho = [1.0 / sigma]
    for _ in range(k - 1):
        rho.append(1.0 / (2.0 * sigma - rho[-1]))
    rho = np.array(rho)
    a, b = rho[1:] * rho[:-1], 2.0 * rho[1:] / delta
    return MassInverse(ops, jnp.asarray(Me), 1.0 / jnp.asarray(diag), jnp.asarray(1.0 / theta),
                       jnp.asarray(a), jnp.asarray(b))


class FaceStepInverse(eqx.Module):
    """C^-1 r = M^-1 (s r - B^T H B M^-1 r) (s: 1 / (c + kappa) per unknown, each tank's kappa)."""
    minv: MassInverse
    s: jax.Array          # (n,)
    H: tuple              # per tank (ny_t, ny_t)

    @property
    def shape(self):
        return self.minv.shape

    def __matmul__(self, r):
        ops = self.minv.ops
        z = self.minv @ r
        ys = ops.B(z)
        s = self.s.reshape(self.s.shape + (1,) * (r.ndim - 1))
        return self.minv @ (s * r - ops.BT([H @ y for H, y in zip(self.H, ys)]))


def face_solver_blocks(liquid, c_step: float, c_sub=None, dense_faces: int = DENSE_STEP_FACES):
    """(Cinv_step, Cinv_mass, Cinv_sub or None, sum_j |K_ij| per row) of a sparse FaceLiquid
    (solve/linear.make_solver): H_c per tank from its Y, W^-1 and kappa (host, float64; in JAX from
    the stop_gradient values where the liquid is at scaled, perhaps traced values: the inverses only
    precondition). Up to `dense_faces` unknowns the step blocks are the dense matrices of the same
    operators (`dense_matrix`), which the Newton iterations apply several times per step."""
    K, mi = liquid.K, liquid.Minv
    sg = jax.lax.stop_gradient
    if K.rho is not None:
        mi = sg(mi)

    def operator(c):
        if K.rho is None:
            H = tuple(jnp.asarray(schur_inverse(np.asarray(Y), np.asarray(wi), float(k), c))
                      for Y, wi, k in zip(K.Y, K.winv, np.asarray(K.kappas)))
            return FaceStepInverse(mi, jnp.asarray(1.0 / (c + np.asarray(K.kappa_n))), H)
        H = tuple(schur_inverse(sg(Y), sg(wi), sg(K.kappas[i]), c, sg(r), sg(N), jnp, jax.scipy.linalg)
                  for i, (Y, wi, r, N) in enumerate(zip(K.Y, K.winv, K.rho, K.pools)))
        return FaceStepInverse(mi, 1.0 / (c + sg(K.kappa_n)), H)

    def block(c):
        op = operator(c)
        return dense_matrix(op, host=K.rho is None) if op.shape[0] <= dense_faces else op

    rowsum = np.asarray(K.abs_rowsum) if K.rho is None else sg(K.abs_rowsum)
    return block(float(c_step)), mi, block(float(c_sub)) if c_sub is not None else None, rowsum


@eqx.filter_jit
def _columns(op):
    X = op @ jnp.eye(op.shape[0], dtype=op.s.dtype)
    return 0.5 * (X + X.T)           # the operator is symmetric: its round-off is not


def dense_matrix(op: FaceStepInverse, host: bool):
    """The (n, n) matrix of the step block's inverse (its columns: the operator on the identity,
    symmetrized), a concrete array from the model's values (`host`), else traced like them."""
    return jnp.asarray(np.asarray(_columns(op))) if host else _columns(op)
