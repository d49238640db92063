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
  ``g_body = A^T (0, 0, -g)``; see ``NodalModel.body_force``.

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

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp

from .element import FLAT_CORNER_PENALTY, ROTATION_PENALTY, SURFACE_BENDING, element_matrices, is_traced
from ...fem.mesh import ELEMENT_FORMS, FACE_FORMS, box_elements, grid_index, grid_nodes
from ...fem.slip import rotate_matrix, rotate_rows, surface_jump_pattern


@dataclass(frozen=True, eq=False)
class NodalModel:
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
    # tanks of other shapes (jaxslosh/geometry): each node's frame (N, 3, 3), whose columns are its axes;
    # `stiffness`, `rotation_coupling`, `parts` and `free` are then on the components in these frames
    # (the scalar `mass` stays on the tank's axes); None: every frame is the tank's
    frames: Optional[np.ndarray] = None
    top_faces: Optional[np.ndarray] = None     # (F, 4) free-surface faces of a shaped tank
    wall_faces: Optional[np.ndarray] = None    # (W, 4) its wetted wall faces, outward
    geometry: Optional[object] = None          # the shape of a shaped tank (jaxslosh/geometry)

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    def mass3(self):
        """The (3N, 3N) mass matrix kron(mass, I3) (in the nodes' frames: R^T kron(mass, I3) R)."""
        xp = jnp if self.traced else np
        M3 = xp.kron(self.mass, xp.eye(3))
        return M3 if self.frames is None else rotate_matrix(xp, M3, self.frames)

    def to_local(self, F):
        """Nodal vectors (N, 3) on the tank's axes -> on the nodes' frames (the identity for a box)."""
        if self.frames is None:
            return F
        xp = jnp if (self.traced or is_traced(F)) else np
        return xp.einsum("nji,nj->ni", self.frames, F)

    def to_global(self, U):
        """Nodal vectors (..., N, 3) on the nodes' frames -> on the tank's axes."""
        if self.frames is None:
            return U
        xp = jnp if (self.traced or is_traced(U)) else np
        return xp.einsum("nij,...nj->...ni", self.frames, U)

    def body_force(self, g_body):
        """Nodal force (3N,) of a uniform body acceleration field g_body (3,), m/s^2: kron(M, I3) tile(g)."""
        if self.traced or is_traced(g_body):
            F = self.mass @ jnp.tile(jnp.asarray(g_body, dtype=float), (self.n_nodes, 1))
        else:
            F = self.mass @ np.tile(np.asarray(g_body, dtype=float), (self.n_nodes, 1))
        return self.to_local(F).reshape(-1)

    def surface_faces(self) -> np.ndarray:
        """(F, 4) node indices of the top faces (counter-clockwise seen from above)."""
        if self.top_faces is not None:
            return self.top_faces
        nx, ny, nz = self.mesh
        top = np.arange(len(self.elements)).reshape(nx, ny, nz)[:, :, -1].reshape(-1)
        return self.elements[top][:, 4:8]


def build_liquid(size, fill_depth, mesh, density, sound_speed, gravity, element="stabilized",
                 sparse=False, geometry=None) -> NodalModel:
    """Build the liquid model of a rigid tank of inner size (a, b, H) filled to ``fill_depth``.

    ``mesh`` = (nx, ny, nz) hexahedra over the liquid region; ``element`` one of ``ELEMENT_FORMS``.
    ``fill_depth``, ``density``, ``sound_speed`` and ``gravity`` may be JAX tracers (float64).
    ``sparse=True`` (concrete values only): ``mass`` and ``stiffness`` are SciPy CSR matrices, for
    meshes whose dense matrices would not fit (see liquid/nodal/sparse.py). ``geometry``: the tank's shape
    (jaxslosh/geometry) where it is not the plain box (then the fill depth is concrete).
    """
    if element not in ELEMENT_FORMS:
        raise ValueError(f"element form {element!r} unknown; choose one of {ELEMENT_FORMS} (the face-normal "
                         f"forms {FACE_FORMS} are liquid/face/element.py's)")
    if geometry is not None and not is_traced(fill_depth):
        counts = geometry.box_counts(float(fill_depth))
        if counts is not None:                 # a box grid given as a mesh file: the box itself
            return build_liquid(size, fill_depth, counts, density, sound_speed, gravity, element, sparse)
    if geometry is not None and not geometry.plain_box:
        return _build_shaped(geometry, fill_depth, mesh, density, sound_speed, gravity, element, sparse)
    a, b = float(size[0]), float(size[1])
    nx, ny, nz = (int(m) for m in mesh)
    traced = any(is_traced(v) for v in (fill_depth, density, sound_speed, gravity))
    if traced:
        if min(a, b) <= 0 or min(nx, ny, nz) < 1:
            raise ValueError("tank size, fill depth and mesh counts must be positive")
        h, rho, c, g = (jnp.asarray(v, dtype=jnp.float64) for v in (fill_depth, density, sound_speed, gravity))
    else:
        h = float(fill_depth)
        if min(a, b, h) <= 0 or min(nx, ny, nz) < 1:
            raise ValueError("tank size, fill depth and mesh counts must be positive")
        rho, c, g = float(density), float(sound_speed), float(gravity)

    topo = topology(nx, ny, nz, element)
    with jax.enable_x64(True):
        xs, ys = np.linspace(0, a, nx + 1), np.linspace(0, b, ny + 1)
        if traced:
            zs = h * jnp.asarray(np.arange(nz + 1) / nz)
            gi, gj, gk = topo.grid.T
            nodes = jnp.stack([jnp.asarray(xs[gi]), jnp.asarray(ys[gj]), zs[gk]], axis=1)
        else:
            nodes = grid_nodes((a, b, h), (nx, ny, nz))
        xe = nodes[topo.elements]                              # (E, 8, 3)
        xf = nodes[topo.faces][:, :, :2]                       # (F, 4, 2)
        el = element_matrices(xe, xf, rho, c, g, h, element, with_parts=not traced)
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
    layers = layer_blocks(el, out, (nx, ny, nz), element, bending) if sparse and not traced else None
    return NodalModel(
        nodes=nodes, elements=topo.elements, mass=mass, stiffness=stiffness, free=topo.free.reshape(-1).copy(),
        surface=topo.surface.copy(), density=rho, sound_speed=c, gravity=g, size=tuple(float(s) for s in size),
        depth=h, element=element, mesh=(nx, ny, nz), rotation_coupling=coupling,
        rotation_stiffness=theta_theta, parts=parts, traced=traced, layers=layers,
    )


def _build_shaped(geometry, fill_depth, mesh, rho, c, g, element, sparse) -> NodalModel:
    """`build_liquid` for another shape (jaxslosh/geometry): its mesh, then the matrices on the nodes' frames."""
    if is_traced(fill_depth):
        raise ValueError("the fill depth of a tank that is not a plain box cannot be traced (its mesh follows it)")
    traced = any(is_traced(v) for v in (rho, c, g))
    h = float(fill_depth)
    tm = geometry.mesh(h, mesh, graded=False)      # the layers of fem/shapes.py `breaks`: see AbstractShape.mesh
    nodes, elements, faces, frames = tm.nodes, tm.elements, tm.top_faces, tm.frames
    pairs = bending = None
    if element != "paper":
        keep, pairs = _rotation_pairs(*tm.grid) if tm.grid is not None else (np.ones((len(elements), 6), bool), [])
        for e0, e1, k in tm.pairs:                 # the shape's extra wall constraints (geometry/section.py)
            keep[[e0, e1], 2 * k:2 * k + 2] = False
        pairs = (keep, list(pairs) + list(tm.pairs))
        bending = surface_jump_pattern(nodes, faces)
    flat = tm.flat.astype(float)
    assemble, parts_of = _assembler(len(nodes), elements, faces, element, pairs, bending, flat)
    xp = jnp if traced else np
    with jax.enable_x64(True):
        if traced:
            density, sound_speed, gravity = (jnp.asarray(v, dtype=jnp.float64) for v in (rho, c, g))
        else:
            density, sound_speed, gravity = float(rho), float(c), float(g)
        el = element_matrices(nodes[elements], nodes[faces][:, :, :2], density, sound_speed, gravity, h, element,
                              with_parts=not traced, div_variation=element != "paper" and bool(flat.any()))
        kappa = ROTATION_PENALTY * density * gravity * float(np.ptp(nodes, axis=0).max())
        out = assemble(el, kappa, SURFACE_BENDING * density * gravity, traced, sparse=sparse and not traced)
        K, C, T = out["stiffness"], out.get("coupling"), out.get("theta_theta")
        C = np.asarray(C.todense()) if sp.issparse(C) else C
        if frames is not None:
            K = rotate_matrix(xp, K, frames)
            C = None if C is None else rotate_rows(xp, C, frames)
    parts = {} if traced else parts_of(el, out)
    if frames is not None:
        parts = {k: rotate_matrix(np, v, frames) for k, v in parts.items()}
    return NodalModel(
        nodes=nodes, elements=elements, mass=out["mass"], stiffness=K, free=tm.free.reshape(-1).copy(),
        surface=np.unique(faces), density=density, sound_speed=sound_speed, gravity=gravity,
        size=tuple(float(s) for s in geometry.size), depth=h, element=element,
        mesh=tuple(tm.grid) if tm.grid is not None else tuple(int(m) for m in mesh), rotation_coupling=C,
        rotation_stiffness=T, parts=parts, traced=traced, layers=None, frames=frames, top_faces=faces,
        wall_faces=tm.wall_faces, geometry=geometry)


def layer_blocks(el, out, mesh, form, bending):
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


def surface_bending_scale(model: NodalModel) -> float:
    """The factor of `surface_bending_pattern` in the stiffness (0 for the paper's form)."""
    if model.element == "paper":
        return 0.0
    nx, ny, _ = model.mesh
    return float(SURFACE_BENDING * model.density * model.gravity * (model.size[0] / nx) * (model.size[1] / ny))


class Topology(NamedTuple):
    grid: np.ndarray          # (N, 3) integer (i, j, k) of every node
    elements: np.ndarray      # (E, 8)
    faces: np.ndarray         # (F, 4) top faces
    free: np.ndarray          # (N, 3) bool
    surface: np.ndarray       # surface node indices
    assemble: object          # (el, kappa, bending, traced) -> dense matrices; see topology
    parts: object             # (el, out) -> sparse energy measures (concrete values only)


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
    return jnp.zeros(shape, dtype=vals.dtype).at[rows, cols].add(vals)


@functools.lru_cache(maxsize=64)
def topology(nx, ny, nz, form) -> Topology:
    """What depends only on the integer mesh (NumPy), and the assembly from element matrices.

    The assembly is written once for an array namespace: NumPy + SciPy when the element matrices
    are concrete (nothing to compile per mesh), JAX (jitted, scatter-add) when they are traced."""
    grid = grid_index(nx, ny, nz)
    n = len(grid)
    elements = box_elements(nx, ny, nz)
    faces = elements.reshape(nx, ny, nz, 8)[:, :, -1, 4:8].reshape(-1, 4)
    free = np.ones((n, 3), dtype=bool)                     # slip walls: no normal displacement
    free[(grid[:, 0] == 0) | (grid[:, 0] == nx), 0] = False
    free[(grid[:, 1] == 0) | (grid[:, 1] == ny), 1] = False
    free[grid[:, 2] == 0, 2] = False
    surface = np.flatnonzero(grid[:, 2] == nz)
    pairs = _rotation_pairs(nx, ny, nz) if form != "paper" else None
    bending = surface_bending_pattern(nx, ny, nz) if form != "paper" else None
    assemble, parts = _assembler(n, elements, faces, form, pairs, bending)
    return Topology(grid, elements, faces, free, surface, assemble, parts)


def _assembler(n, elements, faces, form, rotation_pairs, bending, flat=None):
    """(assemble, parts) of a mesh of n nodes: `rotation_pairs` = (keep, pairs) of the stabilized
    element's rotation rows (see `_rotation_pairs`), `bending` the COO (rows, cols, values) of its
    surface bending measure, `flat` (E,) 1.0 for the elements that get the divergence-variation
    penalty (liquid_element.FLAT_CORNER_PENALTY)."""
    size = 3 * n
    E = len(elements)
    dofs = (3 * elements[:, :, None] + np.arange(3)).reshape(E, 24)
    fs_dofs = 3 * faces + 2

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
        keep, pairs = rotation_pairs
        keep_f = keep.astype(float)
        comp = np.repeat(np.arange(3), 2)                    # curl component of each of the six rows
        pe0, pe1, pk = (np.array([p[i] for p in pairs], dtype=int) for i in range(3))
        prow = 2 * pk[:, None] + np.arange(2)[None, :]       # (P, 2) curl rows of each pair
        pdofs = np.concatenate([dofs[pe0], dofs[pe1]], axis=1) if pairs else np.zeros((0, 48), dtype=int)
        pr, pc = _block_index(np.repeat(pdofs, 2, axis=0))   # two rows (s = 0, 1) per pair
        Br, Bc, Bv = bending
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
            K24 = el["acoustic"] + el["coupling"] + rblocks
            if "div_variation" in el:                         # flat corners of a mapped mesh only
                K24 = K24 + (FLAT_CORNER_PENALTY * kappa) * el["div_variation"] * flat[:, None, None]
            vals = xp.concatenate([
                K24.reshape(-1),
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

    return assemble, parts


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


def surface_bending_pattern(nx, ny, nz):
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
