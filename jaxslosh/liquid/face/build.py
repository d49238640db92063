"""The full-order liquid of face-normal ("rt") tanks (liquid/face/term.py FaceLiquid) from their
models (liquid/face/element.py): the Gauss points' fields and masses, the blocks, the absolute-rotation
penalty and the nodal recovery's weights, host-side NumPy. The blocks are either kept without dense
matrices on the faces (`sparse_tank_blocks`: the mass element by element and the penalty's dense
part on the elements and top faces, liquid/face/schur.py), or dense on the free faces; both scale with
density, sound speed and gravity given in params (traced or not). A plain box's fill depth may be traced too on the
dense blocks: its layers scale with the depth, so every block is a closed function of h / h0
(`traced_depth_blocks`)."""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
from jax.scipy.linalg import block_diag as jax_block_diag
from scipy.linalg import block_diag

from .schur import face_schur, mass_bounds, project_pools
from .element import ROTATION_PENALTY_RATIO, FaceModel, _gauss, _loads, _Mixed, face_modes
from ...fem.mesh import box_gauss_points
from .walls import build_face_tank_with_walls, wall_points
from .blocks import FaceOps, FaceStiffness, owners, top_places
from .term import FaceLiquid
from ...scene.types import RT_FULL_FACES, SceneError
from .inverse import mass_inverse

#: free faces above which a full-order "rt" tank is refused on the dense path (its dense blocks: M, K
#: and two inverses); the sparse path (liquid/face/schur.py) has no such limit
MAX_FULL_FACES = RT_FULL_FACES
#: `simulation.linear_solver = "auto"` takes the sparse blocks above this many free faces in all
RT_SPARSE_AUTO = 0
#: rows of K formed at once for the sums of |K_ij| (the Newton iterations' round-off floor)
ROWS = 1024


def recovery_weights(model: FaceModel, gauss=None):
    """(nodes (G, 8), weights (G, 8)): FaceModel.nodal_fields as fixed weights, G = E x 8 Gauss
    points in element-major order: each node's value is the constant term of the linear field
    fitted by least squares to the Gauss-point values of its elements."""
    x = (_gauss(model) if gauss is None else gauss)[0]                 # (E, P, 3)
    E, P = x.shape[:2]
    rows = np.repeat(model.elements[:, None, :], P, axis=1)             # (E, P, 8)
    h = np.cbrt(model.volume)[:, None, None, None]
    d = (x[:, :, None, :] - model.nodes[rows]) / h
    A = np.concatenate([np.ones(d.shape[:-1] + (1,)), d], axis=-1)    # (E, P, 8, 4)
    N = len(model.nodes)
    AtA = np.zeros((N, 4, 4))
    np.add.at(AtA, rows.reshape(-1), np.einsum("...i,...j->...ij", A, A).reshape(-1, 4, 4))
    row0 = np.linalg.solve(AtA + 1e-12 * np.eye(4), np.broadcast_to(np.eye(4)[:, :1], (N, 4, 1)))[..., 0]
    w = np.einsum("epai,epai->epa", A, row0[rows])
    return rows.reshape(E * P, 8), w.reshape(E * P, 8)


def _kappa(model: FaceModel) -> float:
    """The penalty's kappa: its modes at ROTATION_PENALTY_RATIO times the highest of the 20 lowest
    modes that is sloshing (an acoustic mode would make it needlessly stiff)."""
    fm = face_modes(model, 20)
    slosh = [w for w, k in zip(fm.omega, fm.kind) if k == "sloshing"] or list(fm.omega)
    return (ROTATION_PENALTY_RATIO * float(max(slosh))) ** 2


def absolute_rotation_penalty(model: FaceModel, origin, gauss=None):
    """(K_c (nf, nf), K_dt (nf, 3), K_tt (3, 3)): the penalty 1/2 kappa |P (d + C theta)|_M^2 that holds
    the circulation (K's kernel, the M-orthogonal projection P onto it) at the part of the tank's
    rotation an ideal liquid does not follow, -P C theta (Kelvin: its absolute flow stays
    irrotational), as liquid/face/element.py face_basis does on its three circulation vectors; C: the
    rigid rotations e_k x r as fluxes (their M-projection). M P = M - B^T G^+ B, G = B M^-1 B^T.
    kappa: the penalty's modes at ROTATION_PENALTY_RATIO times the highest of the 20 lowest modes that
    is sloshing (an acoustic mode would make it needlessly stiff)."""
    gauss = _gauss(model) if gauss is None else gauss
    mixed = _Mixed(model)
    r = gauss[0] + np.asarray(origin, dtype=float)
    rot = np.stack([np.cross(np.eye(3)[k], r) for k in range(3)])
    c = mixed.Mlu.solve(_loads(model, gauss, rot)[mixed.f])
    Bd = mixed.B.toarray()
    Y = mixed.Mlu.solve(Bd.T)                                         # M^-1 B^T
    Gp = np.linalg.pinv(Bd @ Y, hermitian=True)
    Pc = c - Y @ (Gp @ (Bd @ c))
    MP = mixed.M.toarray() - Bd.T @ Gp @ Bd
    kappa = _kappa(model)
    MPc = mixed.M @ Pc
    return kappa * 0.5 * (MP + MP.T), kappa * MPc, kappa * (Pc.T @ MPc)


def sparse_tank_blocks(model: FaceModel, origin, gauss=None) -> dict:
    """One tank's full-order blocks without dense matrices on the faces (liquid/face/schur.py): the
    element mass blocks (signed), Y = W - kappa G^+ on its elements and top faces, the
    absolute-rotation penalty's K_dt, K_tt (as `absolute_rotation_penalty`, through G^+), the static
    start's columns K^-1 F for unit gravity along x, y, z, the sums of |K_ij| per row, and the
    spectral bounds of the Jacobi-scaled mass (the Chebyshev iteration's)."""
    gauss = _gauss(model) if gauss is None else gauss
    x, w, phys = gauss
    sch = face_schur(model)
    kappa = _kappa(model)
    r = x + np.asarray(origin, dtype=float)
    rot = np.stack([np.cross(np.eye(3)[k], r) for k in range(3)])
    Pc = sch.kernel_part(sch.minv(_loads(model, gauss, rot)[sch.f]))
    MPc = sch.M @ Pc
    uniform = np.stack([np.broadcast_to(np.eye(3)[k], x.shape) for k in range(3)])
    load = _loads(model, gauss, uniform)[sch.f]
    start = sch.static_solve(load, kappa)
    u0 = sch.minv(load)                 # M^-1 F and B M^-1 F: the start at scaled values (`scaled_start`)
    Y = np.diag(1.0 / sch.winv) - kappa * sch.Gp
    Me = model.density * np.einsum("epfi,epgi,ep->efg", phys, phys, w)        # phys carries the signs
    nf = sch.f.size
    rowsum = np.empty(nf)
    Bc, Mr = sch.B.tocsc(), sch.M.tocsr()
    for s in range(0, nf, ROWS):
        rows = (Bc[:, s:s + ROWS].T @ Y) @ sch.B + kappa * Mr[s:s + ROWS].toarray()   # K's rows s..
        rowsum[s:s + ROWS] = np.abs(rows).sum(axis=1)
    slot = np.full(len(model.faces), -1)
    slot[sch.f] = np.arange(nf)
    return dict(nf=nf, kappa=kappa, Y=Y, winv=sch.winv, Kdt=kappa * MPc, Ktt=kappa * (Pc.T @ MPc), start=start,
                Me=Me, slots=slot[model.element_faces], signs=model.signs, top=slot[model.top], rowsum=rowsum,
                diag=sch.M.diagonal(), bounds=mass_bounds(sch.M, sch.Mlu), pools=sch.N, u0=u0, z0=sch.B @ u0,
                E=len(model.elements))


def stack_sparse(parts: list, scales=None) -> tuple:
    """(FaceStiffness, MassInverse, start (n, 3)) of the tanks' `sparse_tank_blocks`, stacked (tank
    after tank). `scales`: per tank None or its (rho, rho c^2, rho g) over its model's
    (stack.py face_scales), traced or not: the mass M and the penalty kappa M P scale with
    the first (G^+ with it, as G = B M^-1 B^T scales inversely), W's elements (the compression) with
    the second and its top faces (the free surface) with the third, as the dense blocks do."""
    scales = [(1.0, 1.0, 1.0) if sc is None else sc for sc in (scales or [None] * len(parts))]
    n = sum(p["nf"] for p in parts)
    slots, tops, elements, top_ranges, off, e0, t0 = [], [], [], [], 0, 0, 0
    for p in parts:
        slots.append(np.where(p["slots"] < 0, n, p["slots"] + off))
        tops.append(p["top"] + off)
        E, T = len(p["slots"]), len(p["top"])
        elements.append((e0, e0 + E))
        top_ranges.append((t0, t0 + T))
        off, e0, t0 = off + p["nf"], e0 + E, t0 + T
    slots = np.concatenate(slots).astype(np.int32)
    top = np.concatenate(tops).astype(np.int32)
    ops = FaceOps(jnp.asarray(slots), jnp.asarray(np.concatenate([p["signs"] for p in parts])), jnp.asarray(top), n,
                  tuple(elements), tuple(top_ranges), jnp.asarray(owners(slots, n)), jnp.asarray(top_places(top, n)))
    kappa_n = np.concatenate([np.full(p["nf"], p["kappa"]) for p in parts])
    lo = min(p["bounds"][0] for p in parts)
    hi = max(p["bounds"][1] for p in parts)
    if all(_unit(v) for sc in scales for v in sc):      # the scene's values: every block on the host
        Me = np.concatenate([p["Me"] for p in parts])
        kM = np.concatenate([p["kappa"] * p["Me"] for p in parts])
        K = FaceStiffness(ops, jnp.asarray(kM), tuple(jnp.asarray(p["Y"]) for p in parts),
                          jnp.asarray(np.concatenate([p["rowsum"] for p in parts])),
                          tuple(jnp.asarray(p["winv"]) for p in parts), jnp.asarray(kappa_n),
                          jnp.asarray([p["kappa"] for p in parts]))
        Minv = mass_inverse(ops, Me, np.concatenate([p["diag"] for p in parts]), lo, hi)
        return K, Minv, np.concatenate([p["start"] for p in parts])
    sr = [jnp.asarray(sc[0], dtype=float) for sc in scales]
    # W_s = diag(sc on the elements, sg on the top faces) W; Y_s = W_s - sr kappa G^+ = sr Y + (W_s - sr W)
    ws = [jnp.concatenate([jnp.full(p["E"], sc[1], dtype=float), jnp.full(len(p["top"]), sc[2], dtype=float)])
          for p, sc in zip(parts, scales)]
    Y = tuple(r * p["Y"] + jnp.diag((w - r) / p["winv"]) for p, r, w in zip(parts, sr, ws))
    winv = tuple(p["winv"] / w for p, w in zip(parts, ws))
    # sum_j |K_ij| bounded by the largest of the three factors (a round-off floor, not a value)
    rowsum = jnp.concatenate([jnp.max(jnp.abs(jnp.stack([jnp.asarray(v, dtype=float) for v in sc]))) * p["rowsum"]
                              for p, sc in zip(parts, scales)])
    K = FaceStiffness(ops, jnp.concatenate([r * p["kappa"] * p["Me"] for p, r in zip(parts, sr)]), Y, rowsum,
                      winv, jnp.asarray(kappa_n), jnp.asarray([p["kappa"] for p in parts]), rho=tuple(sr),
                      pools=tuple(jnp.asarray(p["pools"]) for p in parts))
    Minv = mass_inverse(ops, jnp.concatenate([r * p["Me"] for p, r in zip(parts, sr)]),
                        jnp.concatenate([r * p["diag"] for p, r in zip(parts, sr)]), lo, hi)
    return K, Minv, scaled_start(parts, K, Minv)


def _unit(v) -> bool:
    return not isinstance(v, jax.core.Tracer) and abs(float(np.asarray(v)) - 1.0) <= 1e-12


def scaled_start(parts, K, Minv):
    """The static start's columns K_s^-1 F_s (F_s = rho_s F: the loads scale with the mass) at scaled
    values: K_s = rho_s K', K' = kappa M + B^T (W' - kappa G^+) B with W' = W_s / rho_s, so the start is
    K'^-1 F = M^-1 (F / kappa - B^T H_0 B M^-1 F), H_0 = G'^+ / kappa - G'^+ W'^-1 G'^+ with G^+
    projected onto W'^-1's complement of the pools (liquid/face/schur.py static_solve). M^-1 F and
    B M^-1 F come from the host; the last M^-1 is the Chebyshev iteration's (rho_s M^-1_s)."""
    ys, u0, rho_n = [], [], []
    for p, Y, wi, r, N in zip(parts, K.Y, K.winv, K.rho, K.pools):
        w1 = r * wi                                                        # W'^-1
        Gp = project_pools((jnp.diag(1.0 / wi) - Y) / (r * p["kappa"]), w1, N, jnp)
        Gz = Gp @ p["z0"]
        ys.append(Gz / p["kappa"] - Gp @ (w1[:, None] * Gz))
        u0.append(p["u0"] / p["kappa"])
        rho_n.append(jnp.full(p["nf"], r))
    return jnp.concatenate(u0) - jnp.concatenate(rho_n)[:, None] * (Minv @ K.ops.BT(ys))


def _component_masses(model, w, phys):
    """(M_xy, M_z) on the free faces (dense): the consistent mass's horizontal and vertical parts."""
    f = np.flatnonzero(model.free)
    rows = np.repeat(model.element_faces, 6, axis=1).reshape(-1)
    cols = np.tile(model.element_faces, (1, 6)).reshape(-1)
    out = []
    for comp in (slice(0, 2), slice(2, 3)):
        Me = model.density * np.einsum("epfi,epgi,ep->efg", phys[..., comp], phys[..., comp], w)
        M = sp.coo_matrix((Me.reshape(-1), (rows, cols)), shape=(len(model.faces),) * 2).tocsr()
        out.append(M[f][:, f].toarray())
    return out


def traced_depth_blocks(model: FaceModel, origin, s, gauss=None):
    """A plain box's blocks at the fill depth s h0 (s traced), from its model at h0: the layers scale
    with the depth (z = s z0), so J = diag(1, 1, s) J0, det J = s det J0 and the Piola field is
    diag(1/s, 1/s, 1) u0. Returns (x (E, P, 3), w (E, P), phys (E, P, 6, 3), M, K_acoustic, K_c,
    K_dt, K_tt) on the free faces, in the model's density: the mass M_xy / s + s M_z, the compression
    over s, and the absolute-rotation penalty of `absolute_rotation_penalty` in JAX (G^+ from G
    plus the pools' null vectors, which are topological) with kappa held at h0's (it sets how stiffly
    the circulation is held, not the physics)."""
    gauss = _gauss(model) if gauss is None else gauss
    x0, w0, phys0 = gauss
    mixed = _Mixed(model)
    f = mixed.f
    Mxy, Mz = _component_masses(model, w0, phys0)
    S = jnp.stack([1.0 / s, 1.0 / s, jnp.ones_like(s)])
    x = x0 * jnp.stack([jnp.ones_like(s), jnp.ones_like(s), s])
    w, phys = w0 * s, phys0 * S
    M = Mxy / s + Mz * s
    Kac = jnp.asarray(model.acoustic[f][:, f].toarray()) / s
    B = mixed.B.toarray()
    N = mixed.P                                        # orthonormal null vectors of G (one per pool)
    G0 = B @ mixed.Mlu.solve(B.T)
    alpha = np.trace(G0) / G0.shape[0]
    Y = jnp.linalg.solve(M, B.T)
    Gp = jnp.linalg.inv(B @ Y + alpha * N @ N.T) - N @ N.T / alpha
    r = x + jnp.asarray(origin, dtype=float)
    rot = jnp.stack([jnp.cross(jnp.eye(3)[k], r) for k in range(3)])                # (3, E, P, 3)
    local = model.density * jnp.einsum("ep,epfi,kepi->efk", w, phys, rot)            # (E, 6, 3)
    F = jax.ops.segment_sum(local.reshape(-1, 3), model.element_faces.reshape(-1), len(model.faces))[f]
    c = jnp.linalg.solve(M, F)
    Pc = c - Y @ (Gp @ (B @ c))
    MP = M - B.T @ Gp @ B
    fm = face_modes(model, 20)
    slosh = [v for v, k in zip(fm.omega, fm.kind) if k == "sloshing"] or list(fm.omega)
    kappa = (ROTATION_PENALTY_RATIO * float(max(slosh))) ** 2
    MPc = M @ Pc
    return x, w, phys, M, Kac, kappa * 0.5 * (MP + MP.T), kappa * MPc, kappa * (Pc.T @ MPc)


def face_full_liquid(tanks, models, scales=None, depths=None, sparse=False, structures=()):
    """The FaceLiquid of every tank (all face-normal, full order), stacked, the (K_dt, K_tt) of the
    absolute-rotation penalty (liquid/base.py RotationPenalty), and per tank its elastic walls
    (liquid/walls.py WallModel) or None. `scales`: per tank None or its (rho, rho c^2, rho g) over its
    model's (stack.py face_scales), traced or not: the masses, the compression and the
    free-surface blocks scale with them. `depths`: per tank None or a plain box's fill depth over its
    model's (traced): `traced_depth_blocks`. A tank with elastic walls (liquid/face/walls.py) adds its
    walls' free nodal dofs after its free faces, and its walls' Gauss points after every tank's liquid
    points; its values are the scene's. `structures` (assemble/structures.py HeldStructure, frame =
    "vessel"): their free nodal dofs after every tank's unknowns, their Gauss points last, as the
    walls' but with no face's flux tied to them (the dense blocks only)."""
    scales = scales or [None] * len(models)
    depths = depths or [None] * len(models)
    xp = jnp if any(isinstance(v, jax.core.Tracer) for sc in scales if sc for v in sc) \
        or any(isinstance(d, jax.core.Tracer) for d in depths) else np
    rs, ms, phis, slots, Ks, Ms, row_scales, rec_n, rec_w, Kdts = ([] for _ in range(10))
    walls, wall_parts, node_slots, parts = [], [], [], []          # wall_parts: (rows, cols, coef, x, m, N, slots) per tank
    Ktt = 0.0
    off, node_off, n_wf = 0, 0, 0
    HELD = -1                                           # the zero slot, known once every tank is counted
    for i, (t, model, fs, ds) in enumerate(zip(tanks, models, scales, depths)):
        sr, sc, sg = fs if fs is not None else (1.0, 1.0, 1.0)
        f = np.flatnonzero(model.free)
        if f.size > MAX_FULL_FACES and not sparse:
            if ds is not None:
                raise SceneError(f"tanks[{i}].fill_depth", f"a traced fill depth of a full-order \"rt\" tank needs "
                                                           f"the dense blocks, and this mesh holds {f.size} free "
                                                           f"faces, more than {MAX_FULL_FACES} for them: trace the "
                                                           "fill depth on a coarser mesh")
            dense_only = structures or any(u.form.elastic for u in tanks)
            hint = ("elastic walls and structures in the vessel's frame take the dense blocks only: use a coarser "
                    "mesh, or set element = \"stabilized\"") if dense_only else \
                ("leave simulation.linear_solver at \"auto\" (or \"sparse\"), add a [tanks.reduction] table (modes = "
                 "N), or set element = \"stabilized\"")
            raise SceneError(f"tanks[{i}].fluid.element", f"a full-order \"rt\" tank holds {f.size} free faces on "
                                                          f"this mesh, more than {MAX_FULL_FACES} for the dense "
                                                          f"blocks: {hint}")
        gauss = _gauss(model)
        E, P = gauss[0].shape[:2]
        slot = np.full(len(model.faces), HELD)
        slot[f] = np.arange(f.size) + off
        tw = None
        if t.form.elastic:
            if ds is not None or any(isinstance(v, jax.core.Tracer) for v in (fs or ())):
                raise SceneError(f"tanks[{i}].walls", "elastic walls need the liquid with the scene's own values "
                                                      "(no traced fill depth, density, sound speed or gravity)")
            tw = build_face_tank_with_walls(t, model)
            x, w, phys = gauss
            Mf, Kf, Kdt, Ktt_t = tw.mass, tw.stiffness + tw.penalty, tw.Kdt, tw.Ktt
            Tw = tw.T[:, f.size:].tocoo()
            wf = np.unique(Tw.row)                                       # the wall faces, in face order
            local = np.searchsorted(wf, Tw.row)
            slot[wf] = -2 - (n_wf + np.arange(wf.size))                  # coded: wall face n_wf + j
            nq = f.size
            xw, mw, Nw, sw = wall_points(tw.walls, tw.wall_dofs, off + nq, HELD)
            wall_parts.append((n_wf + local, off + nq + Tw.col, Tw.data, xw + np.asarray(t.origin, dtype=float),
                               mw, Nw, sw))
            n_wf += wf.size
            ns = np.full((model.n_nodes + len(tw.walls.nodes), 3), HELD)
            ns[model.n_nodes:].reshape(-1)[tw.wall_dofs] = off + nq + np.arange(tw.wall_dofs.size)
            node_slots.append(ns)
            walls.append(tw.walls)
        elif sparse:                    # no dense matrix on the faces (the scene's own values, no walls)
            x, w, phys = gauss
            parts.append(sparse_tank_blocks(model, t.origin, gauss))
            Kdt, Ktt_t, Mf, Kf = parts[-1]["Kdt"], parts[-1]["Ktt"], None, None
        elif ds is None:
            x, w, phys = gauss
            Kc, Kdt, Ktt_t = absolute_rotation_penalty(model, t.origin, gauss)
            Mf, Kac = model.mass[f][:, f].toarray(), model.acoustic[f][:, f].toarray()
            Kf = sc * Kac + sg * model.surface[f][:, f].toarray() + sr * Kc
        else:
            x, w, phys, Mf, Kac, Kc, Kdt, Ktt_t = traced_depth_blocks(model, t.origin, ds, gauss)
            Kf = sc * Kac + sg * model.surface[f][:, f].toarray() + sr * Kc
        if tw is None:
            walls.append(None)
            node_slots.append(np.full((model.n_nodes, 3), HELD))
        rs.append((x + np.asarray(t.origin, dtype=float)).reshape(-1, 3))
        ms.append(sr * (model.density * w).reshape(-1))
        phis.append(phys.reshape(E * P, 6, 3))
        slots.append(np.repeat(slot[model.element_faces], P, axis=0).reshape(E * P, 6))
        if Kf is not None:
            Ks.append(Kf)
            Ms.append(sr * Mf)
        Kdts.append(sr * Kdt)
        Ktt = Ktt + sr * Ktt_t
        X = model.nodes[model.faces[f]]
        area = np.linalg.norm(0.5 * np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1]), axis=1)
        rscale = model.mass[f][:, f].diagonal() * area
        if tw is not None:                         # a wall dof's row over its mass (liquid's share included)
            rscale = np.concatenate([rscale, np.diag(tw.mass)[f.size:]])
        row_scales.append(rscale)
        n_, w_ = recovery_weights(model, gauss)
        rec_n.append(n_ + node_off)
        rec_w.append(w_)
        off += f.size if Mf is None else Mf.shape[0]
        node_off += node_slots[-1].shape[0]
    if structures and sparse:
        raise ValueError("structures in the vessel's frame take the dense blocks")
    for hs in structures:               # block-diagonal: no flux of theirs, the liquid meets them through the vessel
        slot_of = np.full(3 * len(hs.nodes), HELD)
        slot_of[hs.free] = off + np.arange(hs.free.size)
        xs, mst, Ns, sls = box_gauss_points(hs.nodes, hs.elements, hs.density, slot_of)
        none = np.zeros(0, dtype=int)
        wall_parts.append((none, none, np.zeros(0), xs + hs.origin, mst, Ns, sls))
        node_slots.append(slot_of.reshape(-1, 3))
        Ks.append(hs.stiffness)
        Ms.append(np.kron(hs.mass, np.eye(3))[np.ix_(hs.free, hs.free)])
        Kdts.append(np.zeros((hs.free.size, 3)))
        row_scales.append(np.repeat(hs.mass.sum(axis=1), 3)[hs.free])     # its lumped mass per dof
        off += hs.free.size
        node_off += len(hs.nodes)
    fix = lambda a: np.where(a == HELD, off, np.where(a <= -2, off + 1 + (-2 - a), a)).astype(np.int32)  # noqa: E731
    slot = fix(np.concatenate(slots))
    if sparse:
        K, Minv, start = stack_sparse(parts, scales)
        phi = np.concatenate(phis)
        E = phi.shape[0] // P          # every tank's points element by element, P = 8 each (_gauss)
        blocks = dict(K=K, Mff=None, Minv=Minv, start=jnp.asarray(start), sparse=True,
                      phi_e=None if wall_parts else jnp.asarray(phi.reshape(E, P, 6, 3).transpose(0, 2, 1, 3)
                                                                .reshape(E, 6, P * 3)))
    else:
        stack = jax_block_diag if xp is jnp else block_diag
        blocks = dict(K=jnp.asarray(stack(*Ks)), Mff=jnp.asarray(stack(*Ms)))
    extra = {}
    if wall_parts:
        rows, cols, coef, xw, mw, Nw, sw = (np.concatenate(p) for p in zip(*wall_parts))
        rs.append(xw)
        ms.append(mw)
        extra = dict(wall_rows=jnp.asarray(rows.astype(np.int32)), wall_cols=jnp.asarray(cols.astype(np.int32)),
                     wall_coef=jnp.asarray(coef), wall_N=jnp.asarray(Nw), wall_slots=jnp.asarray(fix(sw)),
                     node_slots=jnp.asarray(fix(np.concatenate(node_slots))), n_wall_faces=n_wf,
                     n_liquid_points=int(sum(len(p) for p in phis)))
    liquid = FaceLiquid(r=jnp.asarray(xp.concatenate(rs)), m=jnp.asarray(xp.concatenate(ms)),
                        phi=jnp.asarray(xp.concatenate(phis)), slots=jnp.asarray(slot),
                        scale=jnp.asarray(np.concatenate(row_scales)), rec_nodes=jnp.asarray(np.concatenate(rec_n)),
                        rec_w=jnp.asarray(np.concatenate(rec_w)), n_nodes=node_off, **blocks, **extra)
    return liquid, (jnp.asarray(xp.concatenate(Kdts)), jnp.asarray(Ktt)), tuple(walls)
