"""The face-normal liquid ("rt", liquid/face/element.py) in an elastic tank: its wall faces' fluxes taken
from the walls' displacements.

With rigid walls a wall face's flux is held at zero. With elastic walls it is the volume the wall
sweeps over that face: q_f = int_f u_w . n dA, n the liquid's outward normal, u_w the wall's
displacement (bilinear over the face from its four corner nodes, which the wall mesh shares). That
is a constant linear map Tw from the walls' nodal unknowns to the wall faces' fluxes. Nothing ties
the tangential components: the liquid slides along the walls, as the RT0 field slides along any
face. The map is imposed by elimination, as liquid/walls.py slaves the nodal liquid's wall-normal
dofs: the unknowns are the free faces' fluxes and the walls' free nodal dofs, z = [q; w], and all
faces' fluxes are T z (identity on the free faces, Tw on the wall faces, zero elsewhere). Mass and
stiffness are T^T M T and T^T K T plus the walls' own: constant, symmetric, factored once.

The circulation (divergence-free fields with no flux through the free surface or the walls) is
K's kernel with the walls at rest, (N, 0), B N = 0. An ideal liquid keeps its absolute flow
irrotational (Kelvin): in the kinetic metric its relative field plus the tank's rotation theta x r
is orthogonal to every circulation field, N^T (L z + F theta) = 0, L the free-face rows of the
coupled mass (M T)[f] and F the load of the rotation fields. A moving wall with no flux through
the free faces is not irrotational: L has a wall part (M_fw Tw), and the penalty holds it. The
penalty is that of liquid/face/build.py absolute_rotation_penalty, on the coupled unknowns:
1/2 kappa (L z + F theta)^T Q (L z + F theta), Q = N (N^T M_ff N)^-1 N^T = M_ff^-1 - Y G^+ Y^T,
Y = M_ff^-1 B^T, G = B Y. Every circulation mode then sits at exactly omega^2 = kappa, and every
other mode (M-orthogonal to them) is untouched.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from .element import ROTATION_PENALTY_RATIO, FaceModel, _gauss, _loads, _Mixed, face_modes
from ...fem.mesh import box_gauss_points
from ..modes import Modes
from ..walls import WallModel, build_walls

_G2 = np.array([-1.0, 1.0]) / np.sqrt(3.0)
_QUAD = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])     # a face's corners in cyclic order


def face_area_weights(model: FaceModel, faces) -> np.ndarray:
    """(k, 4, 3): int_f N_a n dA for the four corners a of each face (bilinear N_a, n the outward
    normal of the face's element): q_f = sum_a w_fa . u_a for a displacement bilinear over the face.
    2 x 2 Gauss is exact (N_a times the bilinear area vector is of degree 2 in each direction)."""
    X = model.nodes[model.faces[faces]]                                  # (k, 4, 3)
    out = np.zeros(X.shape)
    for s in _G2:
        for t in _G2:
            N = (1 + _QUAD[:, 0] * s) * (1 + _QUAD[:, 1] * t) / 4.0
            dNs = _QUAD[:, 0] * (1 + _QUAD[:, 1] * t) / 4.0
            dNt = _QUAD[:, 1] * (1 + _QUAD[:, 0] * s) / 4.0
            area = np.cross(np.einsum("a,kai->ki", dNs, X), np.einsum("a,kai->ki", dNt, X))   # (k, 3)
            out += N[None, :, None] * area[:, None, :]
    # orient outwards from the face's (only) element
    owner = np.empty(len(model.faces), dtype=int)
    owner[model.element_faces.reshape(-1)] = np.repeat(np.arange(len(model.elements)), 6)
    centre = model.nodes[model.elements[owner[faces]]].mean(axis=1)
    flip = np.einsum("ki,ki->k", out.sum(axis=1), X.mean(axis=1) - centre) < 0
    out[flip] *= -1.0
    return out


def wall_faces(model: FaceModel) -> np.ndarray:
    """The liquid's wetted wall faces: on the boundary, not free surface, not collapsed."""
    count = np.bincount(model.element_faces.reshape(-1), minlength=len(model.faces))
    collapsed = np.array([len(set(f)) < 3 for f in model.faces])
    return np.flatnonzero((count == 1) & ~model.free & ~collapsed)


@dataclass(frozen=True, eq=False)
class FaceTankWithWalls:
    """The face-normal liquid and its walls on the unknowns z = [free faces' fluxes q (nq); walls'
    free nodal dofs w (nw)] (tank-local coordinates)."""
    model: FaceModel
    walls: Optional[WallModel]        # None for a wall given by its matrices alone (`couple_walls`)
    T: sp.csr_matrix                  # (F, nz) every face's flux from z
    wall_dofs: np.ndarray             # (nw,) the free wall dofs' indices in the walls' 3 Nw vector
    mass: np.ndarray                  # (nz, nz) T^T M T + the walls' mass
    stiffness: np.ndarray             # (nz, nz) T^T K T + the walls' stiffness (no penalty)
    wall_stiffness: np.ndarray        # (nw, nw)
    penalty: np.ndarray               # (nz, nz) kappa L^T Q L
    Kdt: np.ndarray                   # (nz, 3)
    Ktt: np.ndarray                   # (3, 3)
    kappa: float
    n_kernel: int                     # circulation modes (at omega^2 = kappa)

    @property
    def nq(self) -> int:
        return int(np.count_nonzero(self.model.free))

    @property
    def nz(self) -> int:
        return int(self.mass.shape[0])

    def fluxes(self, Z):
        """(k, nz) -> every face's flux (k, F)."""
        return (self.T @ np.atleast_2d(Z).T).T


def couple_walls(model: FaceModel, Tw, Mw, Kw, origin=(0.0, 0.0, 0.0), walls=None, wall_dofs=None,
                 kappa=None) -> FaceTankWithWalls:
    """Couple the liquid with walls whose unknowns w (nw) have mass Mw and stiffness Kw (nw, nw) and
    set the wall faces' fluxes Tw w (Tw (F, nw), zero on the free faces). `origin`: the tank's in the
    vessel frame (the rotation fields). kappa: the penalty's (default: ROTATION_PENALTY_RATIO times the
    highest of the rigid tank's 20 lowest sloshing modes, as at full order with rigid walls)."""
    f = np.flatnonzero(model.free)
    nq, nw = f.size, Mw.shape[0]
    Tw = sp.csr_matrix(Tw)
    if abs(Tw[f]).sum() > 0:
        raise ValueError("the walls set the flux of a free face")
    I = sp.coo_matrix((np.ones(nq), (f, np.arange(nq))), shape=(len(model.faces), nq))
    T = sp.hstack([I, Tw]).tocsr()
    M, K = model.mass, model.stiffness
    MT = (M @ T).toarray()
    Mz = T.T @ MT
    Kz = T.T @ (K @ T).toarray()
    Mz[nq:, nq:] += np.asarray(Mw)
    Kz[nq:, nq:] += np.asarray(Kw)
    mixed = _Mixed(model)
    Bd = mixed.B.toarray()
    Y = mixed.Mlu.solve(Bd.T)                                            # M_ff^-1 B^T
    G, Np = Bd @ Y, mixed.P                  # G's null vectors are the pools' uniform pressures
    alpha = np.trace(G) / G.shape[0]
    Gp = np.linalg.inv(G + alpha * Np @ Np.T) - Np @ Np.T / alpha
    Minv = mixed.Mlu.solve(np.eye(nq))
    Q = Minv - Y @ Gp @ Y.T
    Q = 0.5 * (Q + Q.T)
    L = MT[f]                                                            # (nq, nz)
    gauss = _gauss(model)
    r = gauss[0] + np.asarray(origin, dtype=float)
    rot = np.stack([np.cross(np.eye(3)[k], r) for k in range(3)])
    F = _loads(model, gauss, rot)[f]                                     # (nq, 3)
    if kappa is None:
        fm = face_modes(model, 20)
        slosh = [w for w, k in zip(fm.omega, fm.kind) if k == "sloshing"] or list(fm.omega)
        kappa = (ROTATION_PENALTY_RATIO * float(max(slosh))) ** 2
    QL, QF = Q @ L, Q @ F
    pen = kappa * (L.T @ QL)
    n_ker = nq - (len(model.elements) + len(model.top) - model.pools)
    return FaceTankWithWalls(model=model, walls=walls, T=T,
                             wall_dofs=np.arange(nw) if wall_dofs is None else wall_dofs,
                             mass=0.5 * (Mz + Mz.T), stiffness=0.5 * (Kz + Kz.T), wall_stiffness=np.asarray(Kw),
                             penalty=0.5 * (pen + pen.T), Kdt=kappa * (L.T @ QF), Ktt=kappa * (F.T @ QF),
                             kappa=float(kappa), n_kernel=n_ker)


def shell_flux_map(model: FaceModel, walls: WallModel):
    """(Tw (F, 3 Nw) sparse, faces): the wall faces' fluxes from the shell's nodal displacements,
    each wall face's corners found among the wall nodes (they coincide: liquid/walls.py wall_planes)."""
    faces = wall_faces(model)
    w = face_area_weights(model, faces)                                  # (k, 4, 3)
    scale = float(np.ptp(model.nodes, axis=0).max())
    corners = model.nodes[model.faces[faces]].reshape(-1, 3)
    key = lambda x: np.round(np.asarray(x) / (1e-7 * scale)).astype(np.int64)   # noqa: E731
    index = {tuple(k): j for j, k in enumerate(key(walls.nodes))}
    node = np.array([index.get(tuple(k), -1) for k in key(corners)])
    if np.any(node < 0):
        raise ValueError(f"liquid node {corners[np.flatnonzero(node < 0)[0]]} on a wall has no wall node")
    rows = np.repeat(faces, 12)
    cols = (3 * node.reshape(-1, 4)[:, :, None] + np.arange(3)).reshape(-1)
    Tw = sp.coo_matrix((w.reshape(-1), (rows, cols)), shape=(len(model.faces), 3 * len(walls.nodes))).tocsr()
    return Tw, faces


def build_face_tank_with_walls(tank, model: FaceModel, kappa=None) -> FaceTankWithWalls:
    """A scene tank's face-normal liquid (its model) in its elastic walls (liquid/walls.py build_walls:
    the open box of hexahedra held at its attachment face)."""
    ws = tank.wall_spec
    w = build_walls(tank.size, tank.fill_depth, tank.mesh, ws.thickness, ws.material.young, ws.material.poisson,
                    ws.material.density, wall_mesh=ws.mesh)
    free = np.flatnonzero(~np.repeat(w.held, 3))
    Tw, _ = shell_flux_map(model, w)
    M3 = np.kron(w.mass, np.eye(3))
    return couple_walls(model, Tw[:, free], M3[np.ix_(free, free)], w.stiffness[np.ix_(free, free)],
                        origin=tank.origin, walls=w, wall_dofs=free, kappa=kappa)


def wall_points(walls: WallModel, wall_dofs, offset: int, zero_slot: int):
    """The walls as particles at their elements' 2 x 2 x 2 Gauss points (their consistent mass
    exactly): (x (G, 3) tank-local, m (G,), N (G, 8) the corners' shape values, slots (G, 8, 3) each
    corner dof's unknown, offset + its index among the free wall dofs, or zero_slot where held)."""
    X = walls.nodes[walls.elements]
    rho = float(walls.total_mass / np.prod(X.max(axis=1) - X.min(axis=1), axis=1).sum())    # the walls' density
    slot_of = np.full(3 * len(walls.nodes), zero_slot)
    slot_of[wall_dofs] = offset + np.arange(len(wall_dofs))
    return box_gauss_points(walls.nodes, walls.elements, rho, slot_of)


def face_tank_modes(tw: FaceTankWithWalls, n: int = 10) -> Modes:
    """The n lowest modes of the liquid and its walls together (the hull held still), circulation
    modes left out and counted. Kinds: "wall" when the walls' strain holds most of the potential
    energy, else "sloshing" (the free surface's) or "acoustic". Solved as the largest of
    M x = (1 / lambda) (K + penalty) x, which resolves the low modes to round-off of themselves
    whatever the walls' stiffness (liquid/walls.py tank_modes)."""
    Kp = tw.stiffness + tw.penalty
    k = int(min(n + tw.n_kernel, tw.nz))
    mu, X = sl.eigh(tw.mass, Kp, subset_by_index=[tw.nz - k, tw.nz - 1])
    lam, X = 1.0 / mu[::-1], X[:, ::-1]
    total = np.einsum("ij,ik,kj->j", X, Kp, X)
    circ = np.einsum("ij,ik,kj->j", X, tw.penalty, X) / total
    keep = np.flatnonzero(circ < 0.5)[:n]
    lam, X, total = lam[keep], X[:, keep], total[keep]
    nq = tw.nq
    wall_e = np.einsum("ij,ik,kj->j", X[nq:], tw.wall_stiffness, X[nq:])
    Q = tw.fluxes(X.T)
    surf = np.einsum("if,if->i", Q, (tw.model.surface @ Q.T).T)
    wall_share = np.clip(wall_e / total, 0.0, 1.0)
    share = np.clip(surf / total, 0.0, 1.0)
    kind = tuple("wall" if w > 0.5 else ("sloshing" if s > 0.5 else "acoustic") for w, s in zip(wall_share, share))
    shapes = tw.model.nodal_fields(Q).reshape(len(keep), -1)
    return Modes(omega=np.sign(lam) * np.sqrt(np.abs(lam)), kind=kind, free_surface_share=share, shapes=shapes,
                 circulation=tw.n_kernel)
