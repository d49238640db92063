"""Modal reduction of the tank liquid: its first sloshing modes plus a static correction.

A cheaper accuracy level, selected per tank in the scene (`[tanks.reduction] modes = 20`). The
liquid's relative displacement on the free dofs is d = V eta, with V (nf x m) a Ritz basis:

* the n lowest natural modes Phi of the liquid with the tank held fixed (K Phi = M Phi Omega^2),
  n rounded up so that a degenerate pair (the (1,0) and (0,1) sloshing modes of a square tank) is
  never split;
* a static correction (`static_correction = true`, default): the quasi-static response K^-1 F to
  every load the rigid body puts on the liquid -- a uniform acceleration (translation, and gravity
  turning with the body: 3 patterns), an acceleration field linear in position (angular
  acceleration and centrifugal: 9 patterns) and the absolute-rotation penalty's coupling to the body
  rotation (3 patterns) -- made mass-orthogonal to Phi and diagonalised on their own span (Ritz
  vectors of the residual flexibility). Their frequencies lie far above the sloshing band (they are
  mostly compression), so they respond quasi-statically; with them the reduced model has the full
  model's static response to each of these loads exactly (the hydrostatic start, a steady heel, a
  steady spin), which modes alone only approach as their number grows. With `static_correction =
  false` only the last 3 are added: the stabilized element's penalty on the absolute rotation
  (liquid.py) lets the liquid stay irrotational as the tank turns only through them (the sloshing
  modes carry no vorticity), and without them it would hold the vessel like a stiff spring
  (measured on the paper example: roll 120 % off the full model with 20 modes).

V is mass-normalised (V^T M V = I, V^T K V = diag(omega^2)), so the reduced frequencies are the full
model's (the Ritz values of an invariant subspace are its eigenvalues).

When the tank's fill depth, density or sound speed are traced (gradients, sweeps), the basis is
computed from the scene's values and held fixed, and the reduced matrices and invariants follow the
traced values (a Galerkin projection on a fixed subspace: exact gradients of that reduced model).
"""
from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ..modes import free_matrices, natural_modes


#: relative gap under which two natural frequencies count as one degenerate cluster
DEGENERATE_GAP = 1e-6


class TankBasis(NamedTuple):
    V: np.ndarray          # (nf_t, m) Ritz basis on the tank's free dofs, V^T M V = I
    omega: np.ndarray      # (m,) rad/s: the n modes, then the static-correction Ritz vectors
    n_modes: int           # natural modes in V (after rounding up a split degenerate pair)


def _load_patterns(model, origin):
    """Loads (nf, 15) that the rigid body puts on the liquid: uniform acceleration (3), an
    acceleration field linear in the vessel-frame position (9), the rotation-penalty coupling (3)."""
    f = np.flatnonzero(np.asarray(model.free))
    Ms = model.mass
    N = model.n_nodes
    r = np.asarray(model.nodes) + np.asarray(origin)[None, :]
    m = np.asarray(Ms.sum(axis=1)).reshape(-1)
    Mr = np.asarray(Ms @ r)                                  # (N, 3)
    cols = []
    for c in range(3):
        F = np.zeros((N, 3))
        F[:, c] = m
        cols.append(model.to_local(F).reshape(-1)[f])
    for a in range(3):
        for b in range(3):
            F = np.zeros((N, 3))
            F[:, a] = Mr[:, b]
            cols.append(model.to_local(F).reshape(-1)[f])
    if model.rotation_coupling is not None:
        C = np.asarray(model.rotation_coupling)[f]
        cols += [C[:, k] for k in range(3)]
    return np.stack(cols, axis=1)


def _solve(K, F):
    if sp.issparse(K):
        return splu(K.tocsc()).solve(F)
    return sl.solve(K, F, assume_a="sym")


@functools.lru_cache(maxsize=16)
def _cached_basis(key, model_ref, origin, n, static_correction):
    return _tank_basis(model_ref(), origin, n, static_correction)


def tank_basis(model, origin, n: int, static_correction: bool = True) -> TankBasis:
    """The Ritz basis of one tank's liquid (concrete model): its n lowest natural modes, plus the
    static correction. Cached per tank geometry, mesh, liquid and reduction."""
    key = (tuple(model.size), float(model.depth), tuple(model.mesh), float(model.density),
           float(model.sound_speed), float(model.gravity), model.element, tuple(float(o) for o in origin),
           int(n), bool(static_correction), sp.issparse(model.stiffness), model.geometry)
    return _cached_basis(key, _Ref(model), tuple(float(o) for o in origin), int(n), bool(static_correction))


class _Ref:
    """Hashes by nothing: the cache key above says what the basis depends on."""

    def __init__(self, obj):
        self.obj = obj

    def __call__(self):
        return self.obj

    def __hash__(self):
        return 0

    def __eq__(self, other):
        return isinstance(other, _Ref)


def _tank_basis(model, origin, n, static_correction):
    K, M = free_matrices(model)
    nf = K.shape[0]
    n = int(min(max(n, 1), nf))
    extra = min(4, nf - n)           # to see whether the n-th mode has a degenerate partner
    lam, X = natural_modes(K, M, min(nf - 1, n + extra) if sp.issparse(K) else n + extra)
    omega_all = np.sqrt(np.abs(lam))
    while n < len(lam) and abs(omega_all[n] - omega_all[n - 1]) <= DEGENERATE_GAP * max(omega_all[n], 1e-30):
        n += 1
    Phi, om = X[:, :n], omega_all[:n]
    F = _load_patterns(model, origin)
    if not static_correction:      # the rotation penalty's coupling only (see the module docstring)
        F = F[:, 12:]
    if n == nf or F.shape[1] == 0:
        return TankBasis(Phi, om, n)
    Psi = _solve(K, F)
    B = _mass_orthonormal(Phi, Psi, M)
    Kb = B.T @ (K @ B)
    mu, Z = np.linalg.eigh(0.5 * (Kb + Kb.T))
    V = np.concatenate([Phi, B @ Z], axis=1)
    # one more pass against round-off: V^T M V = I to machine precision
    L = np.linalg.cholesky(0.5 * (V.T @ (M @ V) + (V.T @ (M @ V)).T))
    V = sl.solve_triangular(L, V.T, lower=True).T
    return TankBasis(V, np.concatenate([om, np.sqrt(np.abs(mu))]), n)


def _mass_orthonormal(Phi, Psi, M, rtol=1e-9):
    """An M-orthonormal basis of span(Psi) less span(Phi), nearly dependent directions dropped. The
    loads' responses differ in size by orders of magnitude (compression under a vertical load is
    1e-5 of the sloshing under a horizontal one), so each is normalised first."""
    for _ in range(2):
        Psi = Psi - Phi @ (Phi.T @ (M @ Psi))
    norms = np.sqrt(np.einsum("ij,ij->j", Psi, M @ Psi))
    Psi = Psi[:, norms > 0] / norms[norms > 0]
    G = Psi.T @ (M @ Psi)
    g, W = np.linalg.eigh(0.5 * (G + G.T))
    keep = g > rtol * g.max()
    B = Psi @ (W[:, keep] / np.sqrt(g[keep]))
    return B - Phi @ (Phi.T @ (M @ B))
