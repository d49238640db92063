"""Natural modes of the liquid in a rigid tank, their classification, and the closed-form reference.

The modes solve ``K_ff x = omega^2 M_ff x`` on the free dofs of a ``NodalModel`` (dense
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
from scipy.sparse.linalg import eigsh

from .nodal.model import NodalModel, build_liquid
from ..fem.slip import rotate_matrix


KINDS = ("sloshing", "acoustic", "circulation", "spurious")


@dataclass(frozen=True, eq=False)
class Modes:
    omega: np.ndarray                 # (n,) rad/s, ascending (negative: -sqrt(-lambda), never expected)
    kind: tuple                       # (n,) one of KINDS
    free_surface_share: np.ndarray    # (n,) in [0, 1]
    shapes: np.ndarray                # (n, 3N) mass-normalised (x^T kron(M, I3) x = 1), on the tank's axes
    circulation: int = 0              # zero-frequency circulation modes left out ("rt": dim ker K)


def free_mass(model: NodalModel) -> np.ndarray:
    """kron(mass, I3) restricted to the free dofs, without forming the full 3N matrix."""
    f = np.flatnonzero(model.free)
    if model.frames is not None:                       # a shaped tank: on the nodes' frames
        return np.asarray(model.mass3())[np.ix_(f, f)]
    node, comp = f // 3, f % 3
    return model.mass[np.ix_(node, node)] * (comp[:, None] == comp[None, :])


def free_matrices(model):
    """(K_ff, M_ff) on the free dofs: dense NumPy, or SciPy CSR for a sparse model."""
    f = np.flatnonzero(np.asarray(model.free))
    if sp.issparse(model.stiffness):
        K = model.stiffness.tocsr()[f][:, f]
        M = sp.kron(model.mass, sp.eye(3), format="csr")
        if model.frames is not None:
            M = rotate_matrix(np, M, model.frames)
        M = M.tocsr()[f][:, f]
        return 0.5 * (K + K.T), M
    K = np.asarray(model.stiffness)[np.ix_(f, f)]
    return 0.5 * (K + K.T), free_mass(model)


def natural_modes(K, M, n):
    """The n lowest (omega^2, shapes) of K x = omega^2 M x (dense eigh, or shift-invert Lanczos)."""
    if sp.issparse(K):
        lam, X = eigsh(K.tocsc(), k=n, M=M.tocsc(), sigma=0.0, which="LM")
        order = np.argsort(lam)
        return lam[order], X[:, order]
    lam, X = sl.eigh(K, M, subset_by_index=[0, n - 1])
    return lam, X


def liquid_modes(model: NodalModel, n: int = 10) -> Modes:
    """The n lowest modes of the liquid with the tank held fixed (a model built with sparse=True:
    shift-invert Lanczos on its sparse matrices, for meshes whose dense matrices would not fit)."""
    f = model.free
    K, M = free_matrices(model)
    n = int(min(n, K.shape[0] - (1 if sp.issparse(K) else 0)))
    lam, X = natural_modes(K, M, n)
    omega = np.sign(lam) * np.sqrt(np.abs(lam))
    shapes = np.zeros((n, f.size))
    shapes[:, f] = X.T
    share, kind = classify(model, shapes)
    if model.frames is not None:                   # nodal fields on the tank's axes
        shapes = model.to_global(shapes.reshape(n, -1, 3)).reshape(n, -1)
    return Modes(omega=omega, kind=kind, free_surface_share=share, shapes=shapes)


def energy_shares(model: NodalModel, shapes: np.ndarray) -> dict:
    """Fractions of each mode's potential energy held by the measures in ``model.parts``."""
    shapes = np.atleast_2d(shapes)
    total = np.einsum("ij,ij->i", shapes, (model.stiffness @ shapes.T).T)
    total = np.where(total > 0, total, np.inf)
    out = {}
    for name, part in model.parts.items():
        e = np.einsum("ij,ij->i", shapes, (part @ shapes.T).T)
        out[name] = np.clip(e / total, 0.0, 1.0)
    return out


def classify(model: NodalModel, shapes: np.ndarray):
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


#: what each kind of mode but sloshing is, for the listing that sets them apart (`jaxslosh modes`)
KIND_NOTES = {
    "acoustic": "compression of the liquid",
    "circulation": "a numerical mode: vortical flow held by the element's rotation penalty (an ideal liquid "
                   "has it at zero frequency)",
    "spurious": "a numerical mode: a surface pattern about two elements long that the mesh cannot carry as a "
                "wave (its energy is in the element's surface hourglass and bending terms)",
    "wall": "the tank's elastic walls (a mode of the walls and the liquid together)",
}


def others_in_band(kinds) -> list:
    """Indices of the modes (ascending frequency) that are not sloshing and lie below the highest
    sloshing mode listed: the numerical modes among the sloshing band."""
    kinds = list(kinds)
    slosh = [i for i, k in enumerate(kinds) if k == "sloshing"]
    if not slosh:
        return []
    return [i for i in range(slosh[-1]) if kinds[i] != "sloshing"]


def analytic_sloshing_table(a: float, b: float, h: float, g: float, n: int):
    """The n lowest (omega, m, n) of a rigid a x b tank filled to h: omega^2 = g k tanh(k h),
    k = pi sqrt((m/a)^2 + (n/b)^2), m, n >= 0 not both zero (docs/theory.md, closed forms)."""
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


def effective_roll_inertia(size, mesh, element="stabilized", density=1000.0, sound_speed=1500.0, gravity=9.81,
                           absolute_rotation=True, omegas=(0.02, 0.04)):
    """Low-frequency effective roll inertia of the liquid in a full, closed tank (a lid on top).

    The tank rolls harmonically about the x axis through the liquid's centroid, theta(t) =
    theta0 exp(i W t), slowly (W well below every liquid mode); the liquid's relative motion is
    solved in the frequency domain, (K - W^2 M) d = W^2 M (e_x x r) theta0 - K_dt theta0, and the
    moment the tank must apply, -W^2 I_eff theta0 + (a stiffness), is fitted over two frequencies.
    Returns (I_eff, I_frozen_discrete, I_frozen_exact) in kg m^2. With `absolute_rotation=False`
    the rotation penalty acts on the relative rotation only (the liquid turns with the tank).
    An inviscid liquid does not spin up: Stokes-Joukowski gives 0.1565 I_frozen for a square
    section, 0.45 for a 2:1 one (docs/theory.md item 5)."""
    a, b, h = (float(s) for s in size)
    m = build_liquid((a, b, h), h, mesh, density, sound_speed, gravity, element=element)
    nodes = np.asarray(m.nodes)
    free = np.asarray(m.free).reshape(-1, 3).copy()
    free[np.abs(nodes[:, 2] - h) < 1e-9 * h, 2] = False                # the lid
    f = free.reshape(-1)
    M3 = np.kron(np.asarray(m.mass), np.eye(3))
    K = np.asarray(m.stiffness)
    r = nodes - np.array([a / 2, b / 2, h / 2])
    ex = np.array([1.0, 0.0, 0.0])
    u_rot = np.cross(ex, r).reshape(-1)                                 # rigid rotation field per unit theta
    C = np.asarray(m.rotation_coupling) if (absolute_rotation and m.rotation_coupling is not None) else None
    moments = []
    for W in omegas:
        rhs = W ** 2 * (M3 @ u_rot)
        if C is not None:
            rhs = rhs - C[:, 0]
        d = np.zeros(3 * len(nodes))
        d[f] = np.linalg.solve((K - W ** 2 * M3)[np.ix_(f, f)], rhs[f])
        # rate of the liquid's angular momentum about the centroid, per unit theta0
        Hdot = -W ** 2 * np.cross(r, (M3 @ (d + u_rot)).reshape(-1, 3)).sum(axis=0)[0]
        reaction = 0.0
        if C is not None:
            reaction = C[:, 0] @ d + np.asarray(m.rotation_stiffness)[0, 0]
        moments.append(Hdot + reaction)
    W2 = np.array(omegas) ** 2
    I_eff = -(moments[1] - moments[0]) / (W2[1] - W2[0])
    I_frozen_discrete = u_rot @ M3 @ u_rot
    I_frozen_exact = density * a * b * h * (b * b + h * h) / 12.0
    return float(I_eff), float(I_frozen_discrete), float(I_frozen_exact)
