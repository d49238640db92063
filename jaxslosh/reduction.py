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

The reduced equations are the Galerkin projection of the full ones (model.py), written with the
inertia invariants of the basis, computed once (Exudyn's ObjectFFRFreducedOrder does the same): with
T(P, Q) = sum_ij Ms_ij P_i Q_j^T (3x3) for nodal fields P, Q,

    S0 = sum_i m_i r_i,  U1_k = sum_i m_i U_k,i,  Q0 = T(r, r),  Q1_k = T(r, U_k),  Q2_kl = T(U_k, U_l)

so a residual costs O(m^2) small products, independent of the mesh. The rigid rows, the modal rows,
the kinetic and the potential energy are those of the full model at d = V eta, to round-off
(tests/test_reduction.py checks them against model.py).

When the tank's fill depth, density or sound speed are traced (gradients, sweeps), the basis is
computed from the scene's values and held fixed, and the reduced matrices and invariants follow the
traced values (a Galerkin projection on a fixed subspace: exact gradients of that reduced model).
"""
from __future__ import annotations

import functools
from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from .kinematics import mv3, skew, tv3

#: relative gap under which two natural frequencies count as one degenerate cluster
DEGENERATE_GAP = 1e-6


class TankBasis(NamedTuple):
    V: np.ndarray          # (nf_t, m) Ritz basis on the tank's free dofs, V^T M V = I
    omega: np.ndarray      # (m,) rad/s: the n modes, then the static-correction Ritz vectors
    n_modes: int           # natural modes in V (after rounding up a split degenerate pair)


def _free_matrices(model):
    """(K_ff, M_ff) on the free dofs: dense NumPy, or SciPy CSR for a sparse model."""
    f = np.flatnonzero(np.asarray(model.free))
    if sp.issparse(model.stiffness):
        K = model.stiffness.tocsr()[f][:, f]
        M = sp.kron(model.mass, sp.eye(3), format="csr")[f][:, f]
        return 0.5 * (K + K.T), M
    from .modes import free_mass
    K = np.asarray(model.stiffness)[np.ix_(f, f)]
    return 0.5 * (K + K.T), free_mass(model)


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
        cols.append(F.reshape(-1)[f])
    for a in range(3):
        for b in range(3):
            F = np.zeros((N, 3))
            F[:, a] = Mr[:, b]
            cols.append(F.reshape(-1)[f])
    if model.rotation_coupling is not None:
        C = np.asarray(model.rotation_coupling)[f]
        cols += [C[:, k] for k in range(3)]
    return np.stack(cols, axis=1)


def _natural_modes(K, M, n):
    """The n lowest (omega^2, shapes) of K x = omega^2 M x (dense eigh, or shift-invert Lanczos)."""
    if sp.issparse(K):
        from scipy.sparse.linalg import eigsh
        lam, X = eigsh(K.tocsc(), k=n, M=M.tocsc(), sigma=0.0, which="LM")
        order = np.argsort(lam)
        return lam[order], X[:, order]
    lam, X = sl.eigh(K, M, subset_by_index=[0, n - 1])
    return lam, X


def _solve(K, F):
    if sp.issparse(K):
        from scipy.sparse.linalg import splu
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
           int(n), bool(static_correction), sp.issparse(model.stiffness))
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
    K, M = _free_matrices(model)
    nf = K.shape[0]
    n = int(min(max(n, 1), nf))
    extra = min(4, nf - n)           # to see whether the n-th mode has a degenerate partner
    lam, X = _natural_modes(K, M, min(nf - 1, n + extra) if sp.issparse(K) else n + extra)
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


# ---------------------------------------------------------------------------------------------
# the reduced liquid


class ReducedLiquid(eqx.Module):
    """All tank liquid on a modal basis: d = V eta (eta: m modal coordinates, every tank's stacked).

    The invariants (see the module docstring) replace the dense N x N mass products of `Liquid`."""
    r: jax.Array          # (N, 3) node positions in the vessel frame (for scales and outputs)
    m_nodes: jax.Array    # (N,) lumped nodal masses (row sums of the scalar mass)
    U: jax.Array          # (m, N, 3) the basis as nodal fields (zero on the wall-normal dofs)
    mass: jax.Array       # total liquid mass
    S0: jax.Array         # (3,) sum_i m_i r_i
    U1: jax.Array         # (m, 3) sum_i m_i U_k,i
    Q0: jax.Array         # (3, 3) T(r, r)
    Q1: jax.Array         # (m, 3, 3) T(r, U_k)
    Q2: jax.Array         # (m, m, 3, 3) T(U_k, U_l)
    Mr: jax.Array         # (m, m) V^T M V (the identity for concrete values)
    Kr: jax.Array         # (m, m) V^T K V
    row_scale: jax.Array  # (m,) a mass per modal row, so that row / scale is an acceleration (m/s^2)
    n_nodes: int = eqx.field(static=True)
    Kdt: Optional[jax.Array] = None    # (m, 3) V^T K_dt
    Ktt: Optional[jax.Array] = None    # (3, 3)

    @property
    def nf(self) -> int:
        return int(self.Mr.shape[0])

    def full(self, eta):
        """(m,) modal coordinates -> (N, 3) nodal displacement field."""
        return jnp.einsum("k,knc->nc", eta, self.U)

    def first_moment(self, eta):
        return self.U1.T @ eta

    def _W(self, eta):
        """T(x, U_l) for the deformed positions x = r + U eta: (m, 3, 3)."""
        return self.Q1 + jnp.einsum("k,klab->lab", eta, self.Q2)

    def second_moment(self, eta, W=None):
        """J = T(x, x) = sum_ij Ms_ij x_i x_j^T (3x3)."""
        W = self._W(eta) if W is None else W
        return self.Q0 + jnp.einsum("l,lab->ab", eta, W + jnp.swapaxes(self.Q1, 1, 2))

    def rows(self, system, c, omega, eta_dot, acc, A, g_b):
        """The liquid's share of the residual of model.System.residual: (rigid translation rows
        (inertial), rigid rotation rows (body), modal rows), as the full model's at d = V eta."""
        eta, eta_dd = c.d, acc[6:]
        a0, alpha = acc[:3], acc[3:6]
        b = tv3(A, a0)
        W = self._W(eta)
        J = self.second_moment(eta, W)
        Sx = self.S0 + self.U1.T @ eta
        # translation: sum_j m_j a_j
        s = self.mass * b + self.U1.T @ eta_dd + jnp.cross(alpha, Sx)
        # rotation: sum_ij Ms_ij x_i x a_j
        Txa = jnp.einsum("l,lab->ab", eta_dd, W)
        f_r = jnp.cross(Sx, b) + _axial(Txa) + jnp.trace(J) * alpha - mv3(J, alpha)
        # modal rows: sum_ij Ms_ij U_k,i . a_j
        r_d = mv3(self.U1, b) + self.Mr @ eta_dd + mv3(_axial(W), alpha)
        if system.coriolis:
            v1 = self.U1.T @ eta_dot
            s = s + 2.0 * jnp.cross(omega, v1)
            Txv = jnp.einsum("l,lab->ab", eta_dot, W)
            f_r = f_r + 2.0 * (jnp.trace(Txv) * omega - tv3(Txv, omega))
            Tvu = jnp.einsum("l,lkab->kab", eta_dot, self.Q2)            # T(v, U_k)
            r_d = r_d + 2.0 * mv3(_axial(Tvu), omega)
        if system.centrifugal:
            s = s + jnp.cross(omega, jnp.cross(omega, Sx))
            f_r = f_r + jnp.cross(mv3(J, omega), omega)
            r_d = r_d + jnp.einsum("a,kba,b->k", omega, W, omega) - (omega @ omega) * jnp.trace(W, axis1=1, axis2=2)
        r_d = r_d - mv3(self.U1, g_b) + self.Kr @ eta
        if self.Kdt is not None:
            th, Jth = system.liquid_rotation(c.q, with_jacobian=True)
            r_d = r_d + mv3(self.Kdt, th)
            f_r = f_r + tv3(Jth, self.Kdt.T @ eta + mv3(self.Ktt, th))
        mD = self.U1.T @ eta
        if system.balanced:
            f_r = f_r - jnp.cross(mD, g_b)
        else:
            f_r = f_r - jnp.cross(self.S0 + mD, g_b)
        return mv3(A, s), f_r, r_d

    def kinetic_energy(self, A, V0, omega, eta, eta_dot):
        c = A.T @ V0
        W = self._W(eta)
        J = self.second_moment(eta, W)
        Sx = self.S0 + self.U1.T @ eta
        Txv = jnp.einsum("l,lab->ab", eta_dot, W)
        return 0.5 * (self.mass * c @ c + 2.0 * c @ (self.U1.T @ eta_dot) + 2.0 * c @ jnp.cross(omega, Sx)
                      + eta_dot @ (self.Mr @ eta_dot) + 2.0 * omega @ _axial(Txv)
                      + omega @ (jnp.trace(J) * omega - J @ omega))

    def potential_energy(self, system, q, eta, g_b):
        V = 0.5 * eta @ (self.Kr @ eta) - g_b @ (self.U1.T @ eta)
        if self.Kdt is not None:
            th = system.liquid_rotation(q)
            V = V + eta @ (self.Kdt @ th) + 0.5 * th @ (self.Ktt @ th)
        if not system.balanced:
            V = V - g_b @ self.S0
        return V

    def static_start(self, g_b):
        """The discrete hydrostatic equilibrium Kr eta = V^T F_g (exact with the static correction)."""
        return jnp.linalg.solve(self.Kr, self.U1 @ g_b)


def _axial(T):
    """sum_ij Ms_ij P_i x Q_j from T = T(P, Q): the axial vector of T's antisymmetric part (..., 3)."""
    return jnp.stack([T[..., 1, 2] - T[..., 2, 1], T[..., 2, 0] - T[..., 0, 2], T[..., 0, 1] - T[..., 1, 0]], axis=-1)


# ---------------------------------------------------------------------------------------------
# building it


def reduce_liquid(models, concrete_models, origins, offsets, reductions) -> ReducedLiquid:
    """The reduced liquid of every tank (stacked), from the per-tank `LiquidModel`s.

    `models` may hold traced values (then JAX arithmetic); `concrete_models` are the same tanks at
    the scene's values, from which the bases are computed (they are the `models` when concrete).
    `reductions` holds (modes, static_correction) per tank."""
    traced = any(m.traced for m in models)
    xp = jnp if traced else np
    N = sum(int(m.n_nodes) for m in models)
    Us, Kr_blocks, Mr_blocks, Kdt_rows, scales = [], [], [], [], []
    S0, Q0, mass, Ktt = 0.0, 0.0, 0.0, xp.zeros((3, 3))
    U1s, Q1s, Q2_blocks = [], [], []
    rs, ms = [], []
    coupled = any(m.rotation_coupling is not None for m in models)
    for model, cmodel, origin, off, (n, static) in zip(models, concrete_models, origins, offsets, reductions):
        basis = tank_basis(cmodel, origin, n, static)
        f = np.flatnonzero(np.asarray(model.free))
        Nt, m = int(model.n_nodes), basis.V.shape[1]
        Ut = np.zeros((m, 3 * Nt))
        Ut[:, f] = basis.V.T
        Ut = Ut.reshape(m, Nt, 3)
        r = xp.asarray(model.nodes) + xp.asarray(origin)[None, :]
        Ms = model.mass
        mvec = xp.asarray(Ms.sum(axis=1)).reshape(-1)
        MU = Ms @ Ut.transpose(1, 0, 2).reshape(Nt, 3 * m)            # (Nt, 3m)
        MU = xp.asarray(MU).reshape(Nt, m, 3).transpose(1, 0, 2)       # (m, Nt, 3)
        Mr_ = xp.asarray(Ms @ r)                                        # (Nt, 3)
        S0 = S0 + mvec @ r
        Q0 = Q0 + r.T @ Mr_
        mass = mass + mvec.sum()
        U1s.append(xp.einsum("i,kia->ka", mvec, Ut))
        Q1s.append(xp.einsum("ia,kib->kab", Mr_, Ut))                  # T(r, U_k) = (Ms r)^T U_k
        Q2_blocks.append(xp.einsum("kia,lib->klab", Ut, MU))
        Mr_blocks.append(xp.einsum("kia,lia->kl", Ut, MU))
        Kff = model.stiffness
        if sp.issparse(Kff):
            Kr_t = basis.V.T @ (Kff.tocsr()[f][:, f] @ basis.V)
        else:
            Kr_t = basis.V.T @ xp.asarray(Kff)[np.ix_(f, f)] @ basis.V
        Kr_blocks.append(0.5 * (Kr_t + Kr_t.T))
        if coupled:
            if model.rotation_coupling is not None:
                Kdt_rows.append(basis.V.T @ xp.asarray(model.rotation_coupling)[f])
                Ktt = Ktt + xp.asarray(model.rotation_stiffness)
            else:
                Kdt_rows.append(xp.zeros((m, 3)))
        scales.append(1.0 / np.abs(basis.V).max(axis=0))
        Us.append((off, Ut))
        rs.append(r)
        ms.append(mvec)
    mtot = sum(U.shape[0] for _, U in Us)
    U = np.zeros((mtot, N, 3))
    Q2 = xp.zeros((mtot, mtot, 3, 3))
    k = 0
    for (off, Ut), Q2t in zip(Us, Q2_blocks):
        mt, Nt = Ut.shape[0], Ut.shape[1]
        U[k:k + mt, off:off + Nt] = Ut
        if traced:
            Q2 = Q2.at[k:k + mt, k:k + mt].set(Q2t)
        else:
            Q2[k:k + mt, k:k + mt] = Q2t
        k += mt
    if traced:
        from jax.scipy.linalg import block_diag
    else:
        from scipy.linalg import block_diag
    return ReducedLiquid(
        r=jnp.asarray(xp.concatenate(rs)), m_nodes=jnp.asarray(xp.concatenate(ms)), U=jnp.asarray(U),
        mass=jnp.asarray(mass), S0=jnp.asarray(S0), U1=jnp.asarray(xp.concatenate(U1s)), Q0=jnp.asarray(Q0),
        Q1=jnp.asarray(xp.concatenate(Q1s)), Q2=jnp.asarray(Q2), Mr=jnp.asarray(block_diag(*Mr_blocks)),
        Kr=jnp.asarray(block_diag(*Kr_blocks)), row_scale=jnp.asarray(np.concatenate(scales)), n_nodes=N,
        Kdt=jnp.asarray(xp.concatenate(Kdt_rows)) if coupled else None, Ktt=jnp.asarray(Ktt) if coupled else None)


def is_reduced(liquid) -> bool:
    return isinstance(liquid, ReducedLiquid)


__all__ = ["ReducedLiquid", "TankBasis", "reduce_liquid", "tank_basis", "is_reduced", "skew"]
