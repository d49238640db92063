"""Natural modes of the coupled system (vessel, liquid, structures) from the linearisation about
rest (linear.py): the quadratic eigenproblem

    [lambda^2 M(w) + lambda C(w) + K] x = 0,

solved as the generalized eigenproblem of its companion pencil (which takes the algebraic
unknowns of structures' interfaces: their infinite eigenvalues are dropped). The hull's radiation
depends on frequency, so each mode is found by iteration: the tables' A(w), B(w) (the vessel's and
those of `[[bodies]]` and their coupling, assemble/bodyhydro.py) at the mode's own
damped frequency w = Im(lambda), until it stops moving (a fixed point, within 1e-10); modes above
the tables' frequencies keep the residual's own A_inf and no radiation damping (infinite frequency),
modes below the lowest tabulated frequency take the lowest's. Without radiation tables the matrices
do not depend on frequency and one solve gives every mode.

Each mode reports its undamped natural frequency |lambda|, its damped frequency Im(lambda) (where a
free decay's spectrum peaks), its damping ratio -Re(lambda) / |lambda|, and its dominant unknown:
the group of unknowns (a rigid dof, the liquid, a structure) holding the largest share of the
mode's kinetic energy x^H M x. Rigid-body modes without restoring (lambda = 0: surge and sway of a
free-floating hull whose radiation damping vanishes at zero frequency) and overdamped ones (real
lambda) are not oscillations and are counted apart.

A mode whose potential energy lies mostly (PENALTY_SHARE) in the stabilized liquid element's
rotation penalty (liquid/nodal/element.py, term 3: kappa |P curl d + 2 theta|^2, which holds the
liquid's absolute rotation) is labelled "liquid rotation penalty (numerical)": a slow yaw of the
hull against the liquid its tank holds still, restored by the penalty alone (no hydrostatics acts on
yaw). An inviscid liquid has no such stiffness; the mode is an artefact of the element, not of the
ship. Its share is x^H K_pen x / x^H K x, K_pen the penalty's d-d block (the liquid model's
"rotation" part) with its d-theta and theta-theta blocks (liquid/base.RotationPenalty).
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg as sl
import scipy.sparse.linalg as spla

from ..liquid.base import rotation_penalty
from ..scene.types import Scene
from .linear import Linearisation, linearise
from ..assemble.bodyhydro import frequency_terms, radiating_bodies
from .rao import frequency_matrices, hull_tables, solve_equilibrated

#: |lambda| below this (rad/s) is a rigid-body mode without restoring
ZERO = 1e-6

#: a mode with at least this share of its potential energy in the liquid's rotation penalty is
#: labelled PENALTY_LABEL (the paper example's slow yaw: 1.0000; every other mode there: < 0.001)
PENALTY_SHARE = 0.5
PENALTY_LABEL = "liquid rotation penalty (numerical)"


class CoupledModes(NamedTuple):
    omega: np.ndarray          # (k,) undamped natural frequencies |lambda|, rad/s, ascending
    damped: np.ndarray         # (k,) damped frequencies Im(lambda), rad/s
    damping_ratio: np.ndarray  # (k,)
    dominant: tuple            # (k,) the group of unknowns with the largest kinetic-energy share
    shares: list               # (k,) {group: share of x^H M x}
    shapes: np.ndarray         # (n, k) complex mode shapes over the unknowns
    radiation: tuple           # (k,) "table" (A, B at the mode's frequency), "infinite" or "none"
    not_oscillating: int       # rigid-body (lambda = 0) and overdamped modes among those found
    penalty_share: np.ndarray = np.zeros(0)   # (k,) share of x^H K x in the liquid's rotation penalty
    label: tuple = ()          # (k,) `dominant`, or PENALTY_LABEL for a mode the penalty holds


def _lowest(lin: Linearisation, M, C, k: int):
    """The k eigenvalues of the companion pencil nearest zero, by shift-invert Arnoldi (one LU of
    the 2n pencil; a dense eig of it takes a hundred times longer), with their shapes (n, k)."""
    n = lin.n
    Z, I = np.zeros((n, n)), np.eye(n)
    A = np.block([[Z, I], [-lin.K, -C]])
    B = np.block([[I, Z], [Z, M]])
    s = 1.0 / np.maximum(np.abs(A).max(axis=1) + np.abs(B).max(axis=1), 1e-300)   # the acoustic rows: 1e10
    A, B = A * s[:, None], B * s[:, None]
    # a shift off zero: surge and sway of a free hull have lambda = 0 exactly
    if 2 * n <= max(300, 2 * k):           # small: all of them at once
        lam, V = sl.eig(A, B)
        ok = np.isfinite(lam)
        return lam[ok], V[:n, ok]
    sigma = 1e-3 * (1.0 + 0.5j)
    lu = sl.lu_factor(A - sigma * B)
    op = spla.LinearOperator((2 * n, 2 * n), matvec=lambda v: sl.lu_solve(lu, B @ v), dtype=complex)
    mu, W = spla.eigs(op, k=k, which="LM", v0=np.ones(2 * n, dtype=complex))
    ok = np.abs(mu) > 0
    return sigma + 1.0 / mu[ok], W[:n, ok]


def _refine(lin: Linearisation, matrices, lam, x, tol, max_iterations):
    """The mode near (lam, x) of T(lam) = lam^2 M(w) + lam C(w) + K with the radiation at
    w = Im(lam): Newton's iteration for nonlinear eigenproblems (inverse iteration with the
    update lam - x^H x / x^H T^{-1} T' x), the matrices taken anew at each step, to the fixed point."""
    how = "none"
    for _ in range(max_iterations):
        M, C, how = matrices(lam.imag)
        T = lam * lam * M + lam * C + lin.K
        u = solve_equilibrated(T, ((2.0 * lam * M + C) @ x)[:, None])[:, 0]
        step = np.vdot(x, x) / np.vdot(x, u)
        lam, x = lam - step, u / np.linalg.norm(u)
        if abs(step) <= tol * abs(lam):
            break
    return lam, x, how


def _shares(lin: Linearisation, M, x):
    e = np.real(np.conj(x) * (M @ x))
    total = np.sum(e)
    out = {}
    for label, ei in zip(lin.labels, e):
        out[label] = out.get(label, 0.0) + ei / total
    return out


def coupled_modes(scene: Scene, n: int = 10, *, params=None, linearisation=None, tol: float = 1e-10,
                  max_iterations: int = 50) -> CoupledModes:
    """The `n` lowest oscillating modes of the coupled system (see the module's docstring)."""
    lin = linearisation if linearisation is not None else linearise(scene, params)
    tables = hull_tables(scene, ())
    radiation = bool(scene.effects.radiation and tables is not None and tables.added_mass is not None)

    bodies = radiating_bodies(scene)        # [[bodies]] with radiation tables (assemble/bodyhydro.py)

    def matrices(w):
        if bodies:                          # theirs at the mode's frequency, within their tables' range
            M, C = frequency_matrices(lin, tables, True, min(max(w, tables.omega[0]), tables.omega[-1])) \
                if radiation and w <= tables.omega[-1] else (lin.M.copy(), lin.C.copy())
            dA, dB, _ = frequency_terms(scene, [min(max(w, bodies[0]), bodies[1])], ())
            if w <= bodies[1]:
                N = dA.shape[1]
                M[:N, :N] += dA[0]
                C[:N, :N] += dB[0]
            return M, C, "table"
        if not radiation:
            return lin.M, lin.C, "none"
        if w > tables.omega[-1]:
            return lin.M, lin.C, "infinite"
        M, C = frequency_matrices(lin, tables, True, max(w, tables.omega[0]))
        return M, C, "table"

    # the lowest modes of the residual's own matrices (A_inf on the hull), then each refined with the
    # radiation at its frequency; a few spare ones in case radiation reorders neighbours
    lam, V = _lowest(lin, lin.M, lin.C, 2 * n + 12)
    osc = (lam.imag > ZERO) & (np.abs(lam) > ZERO)
    # an oscillating mode is a conjugate pair; a rigid-body mode without restoring (lambda = 0, twice)
    # or an overdamped one is a pair of real eigenvalues
    left_out = int(np.ceil(np.sum(np.abs(lam.imag) <= ZERO) / 2))
    lam, V = lam[osc], V[:, osc]
    order = np.argsort(np.abs(lam))
    out = []
    for k in order[:n + 4]:
        lk, xk, how = _refine(lin, matrices, lam[k], V[:, k], tol, max_iterations) if radiation or bodies else \
            (lam[k], V[:, k], "none")
        M, _, how = matrices(lk.imag)
        out.append((lk, xk, how, _shares(lin, M, xk)))
    out.sort(key=lambda o: abs(o[0]))
    out = out[:n]
    lam = np.array([o[0] for o in out])
    shares = [o[3] for o in out]
    dominant = tuple(max(s, key=s.get) for s in shares)
    shapes = np.stack([o[1] for o in out], axis=1) if out else np.zeros((lin.n, 0), complex)
    zeta = -lam.real / np.abs(lam)
    zeta = np.where(np.abs(zeta) < 1e-9, 0.0, zeta)      # round-off of undamped modes
    pshare = penalty_shares(lin, shapes)
    label = tuple(PENALTY_LABEL if p >= PENALTY_SHARE else d for p, d in zip(pshare, dominant))
    return CoupledModes(np.abs(lam), lam.imag, zeta, dominant, shares, shapes,
                        tuple(o[2] for o in out), left_out, pshare, label)


def penalty_shares(lin: Linearisation, shapes) -> np.ndarray:
    """(k,) the share of each mode's potential energy x^H K x held by the liquid's rotation penalty
    (see the module's docstring); zeros where the scene has none (no liquid, the "paper" element,
    a liquid built without its energy parts)."""
    b = lin.built
    k = shapes.shape[1]
    pen = rotation_penalty(b.system.terms)
    parts = [tb.model.parts.get("rotation") if getattr(tb.model, "parts", None) else None for tb in b.tanks]
    if pen is None or k == 0 or any(p is None for p in parts):
        return np.zeros(k)
    lay = b.system.layout()
    start = lay.n_small                         # the deformable block (vessel-frame structures too: linear.py)
    liq = np.arange(start, start + lay.nf)
    L = b.system.liquid
    nodal = jax.jit(jax.vmap(lambda d: L.nodal_fields(L.frame_field(d)), in_axes=1))
    D = np.asarray(nodal(jnp.asarray(shapes[liq].real))) + 1j * np.asarray(nodal(jnp.asarray(shapes[liq].imag)))
    E = np.zeros(k)
    for tb, P in zip(b.tanks, parts):
        n = tb.model.n_nodes
        Dt = D[:, tb.node_offset:tb.node_offset + n]                 # (k, N_t, 3), tank axes
        if tb.model.frames is not None:                               # the model's parts: in the nodes' frames
            Dt = np.einsum("nji,knj->kni", np.asarray(tb.model.frames), Dt)
        v = Dt.reshape(k, -1)
        E += np.real(np.einsum("ki,ki->k", v.conj(), (P @ v.T).T))
    th, d = shapes[3:6], shapes[liq]
    Kdt, Ktt = np.asarray(pen.Kdt), np.asarray(pen.Ktt)
    E += np.real(2 * np.einsum("ik,ik->k", th.conj(), Kdt.T @ d) + np.einsum("ik,ik->k", th.conj(), Ktt @ th))
    total = np.real(np.einsum("ik,ik->k", shapes.conj(), lin.K @ shapes))
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(np.abs(total) > 0, E / total, 0.0)
    return np.clip(np.nan_to_num(share), 0.0, None)
