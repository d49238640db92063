"""The face-normal liquid element ("rt"): lowest-order Raviart-Thomas displacements on hexahedra.

The stabilized element (fem/liquid_element.py) keeps the displacement at the nodes and holds the
vortical fields with a one-point divergence and an axial curl penalty. That pair leaves exactly as
many free fields as a box has sloshing modes, so every extra line of constrained nodes -- a duct's
corner, a baffle's foot or edge, a hopper's kink -- removes a whole mode (locking). The face-normal
element avoids the constraint count altogether (Bermúdez & Rodríguez, Comput. Methods Appl. Mech.
Engrg. 119 (1994) 355-370; Bermúdez, Durán, Muschietti, Rodríguez, Solomin, SIAM J. Numer. Anal.
32 (1995) 1280-1295):

* one unknown per face of the mesh: ``q_f``, the volume the liquid moves through the face (m^3), in
  the direction of the face's first element's outward normal; walls (every boundary face but the
  free surface, both faces of a plate, and faces collapsed to a line) have ``q_f = 0``;
* the displacement inside an element is the Piola map of the reference RT0 field: on the reference
  cube [-1, 1]^3 the field of face (axis a, side s) is ``s (1 + s xi_a) / 8 e_a`` (unit outward flux
  through that face, none through the others), mapped by ``u = J u_ref / det J``, which keeps every
  face's flux. Its normal component is continuous across faces, its tangential components are not:
  the liquid slides freely along walls and plates, whatever their shape, with no node frames;
* energies (PHYSICS.md section 2): compression ``1/2 rho c^2 (sum_f s_ef q_f)^2 / V_e`` (the flux
  out of an element is its volume change, exactly); free surface ``1/2 rho g q_f^2 / A_f`` on each
  top face (the gravity energy of the volume it raises, as the stabilized element's face mean);
  kinetic energy ``1/2 rho int |u|^2`` with 2 x 2 x 2 Gauss points (the consistent RT0 mass);
* no rotation penalty. Divergence-free fields with no flux through the free surface have no energy:
  they are the circulation modes, physically of zero frequency, and here exactly at zero (the kernel
  of K); the sloshing modes are M-orthogonal to them and are found by a shifted Lanczos that skips
  the kernel (`face_modes`).

NumPy and SciPy only; modes only (the time-domain coupling uses the nodal elements).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .mesh import GAUSS8, HEX_CORNERS
from .slip import HEX_FACES

#: the reference face of each row of HEX_FACES: (axis, side)
_FACE_AXIS = np.array([2, 2, 1, 0, 1, 0])
_FACE_SIDE = np.array([-1.0, 1.0, -1.0, 1.0, 1.0, -1.0])


@dataclass(frozen=True, eq=False)
class FaceLiquid:
    """The face-normal liquid model of one tank (tank-local coordinates, SI).

    ``faces`` (F, 4) node indices of every distinct face; ``element_faces`` (E, 6) and ``signs`` (E, 6):
    each element's faces (HEX_FACES order) and +1 where the face's unknown is the element's outward
    flux, -1 where it is inward; ``free`` (F,) the faces whose flux is unknown (interior faces and the
    free surface); ``top`` (T,) the free-surface faces; matrices on all F faces (sparse CSR)."""

    nodes: np.ndarray
    elements: np.ndarray
    faces: np.ndarray
    element_faces: np.ndarray
    signs: np.ndarray
    free: np.ndarray
    top: np.ndarray
    top_area: np.ndarray
    volume: np.ndarray
    mass: sp.csr_matrix
    acoustic: sp.csr_matrix
    surface: sp.csr_matrix
    density: float
    sound_speed: float
    gravity: float
    depth: float

    @property
    def stiffness(self):
        return (self.acoustic + self.surface).tocsr()

    @property
    def pools(self) -> int:
        """Separate pools of liquid (elements joined through free faces)."""
        from scipy.sparse.csgraph import connected_components
        E = len(self.elements)
        rows = np.repeat(np.arange(E), 6)
        cols = self.element_faces.reshape(-1)
        keep = self.free[cols]
        A = sp.coo_matrix((np.ones(keep.sum()), (rows[keep], cols[keep])), shape=(E, len(self.faces))).tocsr()
        return int(connected_components(A @ A.T, directed=False)[0])

    def displacement_at(self, q, element, xi):
        """Displacements (P, 3) at reference points xi (P, 3) of the given elements (P,), for face
        fluxes q (F,)."""
        X = self.nodes[self.elements[element]]                       # (P, 8, 3)
        J = np.einsum("pai,pak->pik", X, _shape_gradients(xi))
        detJ = np.linalg.det(J)
        ql = q[self.element_faces[element]] * self.signs[element]    # (P, 6) outward fluxes
        ref = _reference_fields(xi)                                  # (P, 6, 3)
        return np.einsum("pik,pfk,pf->pi", J, ref, ql) / detJ[:, None]

    def nodal_field(self, q):
        """A nodal displacement field (N, 3): each node the mean of its elements' fields there (for
        plots and probes; the model's own field is the element-wise one)."""
        E = len(self.elements)
        xi = np.tile(HEX_CORNERS, (E, 1))
        element = np.repeat(np.arange(E), 8)
        u = self.displacement_at(q, element, xi)
        idx = self.elements.reshape(-1)
        out = np.zeros((len(self.nodes), 3))
        np.add.at(out, idx, u)
        count = np.bincount(idx, minlength=len(self.nodes))
        return out / np.maximum(count, 1)[:, None]


def _shape_gradients(xi):
    """d N_a / d xi_k (P, 8, 3) of the trilinear hex at points xi (P, 3)."""
    xi = np.atleast_2d(xi)
    C = HEX_CORNERS[None]                                           # (1, 8, 3)
    one = 1.0 + C * xi[:, None, :]                                  # (P, 8, 3)
    out = np.empty((len(xi), 8, 3))
    for k in range(3):
        others = [j for j in range(3) if j != k]
        out[:, :, k] = C[:, :, k] * one[:, :, others[0]] * one[:, :, others[1]] / 8.0
    return out


def _reference_fields(xi):
    """The six reference RT0 fields (P, 6, 3) at points xi (P, 3), HEX_FACES order, unit outward flux."""
    xi = np.atleast_2d(xi)
    out = np.zeros((len(xi), 6, 3))
    for f in range(6):
        a, s = _FACE_AXIS[f], _FACE_SIDE[f]
        out[:, f, a] = s * (1.0 + s * xi[:, a]) / 8.0
    return out


def face_topology(elements):
    """(faces (F, 4), element_faces (E, 6), signs (E, 6), boundary (F,) bool, collapsed (F,) bool)."""
    E = len(elements)
    local = elements[:, HEX_FACES].reshape(-1, 4)
    key = np.sort(local, axis=1)
    uniq, first, inv, counts = np.unique(key, axis=0, return_index=True, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    faces = local[first]
    collapsed = np.array([len(set(f)) < 3 for f in uniq])
    owner = np.repeat(np.arange(E), 6)
    # the unknown is the outward flux of the face's first element (lowest index) -- np.unique's
    # `first` is the first occurrence, which is that element's
    signs = np.where(owner == owner[first][inv], 1.0, -1.0).reshape(E, 6)
    if np.any((counts > 2) & ~collapsed):
        raise ValueError("the mesh has a face shared by more than two elements")
    return faces, inv.reshape(E, 6), signs, counts == 1, collapsed


def build_face_liquid(nodes, elements, depth, density, sound_speed, gravity) -> FaceLiquid:
    """The face-normal model of the liquid meshed by hexahedra ``elements`` (positively oriented;
    a collapsed face allowed) at rest below the free surface z = ``depth``."""
    nodes = np.asarray(nodes, dtype=float)
    elements = np.asarray(elements, dtype=int)
    rho, c, g = float(density), float(sound_speed), float(gravity)
    faces, element_faces, signs, on_boundary, collapsed = face_topology(elements)
    scale = float(np.ptp(nodes, axis=0).max())
    Xf = nodes[faces]
    flat_top = np.all(np.abs(Xf[:, :, 2] - depth) < 1e-9 * scale, axis=1)
    # a top face must open upwards: its element lies below it
    top = np.flatnonzero(on_boundary & flat_top & ~collapsed)
    free = ~on_boundary & ~collapsed
    free[top] = True
    normal = 0.5 * np.cross(Xf[top, 2] - Xf[top, 0], Xf[top, 3] - Xf[top, 1])
    top_area = np.abs(normal[:, 2])

    # element matrices (vectorized over elements and Gauss points)
    X = nodes[elements]                                            # (E, 8, 3)
    dN = _shape_gradients(GAUSS8)                                  # (8 gp, 8, 3)
    J = np.einsum("eai,pak->epik", X, dN)                          # (E, P, 3, 3)
    detJ = np.linalg.det(J)
    if np.any(detJ <= 0):
        bad = int(np.flatnonzero((detJ <= 0).any(axis=1))[0])
        raise ValueError(f"element {bad} is inverted or degenerate at a Gauss point")
    volume = detJ.sum(axis=1)
    ref = _reference_fields(GAUSS8)                                # (P, 6, 3)
    phys = np.einsum("epik,pfk->epfi", J, ref) / detJ[:, :, None, None]
    Me = rho * np.einsum("epfi,epgi,ep->efg", phys, phys, detJ)    # (E, 6, 6)
    Me = Me * signs[:, :, None] * signs[:, None, :]

    nF = len(faces)
    rows = np.repeat(element_faces, 6, axis=1).reshape(-1)
    cols = np.tile(element_faces, (1, 6)).reshape(-1)
    M = sp.coo_matrix((Me.reshape(-1), (rows, cols)), shape=(nF, nF)).tocsr()
    E = len(elements)
    D = sp.coo_matrix((signs.reshape(-1), (np.repeat(np.arange(E), 6), element_faces.reshape(-1))),
                      shape=(E, nF)).tocsr()
    Kac = (D.T @ sp.diags(rho * c * c / volume) @ D).tocsr()
    Ks = sp.coo_matrix((rho * g / top_area, (top, top)), shape=(nF, nF)).tocsr()
    return FaceLiquid(nodes=nodes, elements=elements, faces=faces, element_faces=element_faces, signs=signs,
                      free=free, top=top, top_area=top_area, volume=volume, mass=M, acoustic=Kac, surface=Ks,
                      density=rho, sound_speed=c, gravity=g, depth=float(depth))


@dataclass(frozen=True, eq=False)
class FaceModes:
    omega: np.ndarray                 # (n,) rad/s, ascending
    kind: tuple                       # "sloshing" | "acoustic"
    free_surface_share: np.ndarray    # (n,)
    fluxes: np.ndarray                # (n, F) face fluxes, mass-normalised
    circulation: int                  # zero-frequency (circulation) modes left out: dim ker K


def face_modes(model: FaceLiquid, n: int = 10) -> FaceModes:
    """The n lowest modes of nonzero frequency of K q = omega^2 M q (free faces).

    K = B^T W B with B = [D; T] (each element's outward flux, each top face's flux) and W =
    diag(rho c^2 / V_e, rho g / A_f). K's kernel (divergence-free fields with no flux through the
    free surface) is large: every circulation mode, at exactly zero frequency. The modes of nonzero
    frequency are M-orthogonal to it, so q = M^-1 B^T y, and y solves the small problem
    G y = omega^2 W^-1 y, G = B M^-1 B^T (one unknown per element and per top face; its only zero
    modes are the pools' uniform pressures). Shift-invert Lanczos about sigma < 0 on that problem:
    (G - sigma W^-1) x = r is the sparse saddle-point system [[M, -B^T], [B, -sigma W^-1]] [w; x] =
    [0; r], factorised once; q = w."""
    f = np.flatnonzero(model.free)
    M = model.mass[f][:, f].tocsc()
    E, T = len(model.elements), len(model.top)
    D = sp.coo_matrix((model.signs.reshape(-1), (np.repeat(np.arange(E), 6), model.element_faces.reshape(-1))),
                      shape=(E, len(model.faces))).tocsr()
    Tsel = sp.coo_matrix((np.ones(T), (np.arange(T), model.top)), shape=(T, len(model.faces))).tocsr()
    B = sp.vstack([D, Tsel]).tocsr()[:, f]
    rho, c, g = model.density, model.sound_speed, model.gravity
    winv = np.concatenate([model.volume / (rho * c * c), model.top_area / (rho * g)])
    pools = model.pools
    nf, ny = len(f), E + T
    n_ker = nf - (ny - pools)                                       # rank of B is E + T - pools
    L = float(np.ptp(model.nodes[:, :2], axis=0).max())
    sigma = -0.1 * model.gravity * np.pi / L                        # below the first sloshing mode
    S = sp.bmat([[M, -B.T], [B, sp.diags(-sigma * winv)]], format="csc")
    lu = spla.splu(S)
    Mlu = spla.splu(M)

    def shifted_solve(r):
        rhs = np.concatenate([np.zeros(nf), np.ravel(r)])
        return lu.solve(rhs)[nf:]

    G = spla.LinearOperator((ny, ny), matvec=lambda x: B @ Mlu.solve(B.T @ np.ravel(x)), dtype=float)
    OPinv = spla.LinearOperator((ny, ny), matvec=shifted_solve, dtype=float)
    k = int(min(n + pools, ny - 1))
    lam, Y = spla.eigsh(G, k=k, M=sp.diags(winv).tocsc(), sigma=sigma, which="LM", OPinv=OPinv,
                        v0=np.random.default_rng(0).standard_normal(ny), ncv=max(2 * k + 1, 30))
    order = np.argsort(lam)[pools:]
    lam, Y = lam[order], Y[:, order]
    fluxes = np.zeros((len(lam), len(model.faces)))
    fluxes[:, f] = np.stack([Mlu.solve(B.T @ y) for y in Y.T])
    norm = np.sqrt(np.einsum("if,if->i", fluxes, (model.mass @ fluxes.T).T))
    fluxes /= norm[:, None]
    total = np.einsum("if,if->i", fluxes, (model.stiffness @ fluxes.T).T)
    surf = np.einsum("if,if->i", fluxes, (model.surface @ fluxes.T).T)
    share = np.clip(surf / np.where(total > 0, total, np.inf), 0.0, 1.0)
    kind = tuple("sloshing" if s > 0.5 else "acoustic" for s in share)
    return FaceModes(omega=np.sqrt(np.maximum(lam, 0.0)), kind=kind, free_surface_share=share,
                     fluxes=fluxes, circulation=int(n_ker))
