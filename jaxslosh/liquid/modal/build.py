"""The reduced liquid of a scene's tanks: their modal bases (liquid/modal/reduction.py) and the inertia
invariants of liquid/modal/term.py, computed once."""
from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
from jax.scipy.linalg import block_diag as jax_block_diag
from scipy.linalg import block_diag

from ...scene.types import SceneError
from ...staging import on_device
from ..block import LiquidBlock, host_block
from ..face.element import FaceModel, face_basis, face_invariants
from ..face.stack import face_scales
from ..nodal.model import build_liquid
from .reduction import tank_basis
from .term import ModalLiquid


@functools.lru_cache(maxsize=8)
def _face_basis(model: FaceModel, origin: tuple, n: int, static: bool):
    return face_basis(model, origin, n, static)


def face_tank_basis(model: FaceModel, origin, n: int, static: bool):
    """`face_basis` of a face-normal tank, computed once per model (the liquid block and the damping
    of the same scene take the same basis; FaceModel hashes by identity)."""
    return _face_basis(model, tuple(float(v) for v in origin), int(n), bool(static))


def face_sloshing(model: FaceModel, V, n_modes: int) -> np.ndarray:
    """The columns of V[:, :n_modes] (face_basis's modes) that are sloshing modes: most of their
    energy in the free surface (liquid/face/element.py face_modes' rule)."""
    Vm = V[:, :n_modes]
    total = np.einsum("fi,fi->i", Vm, model.stiffness @ Vm)
    surf = np.einsum("fi,fi->i", Vm, model.surface @ Vm)
    return np.flatnonzero(surf > 0.5 * np.where(total > 0, total, np.inf))


def reduce_liquid(models, concrete_models, origins, offsets, reductions, scales=None):
    """The reduced liquid of every tank (stacked), from the per-tank `NodalModel`s.

    `models` may hold traced values (then JAX arithmetic); `concrete_models` are the same tanks at
    the scene's values, from which the bases are computed (they are the `models` when concrete).
    `reductions` holds (modes, static_correction) per tank. Returns (ModalLiquid, (K_dt, K_tt) of
    the rotation penalty on the modal coordinates, or None). `scales`: per tank, None or the
    face-normal tank's (rho, rho c^2, rho g) over its model's (liquid/face/stack.py face_scales; traced
    values scale its blocks, the basis stays the scene's)."""
    scales = scales or [None] * len(models)
    traced = any(m.traced for m in models) or any(isinstance(v, jax.core.Tracer) for s in scales if s for v in s)
    xp = jnp if traced else np
    N = sum(int(m.n_nodes) for m in models)
    Us, Kr_blocks, Mr_blocks, Kdt_rows, row_scales = [], [], [], [], []
    S0, Q0, mass, Ktt = 0.0, 0.0, 0.0, xp.zeros((3, 3))
    U1s, Q1s, Q2_blocks = [], [], []
    rs, ms = [], []
    coupled = any(m.rotation_coupling is not None or isinstance(m, FaceModel) for m in models)
    for model, cmodel, origin, off, (n, static), fs in zip(models, concrete_models, origins, offsets, reductions,
                                                           scales):
        if isinstance(model, FaceModel):         # the face-normal element: invariants are its fields' integrals
            V, _, _, (Kdt_t, Ktt_t, kappa, k0) = face_tank_basis(model, origin, n, static)
            inv = face_invariants(model, V, origin)
            sr, sc, sg = fs if fs is not None else (1.0, 1.0, 1.0)
            m = V.shape[1]
            Kr_t = sc * (V.T @ (model.acoustic @ V)) + sg * (V.T @ (model.surface @ V))
            pen = np.zeros((m, m))
            pen[k0:, k0:] = kappa * np.eye(m - k0)               # the absolute-rotation penalty's own block
            Kr_t = 0.5 * (Kr_t + Kr_t.T) + sr * pen
            S0, Q0, mass = S0 + sr * inv["S0"], Q0 + sr * inv["Q0"], mass + sr * inv["mass"]
            U1s.append(sr * xp.asarray(inv["U1"]))
            Q1s.append(sr * xp.asarray(inv["Q1"]))
            Q2_blocks.append(sr * xp.asarray(inv["Q2"]))
            Mr_blocks.append(sr * xp.asarray(inv["Mr"]))
            Kr_blocks.append(xp.asarray(Kr_t))
            Kdt_rows.append(sr * xp.asarray(Kdt_t))
            Ktt = Ktt + sr * xp.asarray(Ktt_t)
            row_scales.append(1.0 / np.maximum(np.abs(inv["U"]).max(axis=(1, 2)), 1e-300))
            Us.append((off, inv["U"]))
            rs.append(xp.asarray(inv["r"]))
            ms.append(sr * xp.asarray(inv["m_nodes"]))
            continue
        basis = tank_basis(cmodel, origin, n, static)
        f = np.flatnonzero(np.asarray(model.free))
        Nt, m = int(model.n_nodes), basis.V.shape[1]
        Ut = np.zeros((m, 3 * Nt))
        Ut[:, f] = basis.V.T
        Ut = np.asarray(cmodel.to_global(Ut.reshape(m, Nt, 3)))     # shaped tanks: from the nodes' frames
        r = xp.asarray(model.nodes) + xp.asarray(origin)[None, :]
        Ms = model.mass
        mvec = xp.asarray(Ms.sum(axis=1)).reshape(-1)
        MU = Ms @ Ut.transpose(1, 0, 2).reshape(Nt, 3 * m)            # (Nt, 3m)
        MU = xp.asarray(MU).reshape(Nt, m, 3).transpose(1, 0, 2)       # (m, Nt, 3)
        Mr_ = xp.asarray(Ms @ r)                                        # (Nt, 3)
        S0 = S0 + mvec @ r
        Q0 = Q0 + r.T @ Mr_
        mass = mass + mvec.sum()
        U1s.append(xp.einsum("i,kia->ka", mvec, Ut))
        Q1s.append(xp.einsum("ia,kib->kab", Mr_, Ut))                  # T(r, U_k) = (Ms r)^T U_k
        Q2_blocks.append(xp.einsum("kia,lib->klab", Ut, MU))
        Mr_blocks.append(xp.einsum("kia,lia->kl", Ut, MU))
        Kff = model.stiffness
        if sp.issparse(Kff):
            Kr_t = basis.V.T @ (Kff.tocsr()[f][:, f] @ basis.V)
        else:
            Kr_t = basis.V.T @ xp.asarray(Kff)[np.ix_(f, f)] @ basis.V
        Kr_blocks.append(0.5 * (Kr_t + Kr_t.T))
        if coupled:
            if model.rotation_coupling is not None:
                Kdt_rows.append(basis.V.T @ xp.asarray(model.rotation_coupling)[f])
                Ktt = Ktt + xp.asarray(model.rotation_stiffness)
            else:
                Kdt_rows.append(xp.zeros((m, 3)))
        row_scales.append(1.0 / np.abs(basis.V).max(axis=0))
        Us.append((off, Ut))
        rs.append(r)
        ms.append(mvec)
    mtot = sum(U.shape[0] for _, U in Us)
    U = np.zeros((mtot, N, 3))
    Q2 = xp.zeros((mtot, mtot, 3, 3))
    k = 0
    for (off, Ut), Q2t in zip(Us, Q2_blocks):
        mt, Nt = Ut.shape[0], Ut.shape[1]
        U[k:k + mt, off:off + Nt] = Ut
        if traced:
            Q2 = Q2.at[k:k + mt, k:k + mt].set(Q2t)
        else:
            Q2[k:k + mt, k:k + mt] = Q2t
        k += mt
    block_diag_ = jax_block_diag if traced else block_diag
    dev = on_device          # NumPy results onto the device without a compile per shape (jnp.asarray's)
    liquid = ModalLiquid(
        r=dev(xp.concatenate(rs)), m_nodes=dev(xp.concatenate(ms)), U=dev(U),
        mass=dev(mass), S0=dev(S0), U1=dev(xp.concatenate(U1s)), Q0=dev(Q0),
        Q1=dev(xp.concatenate(Q1s)), Q2=dev(Q2), Mr=dev(block_diag_(*Mr_blocks)),
        Kr=dev(block_diag_(*Kr_blocks)), row_scale=dev(np.concatenate(row_scales)), n_nodes=N)
    penalty = (dev(xp.concatenate(Kdt_rows)), dev(Ktt)) if coupled else None
    return liquid, penalty


def reduced_block(scene, tanks, models, params, g) -> LiquidBlock:
    """Every tank's liquid on its modal basis (reduction.py); the bases come from the scene's values,
    and a face-normal tank's blocks scale to traced density, sound speed and gravity (face_scales)."""
    for i, t in enumerate(tanks):
        if not t.form.reduced:
            raise SceneError(f"tanks[{i}].reduction", "reduce every tank or none: another tank has a "
                                                       "[tanks.reduction] table and this one has not")
    scales = [face_scales(scene, t, params, g) if isinstance(m, FaceModel) else None for t, m in zip(tanks, models)]
    concrete = []
    for t, m in zip(tanks, models):
        if getattr(m, "traced", False) or (isinstance(g, jax.core.Tracer) and not isinstance(m, FaceModel)):
            m = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed,
                             scene.environment.gravity, element=t.fluid.element, geometry=t.geometry)
        concrete.append(m)
    offsets, blocks, offset = [], [], 0
    for t, m in zip(tanks, models):
        offsets.append(offset)
        blocks.append(host_block(t, m, offset))
        offset += m.n_nodes
    liquid, penalty = reduce_liquid(models, concrete, [t.origin for t in tanks], offsets,
                                    [(t.reduction.modes, t.reduction.static_correction) for t in tanks], scales)
    return LiquidBlock(liquid, tuple(blocks), penalty)
