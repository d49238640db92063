"""Natural modes of the liquid in a rigid tank, their classification, and the closed-form reference.

The modes solve ``K_ff x = omega^2 M_ff x`` on the free dofs of a ``LiquidModel`` (dense
``scipy.linalg.eigh``). Each mode is classified by where its potential energy ``1/2 x^T K x`` sits:

* ``free_surface_share`` -- the gravity energy of the free surface over the total: for the
  "stabilized" form ``1/2 rho g sum_faces A (mean u_z)^2``, for "paper" ``1/2 rho g int_FS u_z^2``
  (clipped to [0, 1]);
* ``"sloshing"``    free-surface share > 0.5 (a gravity wave);
* ``"acoustic"``    otherwise, if compression (``rho c^2 (div u)^2``, eq. 30) holds > 0.5 of it;
* ``"circulation"`` otherwise, if the rotation penalty (or the p0 |curl u|^2 part of the paper's
  eq. 31) holds > 0.5 of it: a vortical mode, physically of zero frequency, held by the penalty;
* ``"spurious"``    anything else: energy mainly in the surface hourglass / bending terms of the
  "stabilized" form -- surface patterns of about two elements' wavelength, which the mesh cannot
  carry as sloshing (on the 5x5x5 mesh of the 5x5x3 m tank the first is at 5.9 rad/s, 1.6x the
  fourth distinct sloshing frequency).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from .liquid import LiquidModel

KINDS = ("sloshing", "acoustic", "circulation", "spurious")


@dataclass(frozen=True, eq=False)
class Modes:
    omega: np.ndarray                 # (n,) rad/s, ascending (negative: -sqrt(-lambda), never expected)
    kind: tuple                       # (n,) one of KINDS
    free_surface_share: np.ndarray    # (n,) in [0, 1]
    shapes: np.ndarray                # (n, 3N) mass-normalised (x^T kron(M, I3) x = 1), zero on fixed dofs


def free_mass(model: LiquidModel) -> np.ndarray:
    """kron(mass, I3) restricted to the free dofs, without forming the full 3N matrix."""
    f = np.flatnonzero(model.free)
    node, comp = f // 3, f % 3
    return model.mass[np.ix_(node, node)] * (comp[:, None] == comp[None, :])


def liquid_modes(model: LiquidModel, n: int = 10) -> Modes:
    """The n lowest modes of the liquid with the tank held fixed (a model built with sparse=True:
    shift-invert Lanczos on its sparse matrices, for meshes whose dense matrices would not fit)."""
    from .reduction import _free_matrices, _natural_modes
    f = model.free
    K, M = _free_matrices(model)
    n = int(min(n, K.shape[0] - (1 if sp.issparse(K) else 0)))
    lam, X = _natural_modes(K, M, n)
    omega = np.sign(lam) * np.sqrt(np.abs(lam))
    shapes = np.zeros((n, f.size))
    shapes[:, f] = X.T
    share, kind = classify(model, shapes)
    return Modes(omega=omega, kind=kind, free_surface_share=share, shapes=shapes)


def energy_shares(model: LiquidModel, shapes: np.ndarray) -> dict:
    """Fractions of each mode's potential energy held by the measures in ``model.parts``."""
    shapes = np.atleast_2d(shapes)
    total = np.einsum("ij,ij->i", shapes, (model.stiffness @ shapes.T).T)
    total = np.where(total > 0, total, np.inf)
    out = {}
    for name, part in model.parts.items():
        e = np.einsum("ij,ij->i", shapes, (part @ shapes.T).T)
        out[name] = np.clip(e / total, 0.0, 1.0)
    return out


def classify(model: LiquidModel, shapes: np.ndarray):
    """(free_surface_share, kinds) of the given mode shapes (rows)."""
    s = energy_shares(model, shapes)
    kinds = []
    for i in range(len(s["free_surface"])):
        if s["free_surface"][i] > 0.5:
            kinds.append("sloshing")
        elif s["acoustic"][i] > 0.5:
            kinds.append("acoustic")
        elif s["rotation"][i] > 0.5:
            kinds.append("circulation")
        else:
            kinds.append("spurious")
    return s["free_surface"], tuple(kinds)


def analytic_sloshing_table(a: float, b: float, h: float, g: float, n: int):
    """The n lowest (omega, m, n) of a rigid a x b tank filled to h: omega^2 = g k tanh(k h),
    k = pi sqrt((m/a)^2 + (n/b)^2), m, n >= 0 not both zero (PHYSICS.md section 3)."""
    top = int(n) + 1
    rows = []
    for m in range(top + 1):
        for q in range(top + 1):
            if m == 0 and q == 0:
                continue
            k = np.pi * np.hypot(m / a, q / b)
            rows.append((float(np.sqrt(g * k * np.tanh(k * h))), m, q))
    rows.sort()
    return rows[:n]


def analytic_sloshing_omegas(a: float, b: float, h: float, g: float, n: int) -> np.ndarray:
    """The n lowest analytic sloshing angular frequencies (rad/s), sorted, degenerate pairs repeated."""
    return np.array([r[0] for r in analytic_sloshing_table(a, b, h, g, n)])
