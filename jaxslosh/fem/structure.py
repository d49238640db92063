"""Linear elastic substructures on hexahedra, in their own floating frame (paper sections 2-3).

A structure is a rectangular block meshed with (nx, ny, nz) 8-node hexahedra. Its element is the
trilinear hexahedron enriched with Wilson's nine incompatible bubble modes (Wilson, Taylor,
Doherty & Ghaboussi 1973; statically condensed per element): it bends without shear locking, so a
slender mast two elements across bends right, and on the box elements used here it passes the patch
test (the Jacobian is constant). The mass is consistent (2x2x2 Gauss).

Floating frame (eqs. 6-11): the origin is the block's centre of gravity, r the node positions from
it, R = [I, -r~] the rigid-body modes (eq. 8), M_alpha = R^T M R and the projector
P = I - M R M_alpha^-1 R^T (eq. 9). The deformation d = P^T u has no rigid-body part: R^T M d = 0.
The time loop works in the basis Phi of the elastic eigenvectors of K_P = P K P^T (eq. 21) that are
mass-orthonormal (Phi^T M Phi = I, Phi^T K Phi = diag(omega^2)): range(Phi) = range(P^T), so
d = Phi eta is the paper's filtered deformation written in coordinates where M_P and K_P are diagonal.
With every elastic mode kept this is exact, not a reduction (`modes` may truncate it: a cheaper
accuracy level). Everything here is NumPy, built once per scene: only eta and the frame move.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from ..staging import compile_program, no_eager_folding
from .mesh import GAUSS8, HEX_CORNERS, box_mesh


def elasticity_matrix(young: float, poisson: float) -> np.ndarray:
    """Isotropic C (6x6, Voigt order xx, yy, zz, yz, xz, xy with engineering shear strains)."""
    lam = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
    mu = young / (2 * (1 + poisson))
    C = np.zeros((6, 6))
    C[:3, :3] = lam
    C[np.arange(3), np.arange(3)] += 2 * mu
    C[np.arange(3, 6), np.arange(3, 6)] = mu
    return C


@functools.lru_cache(maxsize=1)
def _element_hessian():
    """The compiled Hessian of the element energy in (u, a) for given half sizes and C: one
    compilation serves every element size and material."""
    def strain(grad):            # grad[i, j] = d u_i / d x_j
        return jnp.array([grad[0, 0], grad[1, 1], grad[2, 2], grad[1, 2] + grad[2, 1],
                          grad[0, 2] + grad[2, 0], grad[0, 1] + grad[1, 0]])

    def energy_at(xi, z, half, C):
        u, a = z[:24].reshape(8, 3), z[24:].reshape(3, 3)      # a[k, i]: bubble (1 - xi_k^2) of component i
        dN = HEX_CORNERS * jnp.prod(1 + HEX_CORNERS * xi, axis=1, keepdims=True) / (1 + HEX_CORNERS * xi) / 8.0  # dN/dxi (8, 3)
        grad = u.T @ (dN / half) + a.T @ jnp.diag(-2.0 * xi / half)                    # du_i/dx_j
        eps = strain(grad)
        return 0.5 * eps @ (C @ eps) * jnp.prod(half)

    def energy(z, half, C):
        return jax.vmap(energy_at, in_axes=(0, None, None, None))(jnp.asarray(GAUSS8), z, half, C).sum()

    # staged whole even under the build's ensure_compile_time_eval, and read back from the exported
    # programs where a process compiled it before (cache/programs.py)
    with jax.enable_x64(True), no_eager_folding():
        like = (np.zeros(33), np.zeros(3), np.zeros((6, 6)))
        return compile_program("element-structure", jax.hessian(energy), like)[0]


@functools.lru_cache(maxsize=32)
def box_element(hx: float, hy: float, hz: float, young: float, poisson: float, density: float):
    """(K 24x24, Ms 8x8 scalar mass) of a hx x hy x hz box hexahedron with incompatible modes.

    The element energy 1/2 int eps(u, a) : C : eps(u, a) dV (2x2x2 Gauss) is a quadratic form in
    the 24 nodal displacements u and the 9 bubble amplitudes a (Wilson's modes 1 - xi_k^2 per
    component); its Hessian is taken with JAX and the bubbles are condensed out:
    K = K_uu - K_ua K_aa^-1 K_au. Dofs node-major (3 per node)."""
    half = np.array([hx, hy, hz]) / 2.0
    with jax.enable_x64(True):
        H = np.asarray(_element_hessian()(jnp.zeros(33, dtype=jnp.float64), jnp.asarray(half, dtype=jnp.float64),
                                          jnp.asarray(elasticity_matrix(young, poisson), dtype=jnp.float64)))
    Kuu, Kua, Kaa = H[:24, :24], H[:24, 24:], H[24:, 24:]
    K = Kuu - Kua @ np.linalg.solve(Kaa, Kua.T)
    K = 0.5 * (K + K.T)
    Ms = np.zeros((8, 8))
    for xi in GAUSS8:
        N = np.prod(1 + HEX_CORNERS * xi, axis=1) / 8.0
        Ms += density * np.outer(N, N) * np.prod(half)
    return K, Ms


def rigid_modes(r) -> np.ndarray:
    """R (3N, 6) of eq. (8): node blocks [I, -r~] (translations, then rotations about the origin)."""
    N = r.shape[0]
    R = np.zeros((N, 3, 6))
    R[:, :, :3] = np.eye(3)
    x, y, z = r[:, 0], r[:, 1], r[:, 2]
    # -r~ = [[0, z, -y], [-z, 0, x], [y, -x, 0]]: the displacement of a rotation theta is theta x r
    R[:, 0, 4], R[:, 0, 5] = z, -y
    R[:, 1, 3], R[:, 1, 5] = -z, x
    R[:, 2, 3], R[:, 2, 4] = y, -x
    return R.reshape(3 * N, 6)


def projector(M, R) -> np.ndarray:
    """P = I - M R (R^T M R)^-1 R^T (eq. 9): P^T R = 0 and P M R = 0."""
    Ma = R.T @ M @ R
    return np.eye(M.shape[0]) - M @ R @ np.linalg.solve(Ma, R.T)


def assemble(nodes, elements, Ke, Mse, sparse=False):
    """(3N, 3N) stiffness and (N, N) scalar mass from element matrices: one (24, 24) and (8, 8) pair
    for every element, or a stack (E, 24, 24), (E, 8, 8). Dense, or SciPy CSR when `sparse`."""
    N, E = nodes.shape[0], elements.shape[0]
    Ke = np.broadcast_to(Ke, (E, 24, 24))
    Mse = np.broadcast_to(Mse, (E, 8, 8))
    dofs = (3 * elements[:, :, None] + np.arange(3)).reshape(E, 24)
    K = sp.coo_matrix((Ke.reshape(-1), (np.repeat(dofs, 24, axis=1).reshape(-1), np.tile(dofs, (1, 24)).reshape(-1))),
                      shape=(3 * N, 3 * N)).tocsr()
    Ms = sp.coo_matrix((Mse.reshape(-1), (np.repeat(elements, 8, axis=1).reshape(-1),
                                          np.tile(elements, (1, 8)).reshape(-1))), shape=(N, N)).tocsr()
    K = 0.5 * (K + K.T)
    return (K, Ms) if sparse else (K.toarray(), Ms.toarray())


def assemble_cells(nodes, elements, sizes, young, poisson, density):
    """Dense (3N, 3N) stiffness and (N, N) scalar mass of box hexahedra of the given sizes (E, 3)."""
    E = elements.shape[0]
    keys, inv = np.unique(np.round(sizes, 12), axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    Ke = np.zeros((E, 24, 24))
    Me = np.zeros((E, 8, 8))
    for u, hk in enumerate(keys):
        Ke[inv == u], Me[inv == u] = box_element(*(float(x) for x in hk), float(young), float(poisson), float(density))
    return assemble(nodes, elements, Ke, Me)


@dataclass(frozen=True, eq=False)
class StructureModel:
    """Static model of one elastic block in its floating frame (NumPy).

    `nodes` are block-local (from the min corner); `r` the same from the centre of gravity (the
    frame origin); `mass` the scalar (N, N) mass (3N mass: kron(mass, I3)); `stiffness` (3N, 3N);
    `R` the rigid modes at the COG; `omega` (m,) and `Phi` (3N, m) the elastic modes of the free
    block, mass-orthonormal, in range(P^T)."""
    size: tuple
    mesh: tuple
    nodes: np.ndarray
    elements: np.ndarray
    r: np.ndarray
    cog: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    R: np.ndarray
    omega: np.ndarray
    Phi: np.ndarray
    total_mass: float

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    def mass3(self) -> np.ndarray:
        return np.kron(self.mass, np.eye(3))


def build_structure(size, mesh, young, poisson, density, modes=None) -> StructureModel:
    """The floating-frame model of a block: element matrices, assembly, rigid modes and the elastic
    modal basis of the free block (all 3N - 6 elastic modes unless `modes` truncates it)."""
    size = tuple(float(s) for s in size)
    mesh = tuple(int(m) for m in mesh)
    h = tuple(s / m for s, m in zip(size, mesh))
    Ke, Mse = box_element(*h, float(young), float(poisson), float(density))
    nodes, elements = box_mesh(size, mesh)
    K, Ms = assemble(nodes, elements, Ke, Mse)
    m_nodes = Ms.sum(axis=1)
    cog = m_nodes @ nodes / m_nodes.sum()
    r = nodes - cog
    R = rigid_modes(r)
    M3 = np.kron(Ms, np.eye(3))
    lam, X = sl.eigh(K, M3)
    # the six lowest are the rigid modes (K R = 0); project the rest so that R^T M Phi = 0 to round-off
    Pt = projector(M3, R).T
    X = Pt @ X[:, 6:]
    lam = lam[6:]
    keep = X.shape[1] if modes is None else int(min(modes, X.shape[1]))
    X, lam = X[:, :keep], lam[:keep]
    X = X / np.sqrt(np.einsum("ij,ij->j", X, M3 @ X))
    return StructureModel(size=size, mesh=mesh, nodes=nodes, elements=elements, r=r, cog=cog, mass=Ms,
                          stiffness=K, R=R, omega=np.sqrt(np.maximum(lam, 0.0)), Phi=X,
                          total_mass=float(m_nodes.sum()))


def free_modes(size, mesh, young, poisson, density, n=6):
    """The n lowest elastic angular frequencies (rad/s) of the free block, by sparse shift-invert
    (for meshes too large for the dense basis of `build_structure`); the six rigid modes dropped."""
    size = tuple(float(s) for s in size)
    mesh = tuple(int(m) for m in mesh)
    Ke, Mse = box_element(*(s / m for s, m in zip(size, mesh)), float(young), float(poisson), float(density))
    nodes, elements = box_mesh(size, mesh)
    K, Ms = assemble(nodes, elements, Ke, Mse, sparse=True)
    M3 = sp.kron(Ms, sp.eye(3)).tocsc()
    # shift below zero: K - sigma M is positive definite, the rigid modes come out near zero
    scale = abs(K.diagonal()).max() / abs(M3.diagonal()).max()
    lam = spl.eigsh(K.tocsc(), k=n + 6, M=M3, sigma=-1e-6 * scale, which="LM", return_eigenvectors=False)
    lam = np.sort(lam)
    return np.sqrt(np.maximum(lam[6:], 0.0)), lam[:6]

STRUCTURE_KINDS = ("bending", "torsion", "axial", "other")


@dataclass(frozen=True, eq=False)
class StructureModes:
    omega: np.ndarray          # (n,) rad/s ascending
    kind: tuple                # "bending-x" | "bending-y" | "bending-z" | "torsion" | "axial" | "other"
    shares: dict               # name -> (n,) kinetic-energy shares of each pattern
    shapes: np.ndarray         # (n, 3N) mass-normalised, zero on held dofs


def clamped_modes(model: StructureModel, held_nodes, n=10) -> StructureModes:
    """Modes of the block with the nodes `held_nodes` fixed (the attachment face on a vessel held
    still), classified by the pattern that carries most of their kinetic energy (`classify`)."""
    N = model.n_nodes
    fixed = np.zeros((N, 3), dtype=bool)
    fixed[np.asarray(held_nodes, dtype=int)] = True
    f = np.flatnonzero(~fixed.reshape(-1))
    M3 = model.mass3()
    K = model.stiffness[np.ix_(f, f)]
    M = M3[np.ix_(f, f)]
    n = int(min(n, f.size))
    lam, X = sl.eigh(K, M, subset_by_index=[0, n - 1])
    shapes = np.zeros((n, 3 * N))
    shapes[:, f] = X.T
    axis = None
    if len(held_nodes):
        spread = np.ptp(model.nodes[np.asarray(held_nodes, dtype=int)], axis=0)
        axis = int(np.argmin(spread))           # the held face's normal: the long axis of a mast
    shares, kinds = classify(model, shapes, axis)
    return StructureModes(np.sign(lam) * np.sqrt(np.abs(lam)), kinds, shares, shapes)


def classify(model: StructureModel, shapes, axis=None):
    """Split each mode's kinetic energy among patterns of the cross-sections normal to `axis`
    (default: the block's longest side): in-plane translation of a section along each of the two
    other axes ("bending-x", ...), in-plane rotation of the section ("torsion"), motion along the
    axis ("axial"), and what is left (section distortion: "other"). The largest share names it."""
    nodes = model.nodes
    if axis is None:
        axis = int(np.argmax(model.size))
    others = [k for k in range(3) if k != axis]
    m = model.mass.sum(axis=1)
    key = np.round(nodes[:, axis] / max(model.size) * 1e9).astype(np.int64)
    sections = [np.flatnonzero(key == v) for v in np.unique(key)]
    shares = {f"bending-{'xyz'[k]}": [] for k in others}
    shares.update(torsion=[], axial=[], other=[])
    for u in np.atleast_2d(shapes):
        U = u.reshape(-1, 3)
        total = float(np.sum(m[:, None] * U ** 2)) or 1.0
        acc = {k: 0.0 for k in shares}
        for s in sections:
            ms, X, Us = m[s], nodes[s][:, others], U[s]
            c = ms @ X / ms.sum()
            rel = X - c
            t = ms @ Us[:, others] / ms.sum()                          # in-plane translation
            J = ms @ (rel ** 2).sum(axis=1)
            w = ms @ (rel[:, 0] * Us[:, others[1]] - rel[:, 1] * Us[:, others[0]]) / J if J > 0 else 0.0
            for k, tk in zip(others, t):
                acc[f"bending-{'xyz'[k]}"] += ms.sum() * tk ** 2
            acc["torsion"] += w ** 2 * J
            acc["axial"] += float(ms @ Us[:, axis] ** 2)
        acc["other"] = max(0.0, total - sum(acc.values()))
        for k in shares:
            shares[k].append(acc[k] / total)
    shares = {k: np.clip(np.array(v), 0.0, 1.0) for k, v in shares.items()}
    names = list(shares)
    table = np.stack([shares[k] for k in names], axis=1)
    kinds = tuple(names[i] for i in np.argmax(table, axis=1))
    return shares, kinds


def _roots(f, centres, half):
    """The root of f in each bracket [centre - half, centre + half], by bisection (vectorised; to the
    last bit of the bracket: SciPy's brentq would be no more exact here and costs its import)."""
    lo, hi = np.asarray(centres, float) - half, np.asarray(centres, float) + half
    neg = f(lo) < 0.0
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        same = (f(mid) < 0.0) == neg
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    return 0.5 * (lo + hi)


def euler_bernoulli_cantilever(length, EI, rhoA, n=3) -> np.ndarray:
    """First n bending angular frequencies of a clamped-free Euler-Bernoulli beam (rad/s)."""
    b = _roots(lambda x: np.cos(x) * np.cosh(x) + 1.0, (np.arange(n) + 0.5) * np.pi, 1.0)
    return (b / length) ** 2 * np.sqrt(EI / rhoA)


def euler_bernoulli_free_free(length, EI, rhoA, n=3) -> np.ndarray:
    """First n elastic bending angular frequencies of a free-free Euler-Bernoulli beam (rad/s)."""
    b = _roots(lambda x: np.cos(x) * np.cosh(x) - 1.0, (np.arange(n) + 1.5) * np.pi, 0.5)
    return (b / length) ** 2 * np.sqrt(EI / rhoA)


def centrifugal_stiffness(nodes, elements, sizes, stiffness, mass, held, young, poisson, axis_point):
    """The initial-stress (geometric) stiffness of the stress that spinning causes, per component of
    W = omega omega^T: six (3N, 3N) matrices K_k such that K_G(omega) = sum_k W_k K_k.

    For each component the structure, held at `held`, carries the quasi-static centrifugal load
    f = M (tr(E_k) I - E_k)(r - axis_point) (for W = omega omega^T the acceleration
    |omega|^2 r - omega (omega . r) of points turning about the axis through `axis_point`); its
    stress sigma (from the compatible part of the displacement, at the 2x2x2 Gauss points) gives
    K_G[a i, b j] = delta_ij int dN_a/dx_k sigma_kl dN_b/dx_l dV. A beam pulled by its spin is stiffer
    in bending: the stiffening that a linear floating frame lacks (Kane, Ryan & Banerjee 1987)."""
    N = nodes.shape[0]
    C = elasticity_matrix(young, poisson)
    free = np.flatnonzero(~np.repeat(np.asarray(held, dtype=bool), 3))
    M3 = np.kron(mass, np.eye(3))
    Kff = stiffness[np.ix_(free, free)]
    r = nodes - np.asarray(axis_point, dtype=float)[None, :]
    basis = [np.diag([1.0, 0, 0]), np.diag([0, 1.0, 0]), np.diag([0, 0, 1.0])]
    for i, j in ((1, 2), (0, 2), (0, 1)):
        e = np.zeros((3, 3))
        e[i, j] = e[j, i] = 1.0
        basis.append(e)
    half = sizes / 2.0                                                   # (E, 3)
    dNdxi = np.stack([HEX_CORNERS * np.prod(1 + HEX_CORNERS * xi, axis=1, keepdims=True) / (1 + HEX_CORNERS * xi) / 8.0
                      for xi in GAUSS8])                                # (G, 8, 3)
    dNdx = dNdxi[None, :, :, :] / half[:, None, None, :]                 # (E, G, 8, 3)
    vol = np.prod(half, axis=1)                                          # detJ, weights 1
    rows = np.repeat(elements, 8, axis=1).reshape(-1)
    cols = np.tile(elements, (1, 8)).reshape(-1)
    out = []
    for Ek in basis:
        acc = r @ (np.trace(Ek) * np.eye(3) - Ek).T                     # (N, 3)
        f = (M3 @ acc.reshape(-1))[free]
        u = np.zeros(3 * N)
        u[free] = np.linalg.solve(Kff, f)
        ue = u.reshape(N, 3)[elements]                                   # (E, 8, 3)
        grad = np.einsum("eai,egaj->egij", ue, dNdx)                     # du_i/dx_j
        eps = np.stack([grad[..., 0, 0], grad[..., 1, 1], grad[..., 2, 2], grad[..., 1, 2] + grad[..., 2, 1],
                        grad[..., 0, 2] + grad[..., 2, 0], grad[..., 0, 1] + grad[..., 1, 0]], axis=-1)
        s = eps @ C.T                                                    # (E, G, 6)
        sig = np.stack([np.stack([s[..., 0], s[..., 5], s[..., 4]], -1), np.stack([s[..., 5], s[..., 1], s[..., 3]], -1),
                        np.stack([s[..., 4], s[..., 3], s[..., 2]], -1)], -2)   # (E, G, 3, 3)
        ke = np.einsum("egak,egkl,egbl,e->eab", dNdx, sig, dNdx, vol)     # (E, 8, 8) scalar
        Ks = sp.coo_matrix((ke.reshape(-1), (rows, cols)), shape=(N, N)).toarray()
        out.append(np.kron(0.5 * (Ks + Ks.T), np.eye(3)))
    return out
