"""Liquid in a rigid rectangular tank: the displacement finite elements of the paper's section 5.

González & Park (2013) model the liquid as an inviscid, slightly compressible solid without shear
stiffness, discretised with 8-node hexahedra and 3 displacement unknowns per node, linearised about
the hydrostatic state (eq. 28). Its element stiffness is the mean-dilatation acoustic term (eq. 30)
plus a geometric term from the hydrostatic pre-stress (eq. 31); gravity turning with the body is the
load (eq. 32). This module builds that static model once, in NumPy (the element matrices are Hessians
of element energies, taken with JAX and vmapped over elements, in float64 inside a scoped
``jax.enable_x64`` so that nothing is switched on globally).

Conventions
-----------
* Tank-local coordinates from the tank's inner min corner; the liquid fills [0,a] x [0,b] x [0,h].
* Node (i, j, k) of the (nx, ny, nz) grid has index ``(i*(ny+1) + j)*(nz+1) + k``; elements use the
  standard hex8 ordering (bottom face counter-clockwise, then the top face).
* Degrees of freedom are node-major: dof ``3*n + c`` is component c of node n.
* ``mass`` is a scalar (N, N) matrix; the 3N mass matrix is ``kron(mass, eye(3))``.
* ``free`` is False for the wall-normal dofs (slip walls x=0, x=a, y=0, y=b and the bottom z=0).
* The equation the transient solver integrates (tank frame, relative displacement d):
  ``kron(mass, I3) d'' + stiffness d = kron(mass, I3) tile(g_body)`` on the free dofs, with
  ``g_body = A^T (0, 0, -g)``; see ``LiquidModel.body_force``.

Element forms (``ELEMENT_FORMS``)
---------------------------------
``"paper"`` -- the literal eqs. (30)-(31): mean dilatation plus ``int p0 grad(phi)^T grad(phi) dV``
(full 2x2x2 Gauss), with the gauge pressure ``p0 = rho g (h - z)`` (PHYSICS.md traps 1-2) and a
consistent mass. The literal term equals the consistent pre-stress energy (which, by parts, is the
free-surface energy ``1/2 rho g int_FS u_z^2``) plus ``p0 (div u)^2 + p0 |curl u|^2``: a rotation
penalty that vanishes at the free surface. Known defects (measured, see tests): a circulation mode
at 2.90 rad/s inside the sloshing band of the 5x5x3 m tank on the 5x5x5 mesh, sloshing frequencies
1.5-4.5 % high on that mesh, and a free surface that does not stay level under a static tilt
(its P0 pressure does not match the nodal free surface at the walls: 11 % on 5x5x5).

``"stabilized"`` (default) -- built so that the discrete hydrostatics is exact and no spurious mode
enters the sloshing band. Its stiffness is the sum of

1. acoustic: mean dilatation, eq. (30) (one pressure per element, "P0");
2. free surface: the by-parts form of the consistent pre-stress with the gauge p0 (PHYSICS.md
   trap 3): ``1/2 rho g sum_faces A (mean u_z)^2`` -- the gravity energy of the volume each top
   face displaces -- plus the small volume coupling ``-rho g int u_z (mean div u)``. The face mean
   (rather than the nodal field) is what matches the P0 pressure: for a linear pressure the balance
   of every surface node is then exact, so under a static tilt the free surface stays level;
3. rotation penalty ``1/2 kappa int |P curl d + 2 theta|^2 dV``: P projects each component curl_k
   onto span{1, x_k} inside the element (two Gauss points along axis k, one across). With the
   one-point divergence this is a "box scheme" for the discrete potential flow: every circulation
   mode is held far above the sloshing band (kappa = 10 rho g L, L the largest tank dimension; the
   lowest circulation mode is then about 6x the lowest sloshing one) and the sloshing modes do not
   lock (on 5x5x5 they move by < 0.05 % between kappa = 5e4 and 2e6 Pa). Along a row with an odd
   number n > 1 of elements the box scheme cannot close a uniform surface slope at both walls (an
   alternating-sum condition; the nodal surface of a tilt would carry a zig-zag of relative size
   1/n^2), so in the top layer the two wall elements of each such row are penalised on the
   difference of their curls only (see ``_rotation_penalty``). ``theta`` is the small body rotation
   (PHYSICS.md trap 5): ``stiffness`` holds the d-d block, ``rotation_coupling`` the d-theta block
   and ``rotation_stiffness`` the theta-theta block;
4. surface hourglass control that is zero on every linear surface field (so tilts stay exact):
   ``1/2 rho g A (h.u_z/4)^2`` per top face (h = (1,-1,1,-1)), and a weak surface "bending"
   ``1/2 eps rho g sum_nodes A (second difference of u_z)^2`` (eps = 0.025) against the zig-zag
   surface patterns that no element-local term can see.

Its mass is the kinetic energy ``1/2 rho int |v|^2`` integrated with 8 points at
``(+-xi_h, +-xi_h, +-xi_z)`` instead of Gauss' 1/sqrt(3). Any such rule keeps the total mass, the
centre of mass and the load ``kron(mass, I3) tile(g)`` (every column sum is the lumped nodal mass);
the spread is chosen to cancel the box scheme's O(h^2) dispersion: vertically, the mid-point
kinetic energy (xi_z -> 0) makes the discrete decay of a deep-water mode exact to O(h^2);
horizontally, the consistent mass is exact to O(h^2) for waves along an axis and a slightly narrower
rule balances diagonal ones. xi_z = 0.183 (0.9 of the way to mid-point, to keep M well conditioned,
cond ~ 600) and xi_h = 0.548 are calibrated on the 5x5x5, 10x10x6 and slab meshes (first four
distinct sloshing frequencies within 1.4 %, 0.42 % and 0.3 %). Side effect: second moments of this
mass (the frozen inertia R^T M R) are low by 2 beta (h_e/L)^2 (z^2: -3.6 %, x^2: -0.4 %, I_xx:
-1.2 % on 5x5x5; -0.7 % on 10x10x6).

Limits: a direction meshed with a single element carries no sloshing along it (its one-element
curl constraint holds the surface flat that way: a static tilt along it is not followed at all);
use >= 2 elements along every direction in which the surface should move.

Traceability: ``fill_depth``, ``density``, ``sound_speed`` and ``gravity`` may be JAX tracers (so
that ``jax.grad`` of a simulation works with respect to them). Everything that depends only on the
integer mesh -- connectivity, the ``free`` mask, the surface nodes, the rotation-penalty pairs and
the scatter indices of the assembly -- is NumPy and cached per mesh; the node coordinates, the
element matrices (the same JAX Hessians) and their assembly are JAX when traced (a jitted
scatter-add into dense matrices); with concrete values the same assembly code runs on NumPy and
SciPy (nothing to compile per mesh). With concrete values the model holds NumPy arrays and the
sparse ``parts``; with traced ones it holds JAX arrays and ``parts`` is empty (modes are never
traced).
The tank's length and breadth and the mesh counts are static.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import NamedTuple, Optional

import numpy as np
import scipy.sparse as sp

ELEMENT_FORMS = ("stabilized", "paper")

#: kappa = ROTATION_PENALTY * rho * g * max(a, b, h): kappa k^2 / rho >= 10 pi g k / L puts every circulation
#: mode well above the gravity waves of the same wavenumber (5x5x3 m tank, 5x5x5: first at 6.2x the first sloshing).
ROTATION_PENALTY = 10.0
#: stiffness of the 2D checkerboard of a top face relative to a uniform raise of that face.
SURFACE_HOURGLASS = 1.0
#: weight of the surface second-difference ("bending") term relative to the free-surface stiffness.
SURFACE_BENDING = 0.025
#: 1D kinetic-energy quadrature points +-xi for the stabilized mass (consistent: 1/sqrt(3)).
#: xi = sqrt(1 - 4 b) for the 1D off-diagonal mass b; b = (1 - beta)/6 with beta the blend towards
#: lumped (beta < 0: towards the mid-point rule). Horizontal beta = -0.05, vertical beta = -0.45.
MASS_XI_HORIZONTAL = float(np.sqrt(1.0 - 4.0 * (1.0 + 0.05) / 6.0))
MASS_XI_VERTICAL = float(np.sqrt(1.0 - 4.0 * (1.0 + 0.45) / 6.0))

_XI = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
_G = 1.0 / np.sqrt(3.0)
_GAUSS8 = np.array([[sx, sy, sz] for sx in (-_G, _G) for sy in (-_G, _G) for sz in (-_G, _G)])
_FACE_HOURGLASS = np.array([1.0, -1.0, 1.0, -1.0])


def _is_traced(x) -> bool:
    import jax
    return isinstance(x, jax.core.Tracer)


@dataclass(frozen=True, eq=False)
class LiquidModel:
    """Static finite-element model of the liquid in one rigid rectangular tank (tank frame).

    Units SI. ``stiffness`` and ``mass`` act on the relative displacement d (3N, node-major).
    Rotation penalty with a small body rotation theta (3-vector, body frame, rad): its energy is
    ``1/2 [d; theta]^T [[K_rot, rotation_coupling], [rotation_coupling^T, rotation_stiffness]] [d; theta]``
    where K_rot is already inside ``stiffness``. Add ``rotation_coupling @ theta`` to the internal
    force on d and ``rotation_coupling.T @ d + rotation_stiffness @ theta`` to the internal moment
    on the body to penalise the ABSOLUTE rotation (curl d + 2 theta) instead of the relative one
    (trap 5). theta is the body's rotation vector (body frame, small) since the attitude at which
    the liquid is irrotational (the start). Both are None for "paper" (its p0 |curl|^2 part stays
    on the relative rotation, as written).
    ``parts`` holds sparse (3N, 3N) energy measures used to classify modes: "free_surface" (the
    gravity energy of the free surface), "acoustic" (compression), "rotation" (the rotation
    penalty, or for "paper" the p0 |curl|^2 part of eq. 31). It is empty when the model was built
    from traced values (``traced``): then ``nodes``, ``mass``, ``stiffness``, the rotation blocks,
    ``density``, ``sound_speed``, ``gravity`` and ``depth`` are JAX values; ``free``, ``surface``
    and ``elements`` are always NumPy.
    """

    nodes: np.ndarray
    elements: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    free: np.ndarray
    surface: np.ndarray
    density: float
    sound_speed: float
    gravity: float
    size: tuple
    depth: float
    element: str
    mesh: tuple = (1, 1, 1)
    rotation_coupling: Optional[np.ndarray] = None
    rotation_stiffness: Optional[np.ndarray] = None
    parts: dict = field(default_factory=dict)
    traced: bool = False
    # sparse builds on a grid whose layers are uniform: the element matrices of each layer, for
    # products element by element (boxsolve.elements); None otherwise
    layers: Optional[dict] = None

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    def mass3(self):
        """The (3N, 3N) mass matrix kron(mass, I3)."""
        if self.traced:
            import jax.numpy as jnp
            return jnp.kron(self.mass, jnp.eye(3))
        return np.kron(self.mass, np.eye(3))

    def body_force(self, g_body):
        """Nodal force (3N,) of a uniform body acceleration field g_body (3,), m/s^2: kron(M, I3) tile(g)."""
        if self.traced or _is_traced(g_body):
            import jax.numpy as jnp
            return (self.mass @ jnp.tile(jnp.asarray(g_body, dtype=float), (self.n_nodes, 1))).reshape(-1)
        g_body = np.asarray(g_body, dtype=float)
        return (self.mass @ np.tile(g_body, (self.n_nodes, 1))).reshape(-1)

    def surface_faces(self) -> np.ndarray:
        """(F, 4) node indices of the top faces (counter-clockwise seen from above)."""
        nx, ny, nz = self.mesh
        top = np.arange(len(self.elements)).reshape(nx, ny, nz)[:, :, -1].reshape(-1)
        return self.elements[top][:, 4:8]


def build_liquid(size, fill_depth, mesh, density, sound_speed, gravity, element="stabilized",
                 sparse=False) -> LiquidModel:
    """Build the liquid model of a rigid tank of inner size (a, b, H) filled to ``fill_depth``.

    ``mesh`` = (nx, ny, nz) hexahedra over the liquid region; ``element`` one of ``ELEMENT_FORMS``.
    ``fill_depth``, ``density``, ``sound_speed`` and ``gravity`` may be JAX tracers (float64).
    ``sparse=True`` (concrete values only): ``mass`` and ``stiffness`` are SciPy CSR matrices, for
    meshes whose dense matrices would not fit (see sparse.py).
    """
    import jax
    import jax.numpy as jnp

    if element not in ELEMENT_FORMS:
        raise ValueError(f"element form {element!r} unknown; choose one of {ELEMENT_FORMS}")
    a, b = float(size[0]), float(size[1])
    nx, ny, nz = (int(m) for m in mesh)
    traced = any(_is_traced(v) for v in (fill_depth, density, sound_speed, gravity))
    if traced:
        if min(a, b) <= 0 or min(nx, ny, nz) < 1:
            raise ValueError("tank size, fill depth and mesh counts must be positive")
        h, rho, c, g = (jnp.asarray(v, dtype=jnp.float64) for v in (fill_depth, density, sound_speed, gravity))
    else:
        h = float(fill_depth)
        if min(a, b, h) <= 0 or min(nx, ny, nz) < 1:
            raise ValueError("tank size, fill depth and mesh counts must be positive")
        rho, c, g = float(density), float(sound_speed), float(gravity)

    topo = _topology(nx, ny, nz, element)
    with jax.enable_x64(True):
        xs, ys = np.linspace(0, a, nx + 1), np.linspace(0, b, ny + 1)
        if traced:
            zs = h * jnp.asarray(np.arange(nz + 1) / nz)
            gi, gj, gk = topo.grid.T
            nodes = jnp.stack([jnp.asarray(xs[gi]), jnp.asarray(ys[gj]), zs[gk]], axis=1)
        else:
            zs = np.linspace(0, h, nz + 1)
            X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
            nodes = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
        xe = nodes[topo.elements]                              # (E, 8, 3)
        xf = nodes[topo.faces][:, :, :2]                       # (F, 4, 2)
        el = _element_matrices(xe, xf, rho, c, g, h, element, with_parts=not traced)
        kappa = ROTATION_PENALTY * rho * g * (jnp.maximum(max(a, b), h) if traced else max(a, b, h))
        bending = SURFACE_BENDING * rho * g * (a / nx) * (b / ny)
        out = topo.assemble(el, kappa, bending, traced, sparse=sparse and not traced)
        mass, stiffness = out["mass"], out["stiffness"]
        coupling, theta_theta = out.get("coupling"), out.get("theta_theta")
        if sp.issparse(coupling):
            coupling = np.asarray(coupling.todense())

    parts = {}
    if not traced:
        parts = topo.parts(el, out)
    layers = _layer_blocks(el, out, (nx, ny, nz), element, bending) if sparse and not traced else None
    return LiquidModel(
        nodes=nodes, elements=topo.elements, mass=mass, stiffness=stiffness, free=topo.free.reshape(-1).copy(),
        surface=topo.surface.copy(), density=rho, sound_speed=c, gravity=g, size=tuple(float(s) for s in size),
        depth=h, element=element, mesh=(nx, ny, nz), rotation_coupling=coupling,
        rotation_stiffness=theta_theta, parts=parts, traced=traced, layers=layers,
    )


def _layer_blocks(el, out, mesh, form, bending):
    """The stiffness and mass as element matrices per layer (every element of a layer has the same
    ones on a uniform grid, see `_distinct`): {"stiffness": (nz, 24, 24), "mass": (nz, 8, 8),
    "surface": (4, 4) on the top faces' vertical dofs or None, "bending": the surface bending's
    scale}; None where the assembly holds anything else (the stabilized element's wall pairs of an
    odd mesh) or a layer is not uniform."""
    nx, ny, nz = mesh
    if form == "paper":
        Ke, Kf, bend = el["acoustic"] + el["prestress"], None, 0.0
    else:
        if len(out["pair_blocks"]):
            return None
        Ke = el["acoustic"] + el["coupling"] + out["rotation_blocks"]
        Kf, bend = el["free_surface"] + el["surface_hourglass"], float(bending)

    def per_layer(E, n):
        E = np.asarray(E).reshape(nx * ny, nz, n, n)
        if np.abs(E - E[:1]).max() > 1e-13 * np.abs(E).max():
            return None
        return E[0]
    Ks, Ms = per_layer(Ke, 24), per_layer(el["mass"], 8)
    if Ks is None or Ms is None:
        return None
    if Kf is not None:
        Kf = np.asarray(Kf)
        if np.abs(Kf - Kf[:1]).max() > 1e-13 * np.abs(Kf).max():
            return None
        Kf = 0.5 * (Kf[0] + Kf[0].T)
    return {"stiffness": 0.5 * (Ks + np.swapaxes(Ks, 1, 2)), "mass": Ms, "surface": Kf, "bending": bend}


def surface_bending_scale(model: LiquidModel) -> float:
    """The factor of `_surface_bending_pattern` in the stiffness (0 for the paper's form)."""
    if model.element == "paper":
        return 0.0
    nx, ny, _ = model.mesh
    return float(SURFACE_BENDING * model.density * model.gravity * (model.size[0] / nx) * (model.size[1] / ny))


# ----------------------------------------------------------------------------------------------
# topology (NumPy, cached per mesh) and assembly (SciPy for concrete values, a jitted JAX scatter-add for traced)

class _Topology(NamedTuple):
    grid: np.ndarray          # (N, 3) integer (i, j, k) of every node
    elements: np.ndarray      # (E, 8)
    faces: np.ndarray         # (F, 4) top faces
    free: np.ndarray          # (N, 3) bool
    surface: np.ndarray       # surface node indices
    assemble: object          # (el, kappa, bending, traced) -> dense matrices; see _topology
    parts: object             # (el, out) -> sparse energy measures (concrete values only)


def _box_elements(nx, ny, nz):
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    corner = ((_XI + 1) / 2).astype(int)                   # (8, 3) offsets of the hex8 nodes
    ii = i.reshape(-1, 1) + corner[:, 0]
    jj = j.reshape(-1, 1) + corner[:, 1]
    kk = k.reshape(-1, 1) + corner[:, 2]
    return (ii * (ny + 1) + jj) * (nz + 1) + kk


def _block_index(dofs):
    """(rows, cols) of the entries of the (k, k) blocks on the dof rows (B, k), block-major."""
    k = dofs.shape[1]
    return np.repeat(dofs, k, axis=1).reshape(-1), np.tile(dofs, (1, k)).reshape(-1)


def _coo(vals, rows, cols, shape):
    return sp.coo_matrix((np.asarray(vals).reshape(-1), (rows, cols)), shape=shape).tocsr()


class _SparseNumPy:
    """NumPy, except that `_scatter` assembles SciPy CSR matrices (large meshes, `sparse=True`)."""

    def __getattr__(self, name):
        return getattr(np, name)


_SPARSE_NP = _SparseNumPy()


def _scatter(xp, shape, rows, cols, vals):
    """Dense matrix of the summed COO entries: SciPy for NumPy values, a JAX scatter-add otherwise
    (a SciPy CSR matrix under `_SPARSE_NP`)."""
    if xp is _SPARSE_NP:
        return sp.coo_matrix((vals, (rows, cols)), shape=shape).tocsr()
    if xp is np:
        return sp.coo_matrix((vals, (rows, cols)), shape=shape).toarray()
    import jax.numpy as jnp
    return jnp.zeros(shape, dtype=vals.dtype).at[rows, cols].add(vals)


@functools.lru_cache(maxsize=64)
def _topology(nx, ny, nz, form) -> _Topology:
    """What depends only on the integer mesh (NumPy), and the assembly from element matrices.

    The assembly is written once for an array namespace: NumPy + SciPy when the element matrices
    are concrete (nothing to compile per mesh), JAX (jitted, scatter-add) when they are traced."""
    import jax
    import jax.numpy as jnp

    gi, gj, gk = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), np.arange(nz + 1), indexing="ij")
    grid = np.stack([gi.ravel(), gj.ravel(), gk.ravel()], axis=1)
    n = len(grid)
    size = 3 * n
    elements = _box_elements(nx, ny, nz)
    E = len(elements)
    faces = elements.reshape(nx, ny, nz, 8)[:, :, -1, 4:8].reshape(-1, 4)
    dofs = (3 * elements[:, :, None] + np.arange(3)).reshape(E, 24)
    fs_dofs = 3 * faces + 2
    free = np.ones((n, 3), dtype=bool)                     # slip walls: no normal displacement
    free[(grid[:, 0] == 0) | (grid[:, 0] == nx), 0] = False
    free[(grid[:, 1] == 0) | (grid[:, 1] == ny), 1] = False
    free[grid[:, 2] == 0, 2] = False
    surface = np.flatnonzero(grid[:, 2] == nz)

    r24, c24 = _block_index(dofs)
    r4, c4 = _block_index(fs_dofs)
    rm, cm = _block_index(elements)

    if form == "paper":
        def assemble_xp(xp, el, kappa, bending):
            K = _scatter(xp, (size, size), r24, c24, (el["acoustic"] + el["prestress"]).reshape(-1))
            M = _scatter(xp, (n, n), rm, cm, el["mass"].reshape(-1))
            return {"mass": M, "stiffness": 0.5 * (K + K.T)}

        def parts(el, out):
            return {"free_surface": _coo(el["free_surface"], r4, c4, (size, size)),
                    "acoustic": _coo(el["acoustic"], r24, c24, (size, size)),
                    "rotation": _coo(np.asarray(el["rotation"])[:, :24, :24], r24, c24, (size, size))}
    else:
        # stabilized: the rotation penalty's rows, the wall pairs and the surface bending pattern
        keep, pairs = _rotation_pairs(nx, ny, nz)
        keep_f = keep.astype(float)
        comp = np.repeat(np.arange(3), 2)                    # curl component of each of the six rows
        pe0, pe1, pk = (np.array([p[i] for p in pairs], dtype=int) for i in range(3))
        prow = 2 * pk[:, None] + np.arange(2)[None, :]       # (P, 2) curl rows of each pair
        pdofs = np.concatenate([dofs[pe0], dofs[pe1]], axis=1) if pairs else np.zeros((0, 48), dtype=int)
        pr, pc = _block_index(np.repeat(pdofs, 2, axis=0))   # two rows (s = 0, 1) per pair
        Br, Bc, Bv = _surface_bending_pattern(nx, ny, nz)
        Cr = np.repeat(dofs[:, None, :], 6, axis=1).reshape(-1)     # (E, 6, 24) -> d dof
        Cc = np.broadcast_to(comp[None, :, None], (E, 6, 24)).reshape(-1)
        rows_all = np.concatenate([r24, r4, pr, Br])
        cols_all = np.concatenate([c24, c4, pc, Bc])
        T_rows = keep_f @ (comp[:, None] == np.arange(3)[None, :])    # (E, 3) kept rows per component

        def rotation_blocks(xp, el, kappa):
            w = 0.5 * kappa * el["volume"]                    # weight of each of the six rows
            ck = el["axial_curl"] * keep_f[:, :, None]         # (E, 6, 24)
            blocks = xp.einsum("e,epa,epb->eab", w, ck, ck)
            if pairs:
                c0 = el["axial_curl"][pe0[:, None], prow]      # (P, 2, 24)
                c1 = el["axial_curl"][pe1[:, None], prow]
                r = xp.concatenate([c0, -c1], axis=2)          # (P, 2, 48): c0 - c1 on the pair's dofs
                pblocks = 0.5 * w[pe0][:, None, None, None] * r[..., :, None] * r[..., None, :]
            else:
                pblocks = xp.zeros((0, 2, 48, 48))
            return w, ck, blocks, pblocks

        def assemble_xp(xp, el, kappa, bending):
            w, ck, rblocks, pblocks = rotation_blocks(xp, el, kappa)
            vals = xp.concatenate([
                (el["acoustic"] + el["coupling"] + rblocks).reshape(-1),
                (el["free_surface"] + el["surface_hourglass"]).reshape(-1),
                pblocks.reshape(-1),
                bending * Bv])
            K = _scatter(xp, (size, size), rows_all, cols_all, vals)
            C = _scatter(xp, (size, 3), Cr, Cc, (2.0 * w[:, None, None] * ck).reshape(-1))
            T = xp.diag(4.0 * (w @ T_rows))
            M = _scatter(xp, (n, n), rm, cm, el["mass"].reshape(-1))
            return {"mass": M, "stiffness": 0.5 * (K + K.T), "coupling": C, "theta_theta": T,
                    "rotation_blocks": rblocks, "pair_blocks": pblocks}

        def parts(el, out):
            rot = _coo(np.concatenate([out["rotation_blocks"].reshape(-1), out["pair_blocks"].reshape(-1)]),
                       np.concatenate([r24, pr]), np.concatenate([c24, pc]), (size, size))
            return {"free_surface": _coo(el["free_surface"], r4, c4, (size, size)),
                    "acoustic": _coo(el["acoustic"], r24, c24, (size, size)),
                    "rotation": rot}

    traced_assemble = jax.jit(lambda el, kappa, bending: assemble_xp(jnp, el, kappa, bending))

    def assemble(el, kappa=None, bending=None, traced=False, sparse=False):
        if traced:
            return traced_assemble(el, kappa, bending)
        return assemble_xp(_SPARSE_NP if sparse else np, el, kappa, bending)

    return _Topology(grid, elements, faces, free, surface, assemble, parts)


def _rotation_pairs(nx, ny, nz):
    """The rows of 1/2 kappa int |P curl d + 2 theta|^2 (P: the axial projection, two points per component).

    Each element gives six rows (component k of curl d at xi_k = -+1/sqrt(3)) of weight kappa V/2.
    One exception, for a direction with an odd number n > 1 of elements: in the top layer, the
    one-point curl couples neighbouring nodes only through averages, so along a row of elements
    the shear of the top layer can close at both walls only if the alternating sum of the surface
    slopes vanishes, which a uniform slope (a tilt) violates when n is odd; the static tilt then
    shows an O(1/n^2) zig-zag of the nodal free surface. Replacing, in each such row, the two
    constraints of the elements at the walls by their difference removes exactly this
    incompatibility (the pair's sum component) and, for odd n, leaves no zero-energy mode; the
    difference carries weight kappa V/4 (energy 1/2 (w/2) (c0 - c1)^2) and no theta.
    Returns (keep (E, 6) bool: the rows penalised on their own, pairs [(e0, e1, k)]).
    """
    E = nx * ny * nz
    paired = np.zeros((E, 6), dtype=bool)
    idx = np.arange(E).reshape(nx, ny, nz)
    pairs = []
    if nx % 2 == 1 and nx > 1:                             # curl_y rows of the top-layer wall elements along x
        for j in range(ny):
            pairs.append((idx[0, j, -1], idx[-1, j, -1], 1))
    if ny % 2 == 1 and ny > 1:                             # curl_x rows of the top-layer wall elements along y
        for i in range(nx):
            pairs.append((idx[i, 0, -1], idx[i, -1, -1], 0))
    for e0, e1, k in pairs:
        paired[e0, 2 * k:2 * k + 2] = paired[e1, 2 * k:2 * k + 2] = True
    return ~paired, pairs


def _surface_bending_pattern(nx, ny, nz):
    """sum over surface nodes of (A / (hx hy)) (second difference of u_z)^2 along x and along y, as
    COO (rows, cols, values) of a (3N, 3N) matrix; times hx hy it is the bending measure.

    Only interior stencils are used, so the term vanishes on every linear surface field.
    """
    n = (nx + 1) * (ny + 1) * (nz + 1)

    def dof(i, j):
        return 3 * ((i * (ny + 1) + j) * (nz + 1) + nz) + 2

    rows, cols, vals, weights = [], [], [], []
    r = 0
    for j in range(ny + 1):
        wj = 0.5 if j in (0, ny) else 1.0
        for i in range(1, nx):
            rows += [r] * 3
            cols += [dof(i - 1, j), dof(i, j), dof(i + 1, j)]
            vals += [1.0, -2.0, 1.0]
            weights.append(wj)
            r += 1
    for i in range(nx + 1):
        wi = 0.5 if i in (0, nx) else 1.0
        for j in range(1, ny):
            rows += [r] * 3
            cols += [dof(i, j - 1), dof(i, j), dof(i, j + 1)]
            vals += [1.0, -2.0, 1.0]
            weights.append(wi)
            r += 1
    if r == 0:
        z = np.zeros(0, dtype=int)
        return z, z, np.zeros(0)
    D = sp.csr_matrix((vals, (rows, cols)), shape=(r, 3 * n))
    B = (D.T @ sp.diags(weights) @ D).tocoo()
    return B.row.astype(int), B.col.astype(int), B.data


# ----------------------------------------------------------------------------------------------
# element energies (JAX): their Hessians are the element matrices

_CHUNK = 128          # elements per jitted batch: fixed shapes, so each kernel compiles once per process


def _element_matrices(xe, xf, rho, c, g, h, form, with_parts=True):
    """Element matrices of every term (Hessians of the energies below): NumPy arrays for concrete
    values, JAX arrays when any input is traced.

    ``xe``/``xf`` NumPy or JAX; ``rho, c, g, h`` floats or tracers. Without ``with_parts`` the
    kernels needed only for the mode-classification measures ("paper": the consistent free surface
    and the p0 |curl|^2 part) are skipped."""
    import jax
    import jax.numpy as jnp

    with jax.enable_x64(True):
        xi_h, xi_z = (_G, _G) if form == "paper" else (MASS_XI_HORIZONTAL, MASS_XI_VERTICAL)
        if any(_is_traced(v) for v in (rho, c, g, h)):
            prm = jnp.stack([jnp.asarray(v, dtype=jnp.float64) for v in (rho, c, g, h, 0.0, xi_h, xi_z)])
        else:
            prm = jnp.array([rho, c, g, h, 0.0, xi_h, xi_z], dtype=jnp.float64)
        traced_x = _is_traced(xe) or _is_traced(prm)
        kern = _kernels(form)
        out = {}
        for name, (fn, on_faces) in kern.items():
            if not with_parts and form == "paper" and name in ("free_surface", "rotation"):
                continue
            x = xf if on_faces else xe
            n = len(x)
            if not traced_x:          # concrete: chunks cut and joined in NumPy (no eager JAX op to compile)
                # every energy is invariant under horizontal shifts (p0 depends on z only), so each
                # distinct element shape and height is computed once (a uniform grid: one per layer)
                x, expand = _distinct(np.asarray(x, dtype=np.float64), horizontal_only=not on_faces)
                n = len(x)
                blocks = []
                for i in range(0, n, _CHUNK):
                    chunk = x[i:i + _CHUNK]
                    pad = _CHUNK - len(chunk)
                    if pad:
                        chunk = np.concatenate([chunk, np.repeat(chunk[:1], pad, axis=0)])
                    blocks.append(np.asarray(fn(prm, jnp.asarray(chunk, dtype=jnp.float64)))[:_CHUNK - pad])
                out[name] = np.concatenate(blocks)[expand]
            else:                     # traced: the same fixed-shape chunks, cut by dynamic slices
                x = jnp.asarray(x, dtype=jnp.float64)
                pad = -n % _CHUNK
                xpad = jnp.concatenate([x, jnp.repeat(x[:1], pad, axis=0)]) if pad else x
                blocks = [fn(prm, jax.lax.dynamic_slice_in_dim(xpad, i, _CHUNK)) for i in range(0, n, _CHUNK)]
                out[name] = (blocks[0] if len(blocks) == 1 else jnp.concatenate(blocks))[:n]
    return out


def _distinct(x, horizontal_only):
    """(the distinct elements of x (n, k, dim) up to a shift of their first corner, index of each
    element's representative): horizontal shifts for volume elements, any shift for surface faces."""
    rel = x.copy()
    dims = slice(0, 2) if horizontal_only else slice(None)
    rel[:, :, dims] -= x[:, :1, dims]
    scale = max(float(np.abs(x).max()), 1e-300)
    key = np.round(rel.reshape(len(x), -1) / scale, 11)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return x[first], inverse.reshape(-1)


_KERNEL_CACHE: dict = {}


def _kernels(form):
    """Jitted, batched Hessians of the element energies of one form: {name: (fn(prm, x), on_faces)}."""
    if form in _KERNEL_CACHE:
        return _KERNEL_CACHE[form]
    import jax
    import jax.numpy as jnp

    with jax.ensure_compile_time_eval(), jax.enable_x64(True):   # concrete constants even if first built under a trace
        XI = jnp.asarray(_XI)
        XI2 = jnp.asarray(_XI[:4, :2])
        gauss = jnp.asarray(_GAUSS8)
        gauss4 = jnp.asarray(_GAUSS8[::2, :2])
        corners = jnp.asarray(_XI)
        axial = jnp.asarray([[s if k == j else 0.0 for j in range(3)] for k in range(3) for s in (-_G, _G)])
        axial_comp = jnp.asarray([0, 0, 1, 1, 2, 2])

    def at(x, xi):
        """Shape values (8,), physical gradients (8, 3) and det J of the hex at reference point xi."""
        N = jnp.prod(1.0 + XI * xi, axis=1) / 8.0
        dN = jnp.stack([XI[:, k] * jnp.prod(jnp.where(jnp.arange(3) == k, 1.0, 1.0 + XI * xi), axis=1)
                        for k in range(3)], axis=1) / 8.0
        J = x.T @ dN
        return N, dN @ jnp.linalg.inv(J), jnp.linalg.det(J)

    def points(x, pts):
        return jax.vmap(at, in_axes=(None, 0))(x, pts)

    def grads(d, dNx):                                      # (P, 3, 3): u_i,k at each point
        return jnp.einsum("pak,ai->pik", dNx, d.reshape(8, 3))

    def curls(G):
        return jnp.stack([G[:, 2, 1] - G[:, 1, 2], G[:, 0, 2] - G[:, 2, 0], G[:, 1, 0] - G[:, 0, 1]], axis=1)

    def p0(prm, x, N):                                      # gauge hydrostatic pressure (traps 1-2)
        rho, g, h = prm[0], prm[2], prm[3]
        return rho * g * (h - N @ x[:, 2])

    def e_acoustic(d, prm, x):                              # eq. (30): rho c^2 (int div)^2 / (2 V)
        N, dNx, dJ = points(x, gauss)
        div = jnp.sum(jnp.trace(grads(d, dNx), axis1=1, axis2=2) * dJ)
        return 0.5 * prm[0] * prm[1] ** 2 * div**2 / jnp.sum(dJ)

    def e_coupling(d, prm, x):                              # -rho g int u_z (mean div)   (trap 3)
        N, dNx, dJ = points(x, gauss)
        div = jnp.sum(jnp.trace(grads(d, dNx), axis1=1, axis2=2) * dJ) / jnp.sum(dJ)
        uz = jnp.sum((N @ d.reshape(8, 3)[:, 2]) * dJ)
        return -prm[0] * prm[2] * div * uz

    def e_prestress_paper(d, prm, x):                       # eq. (31) literally: 1/2 int p0 |grad u|^2
        N, dNx, dJ = points(x, gauss)
        G = grads(d, dNx)
        return 0.5 * jnp.sum(p0(prm, x, N) * jnp.sum(G * G, axis=(1, 2)) * dJ)

    def e_rotation_paper(dt, prm, x):                       # the p0 |curl u + 2 theta|^2 part of eq. (31)
        d, theta = dt[:24], dt[24:]
        N, dNx, dJ = points(x, gauss)
        w = curls(grads(d, dNx)) + 2.0 * theta
        return 0.5 * jnp.sum(p0(prm, x, N) * jnp.sum(w * w, axis=1) * dJ)

    def axial_curl(d, prm, x):                              # curl_k d at xi_k = -+1/sqrt(3): P curl d
        N, dNx, dJ = points(x, axial)
        return curls(grads(d, dNx))[jnp.arange(6), axial_comp]

    def volume(prm, x):
        return jnp.sum(points(x, gauss)[2])

    def e_kinetic(v, prm, x):                               # 1/2 rho int v^2, scalar field, spread rule
        pts = corners * jnp.array([prm[5], prm[5], prm[6]])
        N, dNx, dJ = points(x, pts)
        return 0.5 * prm[0] * jnp.sum((N @ v) ** 2 * dJ)

    def face_at(y, xi):
        N = jnp.prod(1.0 + XI2 * xi, axis=1) / 4.0
        dN = jnp.stack([XI2[:, 0] * (1 + XI2[:, 1] * xi[1]), XI2[:, 1] * (1 + XI2[:, 0] * xi[0])], 1) / 4.0
        return N, jnp.linalg.det(y.T @ dN)

    def e_surface_consistent(uz, prm, y):                   # 1/2 rho g int_FS u_z^2 (2x2 Gauss)
        N, dJ = jax.vmap(face_at, in_axes=(None, 0))(y, gauss4)
        return 0.5 * prm[0] * prm[2] * jnp.sum((N @ uz) ** 2 * dJ)

    def e_surface_mean(uz, prm, y):                         # 1/2 rho g A (mean u_z)^2
        A = 4.0 * face_at(y, jnp.zeros(2))[1]
        return 0.5 * prm[0] * prm[2] * A * jnp.mean(uz) ** 2

    def e_surface_hourglass(uz, prm, y):                    # 1/2 rho g A (h . u_z / 4)^2, zero on linear fields
        A = 4.0 * face_at(y, jnp.zeros(2))[1]
        return 0.5 * SURFACE_HOURGLASS * prm[0] * prm[2] * A * (jnp.asarray(_FACE_HOURGLASS) @ uz / 4.0) ** 2

    def batched(fn, size, derivative=jax.hessian):
        H = derivative(fn)
        return jax.jit(jax.vmap(lambda prm, x: H(jnp.zeros(size, dtype=x.dtype), prm, x), in_axes=(None, 0)))

    kern = {
        "mass": (batched(e_kinetic, 8), False),
        "acoustic": (batched(e_acoustic, 24), False),
    }
    if form == "paper":
        kern["free_surface"] = (batched(e_surface_consistent, 4), True)
        kern["rotation"] = (batched(e_rotation_paper, 27), False)
        kern["prestress"] = (batched(e_prestress_paper, 24), False)
    else:
        kern["free_surface"] = (batched(e_surface_mean, 4), True)
        kern["axial_curl"] = (batched(axial_curl, 24, jax.jacfwd), False)
        kern["volume"] = (jax.jit(jax.vmap(volume, in_axes=(None, 0))), False)
        kern["coupling"] = (batched(e_coupling, 24), False)
        kern["surface_hourglass"] = (batched(e_surface_hourglass, 4), True)
    _KERNEL_CACHE[form] = kern
    return kern
