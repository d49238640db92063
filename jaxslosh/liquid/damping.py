"""Host-side data of the liquid's modal damping (`[tanks.damping]`, liquid/modal_damping.py): the sloshing
modes a damping acts on, and each mode's laminar boundary-layer damping ratio.

Boundary-layer damping. Outside a wall's Stokes layer the inviscid flow slides along the wall with a
tangential velocity U cos(omega t); the layer (thickness sqrt(2 nu / omega)) dissipates, averaged over
a period, (rho / 2) sqrt(nu omega / 2) U^2 per unit wall area (Landau & Lifshitz, Fluid Mechanics,
2nd ed., section 24). A mode of energy E (the maximum kinetic energy) decays as exp(-2 zeta omega t),
so zeta = D / (2 omega E) (Keulegan 1959, "Energy dissipation in standing waves in rectangular
basins", J. Fluid Mech. 6, 33-50: the same wall-and-bottom integration, without his surface-film
term). For a mass-normalised mode shape phi (1/2 omega^2 phi^T M phi = E with phi^T M phi = 1) and
U = omega phi_t this is

    zeta = (rho / 2) sqrt(nu / (2 omega)) int_wetted |phi_t|^2 dA,

integrated here over the tank's bottom and its four walls up to the fill depth with the bilinear
(consistent) face mass on the element faces. `rectangular_ratio` is the closed form of the same
integral for the first mode of a rectangular tank with the linear potential-flow mode, the reference
the tests hold the finite-element value to.
"""
from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from ..fem.mesh import grid_index
from .face.element import face_modes, shape_gradients
from .modal.build import face_sloshing, face_tank_basis
from .modal.reduction import tank_basis
from .modes import classify, free_matrices, natural_modes
from .nodal.model import build_liquid

#: modes searched for sloshing ones on a sparse (large) mesh, where all of them cannot be found
SPARSE_SEARCH = 48


def sloshing_modes(model, search: int = 0):
    """(omega (k,), Phi (nf_t, k)): the liquid's sloshing modes (liquid/modes.py classification) in
    ascending frequency, mass-normalised on the free dofs, of a concrete model. Dense models: among
    all their modes; sparse ones: among the lowest `search` (SPARSE_SEARCH when 0). Cached per tank."""
    key = (tuple(model.size), float(model.depth), tuple(model.mesh), float(model.density),
           float(model.sound_speed), float(model.gravity), model.element, sp.issparse(model.stiffness), int(search),
           model.geometry)
    return _cached_modes(key, _Ref(model))


@functools.lru_cache(maxsize=16)
def _cached_modes(key, ref):
    model = ref.obj
    K, M = free_matrices(model)
    if sp.issparse(K):
        lam, X = natural_modes(K, M, min(K.shape[0] - 1, key[-2] or SPARSE_SEARCH))
    else:
        lam, X = sl.eigh(K, M)
    keep = sloshing_share(model, X) & (lam > 0)
    return np.sqrt(lam[keep]), X[:, keep]


def sloshing_share(model, X) -> np.ndarray:
    """(k,) bool: which columns of X (mode shapes on the free dofs) are sloshing modes."""
    shapes = np.zeros((X.shape[1], np.asarray(model.free).size))
    shapes[:, np.flatnonzero(np.asarray(model.free))] = X.T
    _, kind = classify(model, shapes)
    return np.array([k == "sloshing" for k in kind], dtype=bool)


class _Ref:
    """Hashes by nothing: the cache key says what the modes depend on."""

    def __init__(self, obj):
        self.obj = obj

    def __hash__(self):
        return 0

    def __eq__(self, other):
        return isinstance(other, _Ref)


def wall_integrals(model, Phi):
    """(k,) int_wetted |phi_t|^2 dA of each mode (columns of Phi on the free dofs): the tangential
    components on the bottom (z = 0) and the four walls (x = 0, a; y = 0, b) up to the fill depth
    (a tank of another shape: on its wall faces, both faces of baffles included)."""
    if hasattr(model, "element_faces"):          # the face-normal element: Phi (F, k) face fluxes
        return _rt_wall_integrals(model, Phi)
    if model.wall_faces is not None:
        return _face_integrals(model, Phi)
    nx, ny, nz = (int(n) for n in model.mesh)
    a, b = float(model.size[0]), float(model.size[1])
    hx, hy, hz = a / nx, b / ny, float(model.depth) / nz
    f = np.flatnonzero(np.asarray(model.free))
    full = np.zeros((Phi.shape[1], 3 * model.n_nodes))
    full[:, f] = Phi.T
    U = full.reshape(Phi.shape[1], model.n_nodes, 3)
    ijk = grid_index(nx, ny, nz)
    planes = (  # (nodes on the plane, in-plane axes (grid index, count, spacing) x 2, tangential components)
        (ijk[:, 0] == 0, (1, ny, hy), (2, nz, hz), (1, 2)), (ijk[:, 0] == nx, (1, ny, hy), (2, nz, hz), (1, 2)),
        (ijk[:, 1] == 0, (0, nx, hx), (2, nz, hz), (0, 2)), (ijk[:, 1] == ny, (0, nx, hx), (2, nz, hz), (0, 2)),
        (ijk[:, 2] == 0, (0, nx, hx), (1, ny, hy), (0, 1)),
    )
    out = np.zeros(Phi.shape[1])
    for on, (ax1, n1, h1), (ax2, n2, h2), comps in planes:
        idx = np.flatnonzero(on)
        order = np.lexsort((ijk[idx, ax2], ijk[idx, ax1]))      # node order on the plane: ax1 major
        idx = idx[order]
        M1, M2 = _line_mass(n1, h1), _line_mass(n2, h2)
        for c in comps:
            F = U[:, idx, c].reshape(-1, n1 + 1, n2 + 1)
            out += np.einsum("kij,kij->k", F, M1 @ F @ M2)
    return out


def _line_mass(n: int, h: float) -> np.ndarray:
    """The consistent mass of n linear elements of length h on a line: int f g = f^T M g."""
    M = np.zeros((n + 1, n + 1))
    i = np.arange(n)
    M[i, i] += 2.0
    M[i + 1, i + 1] += 2.0
    M[i, i + 1] += 1.0
    M[i + 1, i] += 1.0
    return M * h / 6.0


def boundary_layer_ratios(model, omega, Phi, viscosity: float) -> np.ndarray:
    """(k,) each mode's laminar boundary-layer damping ratio (module docstring)."""
    if viscosity == 0.0:
        return np.zeros(omega.shape)
    return 0.5 * float(model.density) * np.sqrt(viscosity / (2.0 * omega)) * wall_integrals(model, Phi)


def rectangular_ratio(a: float, b: float, h: float, g: float, viscosity: float) -> float:
    """The boundary-layer damping ratio of the first sloshing mode (one half-wave along a) of a
    rectangular tank a x b filled to h, from the linear mode phi = cos(k x) cosh(k (z + h)), k = pi / a,
    omega^2 = g k tanh(k h): the module docstring's integral over the bottom (u), the walls y = 0, b
    (u and w) and the end walls x = 0, a (w), over the energy, in closed form:

        zeta = sqrt(nu / (2 omega)) [1/a + 1/b + k (1 - 2 h / a) / sinh(2 k h)]."""
    k = np.pi / a
    omega = np.sqrt(g * k * np.tanh(k * h))
    bracket = 1.0 / a + 1.0 / b + k * (1.0 - 2.0 * h / a) / np.sinh(2.0 * k * h)
    return float(np.sqrt(viscosity / (2.0 * omega)) * bracket)


def _face_integrals(model, Phi):
    """`wall_integrals` over the wall faces of any mesh: each face's tangential field, integrated by
    the bilinear face's consistent mass (2 x 2 Gauss on the curved quadrilateral)."""
    f = np.flatnonzero(np.asarray(model.free))
    full = np.zeros((Phi.shape[1], 3 * model.n_nodes))
    full[:, f] = Phi.T
    U = np.asarray(model.to_global(full.reshape(Phi.shape[1], model.n_nodes, 3)))
    faces = np.asarray(model.wall_faces)
    X = np.asarray(model.nodes)[faces]                                  # (W, 4, 3)
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    g = 1.0 / np.sqrt(3.0)
    Mf = np.zeros((len(faces), 4, 4))
    for p in np.array([[sx, sy] for sx in (-g, g) for sy in (-g, g)]):
        N = (1 + corners[:, 0] * p[0]) * (1 + corners[:, 1] * p[1]) / 4.0
        dN = np.stack([corners[:, 0] * (1 + corners[:, 1] * p[1]), corners[:, 1] * (1 + corners[:, 0] * p[0])], 1) / 4.0
        t1, t2 = np.einsum("a,wai->wi", dN[:, 0], X), np.einsum("a,wai->wi", dN[:, 1], X)
        Mf += np.linalg.norm(np.cross(t1, t2), axis=1)[:, None, None] * np.outer(N, N)[None]
    nrm = np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    Uf = U[:, faces]                                                      # (k, W, 4, 3)
    Ut = Uf - np.einsum("kwac,wc->kwa", Uf, nrm)[..., None] * nrm[None, :, None, :]
    return np.einsum("kwac,wab,kwbc->k", Ut, Mf, Ut)


def _rt_wall_integrals(model, Q):
    """`wall_integrals` of the face-normal element (liquid/face/element.py) for face fluxes Q (F, k): on
    every wall face (a boundary face that is not on the free surface, both faces of a plate
    included), the tangential part of the element's own field (its normal part there is zero),
    integrated with 2 x 2 Gauss points on the mapped face."""
    counts = np.bincount(model.element_faces.reshape(-1), minlength=len(model.faces))
    wall = counts == 1
    wall[model.top] = False
    e, j = np.nonzero(wall[model.element_faces])                  # element and local face of each wall face
    axis = np.array([2, 2, 1, 0, 1, 0])[j]                        # liquid_rt's reference face (axis, side)
    side = np.array([-1.0, 1.0, -1.0, 1.0, 1.0, -1.0])[j]
    g = 1.0 / np.sqrt(3.0)
    out = np.zeros(Q.shape[1])
    for a, b in ((-g, -g), (g, -g), (-g, g), (g, g)):
        xi = np.zeros((len(e), 3))
        xi[np.arange(len(e)), axis] = side
        xi[np.arange(len(e)), (axis + 1) % 3] = a
        xi[np.arange(len(e)), (axis + 2) % 3] = b
        Jm = np.einsum("pai,pak->pik", model.nodes[model.elements[e]], shape_gradients(xi))
        t1 = Jm[np.arange(len(e)), :, (axis + 1) % 3]
        t2 = Jm[np.arange(len(e)), :, (axis + 2) % 3]
        nrm = np.cross(t1, t2)
        dA = np.linalg.norm(nrm, axis=1)
        n = nrm / np.maximum(dA, 1e-300)[:, None]
        for k in range(Q.shape[1]):
            u = model.displacement_at(Q[:, k], e, xi)
            ut = u - np.einsum("pi,pi->p", u, n)[:, None] * n
            out[k] += np.einsum("pi,pi,p->", ut, ut, dA)
    return out


class SloshingBasis(NamedTuple):
    """One tank's sloshing modes as the modal damping takes them (assemble/damping.py)."""
    model: object          # the concrete element model (the boundary-layer integrals' mesh)
    n: int                 # the tank's unknowns in the liquid block
    omega: np.ndarray      # (k,) rad/s
    Phi: np.ndarray        # the modes (on the model's dofs, or on the tank's modal basis)
    Bt: np.ndarray         # (n, k) M Phi on the tank's unknowns
    where: str             # what holds the modes, for the error where a table lists more


def sloshing_basis(model, t, gravity: float) -> SloshingBasis:
    """The sloshing modes of tank `t` (its element model `model`): at full order on its free dofs
    (or faces), or on its modal basis (a reduced tank's, [tanks.reduction]: the block reduces every
    tank or none); from the scene's values (`gravity` the scene's) where the model was built at
    traced ones."""
    reduced = t.form.reduced
    if t.form.face_normal and not reduced:      # full order: its lowest modes, on the free faces
        fm = face_modes(model, SPARSE_SEARCH)
        slosh = np.array([k == "sloshing" for k in fm.kind], dtype=bool)
        f = np.flatnonzero(model.free)
        omega, Phi = fm.omega[slosh], fm.fluxes[slosh].T                # Phi on all faces (wall integrals)
        return SloshingBasis(model, f.size, omega, Phi, model.mass[f][:, f] @ Phi[f],
                             f"the {SPARSE_SEARCH} lowest modes searched on this mesh hold {omega.size}")
    if t.form.face_normal:                # on its modal basis
        V, omega_b, n_modes, (_, _, _, k0) = face_tank_basis(model, t.origin, t.reduction.modes,
                                                             t.reduction.static_correction)
        slosh = face_sloshing(model, V, n_modes)
        return SloshingBasis(model, V.shape[1], omega_b[slosh], V[:, slosh], np.eye(V.shape[1])[:, slosh],
                             f"the reduced basis holds {slosh.size} ([tanks.reduction] modes = {t.reduction.modes})")
    if model.traced:
        model = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed,
                             gravity, element=t.fluid.element, geometry=t.geometry)
    if reduced:
        basis = tank_basis(model, t.origin, t.reduction.modes, t.reduction.static_correction)
        n_t = basis.V.shape[1]
        slosh = np.flatnonzero(sloshing_share(model, basis.V[:, :basis.n_modes]))
        return SloshingBasis(model, n_t, basis.omega[slosh], basis.V[:, slosh],
                             np.eye(n_t)[:, slosh],         # V^T M Phi: the basis holds these modes as they are
                             f"the reduced basis holds {slosh.size} ([tanks.reduction] modes = {t.reduction.modes})")
    omega, Phi = sloshing_modes(model)
    Bt = free_matrices(model)[1] @ Phi
    Bt = np.asarray(Bt.todense() if sp.issparse(Bt) else Bt)
    if sp.issparse(model.stiffness):     # a large mesh: only its lowest modes are searched
        where = f"the {min(Phi.shape[0] - 1, SPARSE_SEARCH)} lowest modes searched on this mesh hold {omega.size}"
    else:
        where = f"the mesh carries {omega.size}"
    return SloshingBasis(model, Phi.shape[0], omega, Phi, Bt, where)
