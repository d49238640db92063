"""The face-normal liquid's full-order blocks without dense matrices on the faces (host side).

The stiffness the full-order runs use (liquid/face/build.py, liquid/face/term.py) is

    K = B^T W B + kappa M P,    M P = M - B^T G^+ B,    G = B M^-1 B^T,

with B = [D; T] (each element's outward flux, each top face's flux), W = diag(rho c^2 / V_e,
rho g / A_f) and P the M-orthogonal projection onto the circulation kernel (ker B). M and B are
sparse; only G^+ is dense, and it lives on the elements and top faces (ny = E + T, about nf / 2.7
unknowns), not on the faces. So

    K = kappa M + B^T Y B,    Y = W - kappa G^+          (ny x ny),

and the Newton block C = c M + K = (c + kappa) M + B^T Y B inverts by the Woodbury identity into

    C^-1 r = M^-1 (r / (c + kappa) - B^T H_c B M^-1 r),
    H_c = W^1/2 [ (1/c^2) (I - (I + c S)^-1) - kappa / (c (c + kappa)) S ] W^1/2,   S = W^-1/2 G^+ W^-1/2

(on the generalized eigenvectors of G y = lambda W^-1 y, H_c is (lambda - kappa) / (lambda (lambda + c)
(c + kappa)), so that C^-1 is 1 / (c + kappa) on the kernel and 1 / (c + lambda) on mode lambda).
The pools' uniform pressures (G's null vectors) drop out: B^T annihilates them.

Here: G formed densely from sparse solves with M (SciPy's LU, symmetric mode), its generalized
inverse, H_c, the static start K^-1 F, and the spectral bounds of the Jacobi-scaled M that the
Chebyshev iteration for M^-1 (liquid/face/inverse.py) needs. NumPy and SciPy only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: columns of M^-1 B^T formed at once while G is assembled (memory: nf x CHUNK floats)
CHUNK = 512


def _spd_lu(A):   # symmetric positive definite: symmetric ordering, no pivoting (as liquid/face/element.py)
    return spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))


@dataclass(frozen=True, eq=False)
class FaceSchur:
    """One tank's free-surface Schur complement and what comes with it (free faces `f`)."""
    f: np.ndarray           # (nf,) the free faces
    B: sp.csr_matrix        # (ny, nf) [D; T] on the free faces
    winv: np.ndarray        # (ny,) W^-1: V_e / (rho c^2), A_f / (rho g)
    M: sp.csc_matrix        # (nf, nf) the consistent mass on the free faces
    Mlu: object             # its sparse LU (symmetric mode)
    G: np.ndarray           # (ny, ny) B M^-1 B^T, dense
    Gp: np.ndarray          # (ny, ny) its generalized inverse V Lambda^+ V^T (see `face_schur`)
    N: np.ndarray           # (ny, pools) orthonormal null vectors of G (one uniform pressure per pool)

    def minv(self, r):
        return self.Mlu.solve(np.asarray(r, dtype=float))

    def kernel_part(self, c):
        """P c = c - M^-1 B^T G^+ B c (columns of c)."""
        return c - self.minv(self.B.T @ (self.Gp @ (self.B @ c)))

    def static_solve(self, F, kappa):
        """K^-1 F (columns), K = kappa M + B^T (W - kappa G^+) B: C^-1 at c = 0, H_0 = G^+ / kappa
        - G^+ W^-1 G^+."""
        z = self.B @ self.minv(F)
        Gz = self.Gp @ z
        Hz = Gz / kappa - self.Gp @ (self.winv.reshape((-1,) + (1,) * (Gz.ndim - 1)) * Gz)
        return self.minv(F / kappa - self.B.T @ Hz)


def mixed_operators(model):
    """(free faces, B (ny, nf), M (nf, nf), W^-1 (ny,)) of a FaceModel (as liquid/face/element.face_modes)."""
    f = np.flatnonzero(model.free)
    E, T = len(model.elements), len(model.top)
    D = sp.coo_matrix((model.signs.reshape(-1), (np.repeat(np.arange(E), 6), model.element_faces.reshape(-1))),
                      shape=(E, len(model.faces))).tocsr()
    Tsel = sp.coo_matrix((np.ones(T), (np.arange(T), model.top)), shape=(T, len(model.faces))).tocsr()
    B = sp.vstack([D, Tsel]).tocsr()[:, f]
    rho, c, g = model.density, model.sound_speed, model.gravity
    winv = np.concatenate([model.volume / (rho * c * c), model.top_area / (rho * g)])
    return f, B, model.mass[f][:, f].tocsc(), winv


def pool_vectors(model) -> np.ndarray:
    """(E + T, pools) orthonormal null vectors of G = B M^-1 B^T: per pool, +1 on its elements and
    -1 on its top faces (a uniform pressure moves nothing)."""
    E, T = len(model.elements), len(model.top)
    labels = model.pool_labels()
    owner = np.empty(len(model.faces), dtype=int)
    owner[model.element_faces.reshape(-1)] = np.repeat(np.arange(E), 6)
    P = np.zeros((E + T, int(labels.max() + 1)))
    P[np.arange(E), labels] = 1.0
    P[E + np.arange(T), labels[owner[model.top]]] = -1.0
    return P / np.linalg.norm(P, axis=0)


def face_schur(model) -> FaceSchur:
    """G = B M^-1 B^T of a FaceModel, formed from CHUNK sparse solves at a time, and a generalized
    inverse: V Lambda^+ V^T on the generalized eigenvectors of G y = lambda W^-1 y (V^T W^-1 V = I),
    which the closed forms of `schur_inverse` and `FaceSchur.static_solve` need. It is Q G^+ Q^T,
    G^+ = (G + a N N^T)^-1 - N N^T / a the Moore-Penrose inverse (N: the pools' null vectors; a
    Cholesky) and Q = I - N (N^T W^-1 N)^-1 N^T W^-1, the projection onto the vectors W^-1-orthogonal
    to the pools. Any generalized inverse gives the same B^T G^+ B (B^T annihilates N): the
    stiffness is the dense path's."""
    f, B, M, winv = mixed_operators(model)
    Mlu = _spd_lu(M)
    ny = B.shape[0]
    Bt = B.T.tocsc()
    G = np.empty((ny, ny))
    for s in range(0, ny, CHUNK):
        G[:, s:s + CHUNK] = B @ Mlu.solve(Bt[:, s:s + CHUNK].toarray())
    G = 0.5 * (G + G.T)
    N = pool_vectors(model)
    a = float(np.trace(G)) / ny
    cho = sl.cho_factor(G + a * (N @ N.T), lower=True, check_finite=False)
    Gp = sl.cho_solve(cho, np.eye(ny), check_finite=False) - (N @ N.T) / a      # Moore-Penrose
    return FaceSchur(f=f, B=B, winv=winv, M=M, Mlu=Mlu, G=G, Gp=project_pools(Gp, winv, N), N=N)


def project_pools(Gp, winv, N, xp=np):
    """Q G^+ Q^T, Q = I - N (N^T W^-1 N)^-1 N^T W^-1: the generalized inverse onto the W^-1-orthogonal
    complement of the pools, whose closed forms hold for this W (`xp` = jax.numpy where W is traced:
    liquid/face/inverse.py, liquid/face/build.py)."""
    WN = winv[:, None] * N
    C = xp.linalg.inv(N.T @ WN)
    Z = Gp @ WN @ C
    out = Gp - Z @ N.T - N @ Z.T + N @ (C @ (WN.T @ Z)) @ N.T
    return 0.5 * (out + out.T)


def schur_inverse(Y, winv, kappa, c: float, r=1.0, N=None, xp=np, linalg=sl):
    """H_c of the module's docstring from Y = W - kappa G^+ (the stiffness's dense block), W^-1 and
    kappa: C^-1 r = M^-1 (r / (c + kappa) - B^T H_c B M^-1 r). c > 0. At scaled values (mass rho_s =
    r, W'^-1 = r W_s^-1, with the pools' null vectors N): r H'_c, so that C^-1 r = M_s^-1 (r / (c +
    kappa) - B^T (r H'_c) B M_s^-1 r); `xp`, `linalg`: jax.numpy and jax.scipy.linalg for traced
    values."""
    w1 = r * winv
    Gp = (xp.diag(1.0 / winv) - xp.asarray(Y)) / (r * kappa)
    if N is not None:
        Gp = project_pools(Gp, w1, N, xp)
    s = xp.sqrt(w1)
    S = s[:, None] * Gp * s[None, :]
    n = S.shape[0]
    cho = linalg.cho_factor(xp.eye(n) + c * S, lower=True)
    R = linalg.cho_solve(cho, xp.eye(n))                                # (I + c S)^-1
    H = ((xp.eye(n) - R) / (c * c) - (kappa / (c * (c + kappa))) * S) / s[:, None] / s[None, :]
    return r * 0.5 * (H + H.T)


def mass_bounds(M, Mlu=None) -> tuple[float, float]:
    """The extreme eigenvalues of D^-1 M (D = diag M), for the Chebyshev iteration (about 0.3-0.5
    and 1.5-2.4 on the meshes of tests/shape_cases.py)."""
    d = 1.0 / np.sqrt(M.diagonal())
    A = sp.diags(d) @ M @ sp.diags(d)
    n = A.shape[0]
    if n < 50:
        w = np.linalg.eigvalsh(A.toarray())
        return float(w[0]), float(w[-1])
    v0 = np.ones(n)
    hi = spla.eigsh(A, 1, which="LA", return_eigenvectors=False, v0=v0, tol=1e-6)[0]
    lu = Mlu if Mlu is not None else _spd_lu(M)
    op = spla.LinearOperator((n, n), matvec=lambda x: lu.solve(np.ravel(x) / d) / d, dtype=float)
    lo = spla.eigsh(A, 1, sigma=0.0, OPinv=op, which="LM", return_eigenvectors=False, v0=v0, tol=1e-6)[0]
    return float(lo), float(hi)
