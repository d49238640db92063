"""The full-order liquid of face-normal ("rt") tanks (physics/face_liquid.py FluxLiquid) from their
models (fem/liquid_rt.py): the Gauss points' fields and masses, the dense blocks on the free faces,
the hydrostatic responses and the nodal recovery's weights, all host-side NumPy."""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from scipy.linalg import block_diag

from ..fem.liquid_rt import ROTATION_PENALTY_RATIO, FaceLiquid, _gauss, _loads, _Mixed, face_modes
from ..physics.face_liquid import FluxLiquid
from ..scene.types import RT_FULL_FACES, SceneError

#: free faces above which a full-order "rt" tank is refused (its dense blocks: M, K and two inverses)
MAX_FULL_FACES = RT_FULL_FACES


def recovery_weights(model: FaceLiquid, gauss=None):
    """(nodes (G, 8), weights (G, 8)): FaceLiquid.nodal_fields as fixed weights, G = E x 8 Gauss
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


def static_responses(model: FaceLiquid, gauss=None):
    """(nf, 3) on the free faces: K^+ F_k for the loads of unit uniform accelerations along x, y, z,
    the response M-orthogonal to K's kernel (fem/liquid_rt.py face_basis's mixed solves)."""
    gauss = _gauss(model) if gauss is None else gauss
    E, P = gauss[0].shape[:2]
    fields = np.zeros((3, E, P, 3))
    for k in range(3):
        fields[k, ..., k] = 1.0
    mixed = _Mixed(model)
    F = _loads(model, gauss, fields)[mixed.f]
    z, _ = mixed.solve(mixed.B @ mixed.Mlu.solve(F))
    _, Psi = mixed.solve(mixed.winv[:, None] * mixed.pool_fix(z))
    return Psi


def absolute_rotation_penalty(model: FaceLiquid, origin, gauss=None):
    """(K_c (nf, nf), K_dt (nf, 3), K_tt (3, 3)): the penalty 1/2 kappa |P (d + C theta)|_M^2 that holds
    the circulation (K's kernel, the M-orthogonal projection P onto it) at the part of the tank's
    rotation an ideal liquid does not follow, -P C theta (Kelvin: its absolute flow stays
    irrotational), as fem/liquid_rt.py face_basis does on its three circulation vectors; C: the
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
    fm = face_modes(model, 20)
    slosh = [w for w, k in zip(fm.omega, fm.kind) if k == "sloshing"] or list(fm.omega)
    kappa = (ROTATION_PENALTY_RATIO * float(max(slosh))) ** 2
    MPc = mixed.M @ Pc
    return kappa * 0.5 * (MP + MP.T), kappa * MPc, kappa * (Pc.T @ MPc)


def face_full_liquid(tanks, models):
    """The FluxLiquid of every tank (all face-normal, full order), stacked, and the (K_dt, K_tt) of
    the absolute-rotation penalty (physics/liquid.py RotationPenalty)."""
    rs, ms, phis, slots, Ks, Ms, Zs, scales, rec_n, rec_w, Kdts = ([] for _ in range(11))
    Ktt = np.zeros((3, 3))
    off, node_off = 0, 0
    for i, (t, model) in enumerate(zip(tanks, models)):
        f = np.flatnonzero(model.free)
        if f.size > MAX_FULL_FACES:
            raise SceneError(f"tanks[{i}].fluid.element", f"a full-order \"rt\" tank holds {f.size} free faces on "
                                                          f"this mesh, more than {MAX_FULL_FACES} (its blocks are dense): "
                                                          "add a [tanks.reduction] table (modes = N), or set "
                                                          "element = \"stabilized\"")
        gauss = _gauss(model)
        x, w, phys = gauss
        E, P = x.shape[:2]
        slot = np.full(len(model.faces), -1)
        slot[f] = np.arange(f.size) + off
        rs.append((x + np.asarray(t.origin, dtype=float)).reshape(-1, 3))
        ms.append((model.density * w).reshape(-1))
        phis.append(phys.reshape(E * P, 6, 3))
        slots.append(np.repeat(slot[model.element_faces], P, axis=0).reshape(E * P, 6))
        Kc, Kdt, Ktt_t = absolute_rotation_penalty(model, t.origin, gauss)
        Ks.append(model.stiffness[f][:, f].toarray() + Kc)
        Kdts.append(Kdt)
        Ktt = Ktt + Ktt_t
        Ms.append(model.mass[f][:, f].toarray())
        Zs.append(static_responses(model, gauss))
        X = model.nodes[model.faces[f]]
        area = np.linalg.norm(0.5 * np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1]), axis=1)
        scales.append(np.diag(Ms[-1]) * area)
        n_, w_ = recovery_weights(model, gauss)
        rec_n.append(n_ + node_off)
        rec_w.append(w_)
        off += f.size
        node_off += model.n_nodes
    slot = np.concatenate(slots)
    slot = np.where(slot < 0, off, slot)
    liquid = FluxLiquid(r=jnp.asarray(np.concatenate(rs)), m=jnp.asarray(np.concatenate(ms)),
                      phi=jnp.asarray(np.concatenate(phis)), slots=jnp.asarray(slot.astype(np.int32)),
                      K=jnp.asarray(block_diag(*Ks)), Mff=jnp.asarray(block_diag(*Ms)),
                      Z=jnp.asarray(np.concatenate(Zs, axis=0)),   # each tank answers the same g_b
                      scale=jnp.asarray(np.concatenate(scales)), rec_nodes=jnp.asarray(np.concatenate(rec_n)),
                      rec_w=jnp.asarray(np.concatenate(rec_w)), n_nodes=node_off)
    return liquid, (jnp.asarray(np.concatenate(Kdts)), jnp.asarray(Ktt))

