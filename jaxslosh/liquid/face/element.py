"""The face-normal liquid element ("rt"): lowest-order Raviart-Thomas displacements on hexahedra.

The stabilized element (liquid/nodal/element.py) keeps the displacement at the nodes and holds the
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
* energies (docs/theory.md, what the paper leaves out): compression ``1/2 rho c^2 (sum_f s_ef q_f)^2 / V_e`` (the flux
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

from .schur import mixed_operators
from ...fem.mesh import GAUSS8, HEX_CORNERS
from .mesh import face_topology, free_faces

#: the reference face of each row of HEX_FACES: (axis, side)
_FACE_AXIS = np.array([2, 2, 1, 0, 1, 0])
_FACE_SIDE = np.array([-1.0, 1.0, -1.0, 1.0, 1.0, -1.0])


@dataclass(frozen=True, eq=False)
class FaceModel:
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
    geometry: object = None           # the geometry shape (jaxslosh.geometry) it was meshed from (probes, outputs)

    traced = False                    # built from concrete values only
    frames = None                     # no node frames: the walls hold face fluxes
    rotation_coupling = None

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def stiffness(self):
        return (self.acoustic + self.surface).tocsr()

    @property
    def pools(self) -> int:
        """Separate pools of liquid (elements joined through free faces)."""
        return int(self.pool_labels().max() + 1)

    def pool_labels(self):
        """(E,) the pool of each element."""
        from scipy.sparse.csgraph import connected_components
        E = len(self.elements)
        rows = np.repeat(np.arange(E), 6)
        cols = self.element_faces.reshape(-1)
        keep = self.free[cols]
        A = sp.coo_matrix((np.ones(keep.sum()), (rows[keep], cols[keep])), shape=(E, len(self.faces))).tocsr()
        return connected_components(A @ A.T, directed=False)[1]

    def displacement_at(self, q, element, xi):
        """Displacements (P, 3) at reference points xi (P, 3) of the given elements (P,), for face
        fluxes q (F,)."""
        X = self.nodes[self.elements[element]]                       # (P, 8, 3)
        J = np.einsum("pai,pak->pik", X, shape_gradients(xi))
        detJ = np.linalg.det(J)
        ql = q[self.element_faces[element]] * self.signs[element]    # (P, 6) outward fluxes
        ref = _reference_fields(xi)                                  # (P, 6, 3)
        return np.einsum("pik,pfk,pf->pi", J, ref, ql) / detJ[:, None]

    def nodal_field(self, q):
        """A nodal displacement field (N, 3) for plots and probes (the model's own field is the
        element-wise one): at each node the value of the linear field fitted, by least squares, to
        the Gauss-point values of the elements round it (a patch recovery: at a wall or on the free
        surface it extrapolates the field to the node rather than averaging it inwards)."""
        return self.nodal_fields(np.asarray(q)[None])[0]

    def nodal_fields(self, Q):
        """`nodal_field` of several flux fields Q (k, F) -> (k, N, 3)."""
        x, _, _ = _gauss(self)
        u = _fields(self, _gauss(self), np.atleast_2d(Q))                  # (k, E, P, 3)
        E, P = x.shape[:2]
        node = np.repeat(self.elements, P, axis=0).reshape(E, P, 8)       # each Gauss point, for every corner
        rows = self.elements[:, None, :].repeat(P, axis=1)                 # (E, P, 8) node of corner a
        h = np.cbrt(self.volume)[:, None, None, None]
        d = (x[:, :, None, :] - self.nodes[rows]) / h                       # (E, P, 8, 3) scaled offsets
        A = np.concatenate([np.ones(d.shape[:-1] + (1,)), d], axis=-1)     # (E, P, 8, 4)
        N = len(self.nodes)
        AtA = np.zeros((N, 4, 4))
        np.add.at(AtA, rows.reshape(-1), np.einsum("...i,...j->...ij", A, A).reshape(-1, 4, 4))
        del node
        # the value at the node is the fit's constant term: row 0 of (A^T A)^-1 applied to A^T b
        row0 = np.linalg.solve(AtA + 1e-12 * np.eye(4), np.broadcast_to(np.eye(4)[:, :1], (N, 4, 1)))[..., 0]
        wts = np.einsum("epai,epai->epa", A, row0[rows])                  # (E, P, 8) weight of each point
        k = u.shape[0]                                                     # the sums as one sparse product
        S = sp.csr_matrix((wts.reshape(-1), (rows.reshape(-1), np.repeat(np.arange(E * P), 8))), shape=(N, E * P))
        return (S @ u.reshape(k, E * P, 3).transpose(1, 0, 2).reshape(E * P, 3 * k)).reshape(N, k, 3).transpose(1, 0, 2)


def shape_gradients(xi):
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


def build_face_liquid(nodes, elements, depth, density, sound_speed, gravity, geometry=None) -> FaceModel:
    """The face-normal model of the liquid meshed by hexahedra ``elements`` (positively oriented;
    a collapsed face allowed) at rest below the free surface z = ``depth``."""
    nodes = np.asarray(nodes, dtype=float)
    elements = np.asarray(elements, dtype=int)
    rho, c, g = float(density), float(sound_speed), float(gravity)
    faces, element_faces, signs, on_boundary, collapsed = face_topology(elements)
    free, top = free_faces(nodes, faces, on_boundary, collapsed, depth)
    Xf = nodes[faces]
    normal = 0.5 * np.cross(Xf[top, 2] - Xf[top, 0], Xf[top, 3] - Xf[top, 1])
    top_area = np.abs(normal[:, 2])

    # element matrices (vectorized over elements and Gauss points)
    X = nodes[elements]                                            # (E, 8, 3)
    dN = shape_gradients(GAUSS8)                                  # (8 gp, 8, 3)
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
    return FaceModel(nodes=nodes, elements=elements, faces=faces, element_faces=element_faces, signs=signs,
                      free=free, top=top, top_area=top_area, volume=volume, mass=M, acoustic=Kac, surface=Ks,
                      density=rho, sound_speed=c, gravity=g, depth=float(depth), geometry=geometry)


def _spd_lu(A):   # a symmetric (quasi-)definite matrix: symmetric ordering, no pivoting
    return spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))


class _SaddleSolver:
    """Solves [[M, -B^T], [B, c W^-1]] [w; x] = [a; b] (c > 0). With its second row negated the
    matrix is symmetric quasi-definite (M positive definite, -c W^-1 negative definite), which
    factors with any symmetric ordering and no pivoting: a minimum-degree ordering keeps the fill
    several times below partial pivoting's (a 20x20x12 box: 3e6 nonzeros against 2e7, the factor
    twenty times quicker). Without pivoting the solve is refined against the matrix itself, to the
    round-off of the pivoted one."""

    def __init__(self, M, B, cwinv):
        self.A, self.n = sp.bmat([[M, -B.T], [-B, sp.diags(-cwinv)]], format="csc"), M.shape[0]
        self.lu = _spd_lu(self.A)

    def solve(self, rhs):
        b = np.array(rhs, dtype=float)
        b[self.n:] *= -1.0
        x, prev = self.lu.solve(b), np.inf
        for _ in range(3):                 # one step reaches round-off; stop once it stalls
            r = b - self.A @ x
            res = np.abs(r).max()
            if res > 0.1 * prev or res == 0.0:
                break
            x, prev = x + self.lu.solve(r), res
        return x


@dataclass(frozen=True, eq=False)
class FaceModes:
    omega: np.ndarray                 # (n,) rad/s, ascending
    kind: tuple                       # "sloshing" | "acoustic"
    free_surface_share: np.ndarray    # (n,)
    fluxes: np.ndarray                # (n, F) face fluxes, mass-normalised
    circulation: int                  # zero-frequency (circulation) modes left out: dim ker K


def face_modes(model: FaceModel, n: int = 10) -> FaceModes:
    """The n lowest modes of nonzero frequency of K q = omega^2 M q (free faces).

    K = B^T W B with B = [D; T] (each element's outward flux, each top face's flux) and W =
    diag(rho c^2 / V_e, rho g / A_f). K's kernel (divergence-free fields with no flux through the
    free surface) is large: every circulation mode, at exactly zero frequency. The modes of nonzero
    frequency are M-orthogonal to it, so q = M^-1 B^T y, and y solves the small problem
    G y = omega^2 W^-1 y, G = B M^-1 B^T (one unknown per element and per top face; its only zero
    modes are the pools' uniform pressures). Shift-invert Lanczos about sigma < 0 on that problem:
    (G - sigma W^-1) x = r is the sparse saddle-point system [[M, -B^T], [B, -sigma W^-1]] [w; x] =
    [0; r], factorised once (`_SaddleSolver`); q = w."""
    f, B, M, winv = mixed_operators(model)
    E, T = len(model.elements), len(model.top)
    pools = model.pools
    nf, ny = len(f), E + T
    n_ker = nf - (ny - pools)                                       # rank of B is E + T - pools
    L = float(np.ptp(model.nodes[:, :2], axis=0).max())
    sigma = -0.1 * model.gravity * np.pi / L                        # below the first sloshing mode
    lu = _SaddleSolver(M, B, -sigma * winv)
    Mlu = _spd_lu(M)

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


# ------------------------------------------------------------------------------ runs: a modal basis

#: the absolute-rotation penalty's modes at this multiple of the highest sloshing mode kept
ROTATION_PENALTY_RATIO = 10.0


def _gauss(model: FaceModel):
    """(positions (E, P, 3), weights det J (E, P), signed basis fields (E, P, 6, 3)) at the 2x2x2 Gauss points."""
    X = model.nodes[model.elements]
    dN = shape_gradients(GAUSS8)
    N = np.prod(1.0 + HEX_CORNERS[None] * GAUSS8[:, None, :], axis=2) / 8.0     # (P, 8)
    J = np.einsum("eai,pak->epik", X, dN)
    detJ = np.linalg.det(J)
    phys = np.einsum("epik,pfk->epfi", J, _reference_fields(GAUSS8)) / detJ[:, :, None, None]
    return np.einsum("pa,eai->epi", N, X), detJ, phys * model.signs[:, None, :, None]


def _fields(model, gauss, Q):
    """Displacements (k, E, P, 3) at the Gauss points of face fluxes Q (k, F)."""
    return np.einsum("epfi,kef->kepi", gauss[2], Q[:, model.element_faces])


def _loads(model, gauss, fields):
    """Generalized forces (F, k) rho int phi_f . a_k dV of acceleration fields a_k (k, E, P, 3)."""
    _, w, phys = gauss
    local = model.density * np.einsum("ep,epfi,kepi->kef", w, phys, fields)
    out = np.zeros((len(fields), len(model.faces)))
    for k in range(len(fields)):
        np.add.at(out[k], model.element_faces.reshape(-1), local[k].reshape(-1))
    return out.T


class _Mixed:
    """Solves with G = B M^-1 B^T on the free faces (the saddle-point system, iterated on a
    shifted factor; every right-hand side here is cleared of the pools' uniform pressures)."""

    def __init__(self, model: FaceModel):
        f = np.flatnonzero(model.free)
        E, T = len(model.elements), len(model.top)
        D = sp.coo_matrix((model.signs.reshape(-1), (np.repeat(np.arange(E), 6), model.element_faces.reshape(-1))),
                          shape=(E, len(model.faces))).tocsr()
        Tsel = sp.coo_matrix((np.ones(T), (np.arange(T), model.top)), shape=(T, len(model.faces))).tocsr()
        self.B = sp.vstack([D, Tsel]).tocsr()[:, f]
        self.M = model.mass[f][:, f].tocsc()
        self.winv = np.concatenate([model.volume / (model.density * model.sound_speed ** 2),
                                    model.top_area / (model.density * model.gravity)])
        L = float(np.ptp(model.nodes[:, :2], axis=0).max())
        # G x = r by the fixed point (G + c W^-1) x' = r + c W^-1 x on the quasi-definite factor of
        # face_modes' shift: each step shrinks a mode's error by c / (lambda + c), the lowest
        # sloshing one's by about 0.1 (a U-tube's slow mode: 0.3)
        self.c = 0.1 * model.gravity * np.pi / L
        self.lu = _SaddleSolver(self.M, self.B, self.c * self.winv)
        self.Mlu = _spd_lu(self.M)
        labels = model.pool_labels()
        owner = np.empty(len(model.faces), dtype=int)
        owner[model.element_faces.reshape(-1)] = np.repeat(np.arange(E), 6)
        top_owner = labels[owner[model.top]]
        P = np.zeros((E + T, int(labels.max() + 1)))
        P[np.arange(E), labels] = 1.0
        P[E + np.arange(T), top_owner] = -1.0
        self.P = P / np.linalg.norm(P, axis=0)
        self.nf, self.f = len(f), f

    def pool_fix(self, z):
        """z plus the pools' null vectors that make W^-1 z orthogonal to them (a solvable G y = W^-1 z)."""
        Pw = self.winv[:, None] * self.P
        return z - self.P @ ((Pw.T @ z) / np.einsum("ij,ij->j", self.P, Pw)[:, None])

    def solve(self, r):
        """(x, w = M^-1 B^T x) with G x = r (r cleared of the pools' null vectors)."""
        r = r - self.P @ (self.P.T @ r)
        cw = self.c * self.winv.reshape((-1,) + (1,) * (r.ndim - 1))
        zero, x, prev = np.zeros((self.nf,) + r.shape[1:]), np.zeros_like(r), np.inf
        for _ in range(100):
            out = self.lu.solve(np.concatenate([zero, r + cw * x]))
            step = np.abs(out[self.nf:] - x).max() / max(np.abs(x).max(), 1e-300)
            x = out[self.nf:]
            if step <= 1e-14 or step > 0.7 * prev:       # converged, or stalled at round-off
                break
            prev = step
        return x, out[:self.nf]


def face_basis(model: FaceModel, origin, n: int, static_correction: bool = True):
    """A Ritz basis of the face-normal liquid for runs (liquid/modal/reduction.py's counterpart).

    Returns (V (F, m) on all faces, omega (m,), n_modes, (K_dt (m, 3), K_tt (3, 3))): the n lowest
    sloshing modes; with ``static_correction`` the quasi-static responses K^+ F to the loads of a
    uniform acceleration (3) and of the acceleration fields that are gradients of quadratics (the
    symmetric parts of a field linear in position: centrifugal, 6), made M-orthonormal to the modes
    and diagonalised; and the circulation the tank's rotation drives. The last is the kernel part
    P c_k of each rigid rotation e_k x r: an ideal liquid keeps its absolute flow irrotational, so
    relative to the tank it turns back by -theta (Kelvin); the basis holds span{P c_k}, and the
    penalty 1/2 kappa |P (c theta) + V_c zeta|_M^2 ties those coordinates to the body rotation
    theta through the same K_dt, K_tt terms as the stabilized element's rotation penalty
    (kappa: the penalty modes at ROTATION_PENALTY_RATIO times the highest sloshing mode kept)."""
    modes = face_modes(model, n)
    f = np.flatnonzero(model.free)
    Phi = modes.fluxes[:, f].T                                   # (nf, n), M-orthonormal
    mixed = _Mixed(model)
    M = mixed.M
    gauss = _gauss(model)
    r = gauss[0] + np.asarray(origin, dtype=float)
    E, P = r.shape[:2]
    # the rigid rotations' fluxes: the M-projection onto the faces' space of e_k x r is not needed,
    # only its kernel part, which the load rho int phi . (e_k x r) determines: c = M^-1 F, and
    # P c = c - M^-1 B^T G^-1 B c
    rot = np.stack([np.cross(np.eye(3)[k], r) for k in range(3)])          # (3, E, P, 3)
    Frot = _loads(model, gauss, rot)[f]
    c = mixed.Mlu.solve(Frot)
    _, w = mixed.solve(mixed.B @ c)
    Pc = c - w
    Gc = Pc.T @ (M @ Pc)
    g, Z = np.linalg.eigh(0.5 * (Gc + Gc.T))
    keep = g > 1e-9 * max(g.max(), 1e-300)
    Vc = Pc @ (Z[:, keep] / np.sqrt(g[keep]))                   # M-orthonormal kernel vectors
    cols = [Phi]
    om = [modes.omega]
    if static_correction:
        one = np.ones((E, P))
        fields = [np.stack([one * (a == k) for k in range(3)], axis=-1) for a in range(3)]
        for a in range(3):
            for b in range(a, 3):
                F = np.zeros((E, P, 3))
                F[..., a] += r[..., b]
                F[..., b] += r[..., a]
                fields.append(F)
        F = _loads(model, gauss, np.stack(fields))[f]             # (nf, 9)
        # K Psi = F with Psi = M^-1 B^T y: G W G y = B M^-1 F
        z, _ = mixed.solve(mixed.B @ mixed.Mlu.solve(F))
        _, Psi = mixed.solve(mixed.winv[:, None] * mixed.pool_fix(z))
        for _ in range(2):
            Psi = Psi - Phi @ (Phi.T @ (M @ Psi))
        norms = np.sqrt(np.einsum("ij,ij->j", Psi, M @ Psi))
        Psi = Psi[:, norms > 1e-12 * norms.max()] / norms[norms > 1e-12 * norms.max()]
        Gp = Psi.T @ (M @ Psi)
        gp, Wp = np.linalg.eigh(0.5 * (Gp + Gp.T))
        kp = gp > 1e-9 * gp.max()
        Bp = Psi @ (Wp[:, kp] / np.sqrt(gp[kp]))
        Bp = Bp - Phi @ (Phi.T @ (M @ Bp))
        K = model.stiffness[f][:, f]
        Kb = Bp.T @ (K @ Bp)
        mu, Zb = np.linalg.eigh(0.5 * (Kb + Kb.T))
        cols.append(Bp @ Zb)
        om.append(np.sqrt(np.abs(mu)))
    cols.append(Vc)
    V = np.concatenate(cols, axis=1)
    Mv = V.T @ (M @ V)
    Lc = np.linalg.cholesky(0.5 * (Mv + Mv.T))
    V = np.linalg.solve(Lc, V.T).T                               # V^T M V = I to round-off
    slosh = [w for w, k in zip(modes.omega, modes.kind) if k == "sloshing"] or [float(np.max(om[0]))]
    kappa = (ROTATION_PENALTY_RATIO * max(max(slosh), 1e-30)) ** 2     # not an acoustic mode's: needlessly stiff
    m = V.shape[1]
    nc = Vc.shape[1]
    # the kernel coordinates are the last nc (the Cholesky pass leaves a triangular mix: project again)
    Vk = V[:, m - nc:]
    Kdt = np.zeros((m, 3))
    Kdt[m - nc:] = kappa * (Vk.T @ (M @ Pc))
    Ktt = kappa * Gc
    Vfull = np.zeros((len(model.faces), m))
    Vfull[f] = V
    omega = np.concatenate(om + [np.full(nc, np.sqrt(kappa))])
    return Vfull, omega, len(modes.omega), (Kdt, Ktt, kappa, m - nc)


def face_invariants(model: FaceModel, V, origin):
    """The inertia invariants of liquid/modal/term.py for the basis V (F, m), as integrals of the
    element fields (2x2x2 Gauss): mass, S0, Q0, U1 (m, 3), Q1 (m, 3, 3), Q2 (m, m, 3, 3), Mr, Kr;
    and the basis as nodal fields (m, N, 3) for outputs and probes, and lumped nodal masses (N,)."""
    gauss = _gauss(model)
    x, w, _ = gauss
    r = x + np.asarray(origin, dtype=float)
    rho = model.density
    u = _fields(model, gauss, V.T)                                # (m, E, P, 3)
    mass = rho * w.sum()
    S0 = rho * np.einsum("ep,epa->a", w, r)
    Q0 = rho * np.einsum("ep,epa,epb->ab", w, r, r)
    U1 = rho * np.einsum("ep,kepa->ka", w, u)
    Q1 = rho * np.einsum("ep,epa,kepb->kab", w, r, u)
    uf = u.reshape(len(u), -1, 3).transpose(1, 0, 2).reshape(-1, 3 * len(u))   # (E P, 3 m): one product
    Q2 = (rho * (uf * w.reshape(-1, 1)).T @ uf).reshape(len(u), 3, len(u), 3).transpose(0, 2, 1, 3)
    Mr = np.einsum("klaa->kl", Q2)
    Kr = V.T @ (model.stiffness @ V)
    U = model.nodal_fields(V.T)
    m_nodes = np.zeros(model.n_nodes)
    np.add.at(m_nodes, model.elements.reshape(-1), np.repeat(rho * model.volume / 8.0, 8))
    return dict(mass=mass, S0=S0, Q0=Q0, U1=U1, Q1=Q1, Q2=Q2, Mr=0.5 * (Mr + Mr.T), Kr=0.5 * (Kr + Kr.T), U=U,
                m_nodes=m_nodes, r=model.nodes + np.asarray(origin, dtype=float))
