"""The liquid's modal damping of a scene (`[tanks.damping]`, physics/damping.py) from its tanks'
sloshing modes (fem/damping.py): full order on the stacked free dofs, or on the modal basis of a
reduced liquid (assemble/reduced.py).

The modes come from the scene's values (as a reduced basis does): a traced fill depth or density
leaves them as they are, and a traced `tanks.<name>.damping.ratio` scales the damping of each.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp

from ..fem.damping import SPARSE_SEARCH, boundary_layer_ratios, sloshing_modes, sloshing_share
from ..fem.liquid import build_liquid
from ..fem.liquid_rt import FaceLiquid, face_modes
from ..fem.modes import free_matrices
from ..fem.reduction import tank_basis
from ..physics.damping import ModalDamping
from ..scene.fields import show
from ..scene.types import Scene, SceneError
from .liquid import build_liquid_block
from .reduced import face_sloshing, face_tank_basis


class TankDamping(NamedTuple):
    """One tank's damped modes: their frequencies (rad/s) and ratios (the ratio part may be traced)."""
    name: str
    omega: np.ndarray
    zeta: object


def build_damping(scene: Scene, params: Optional[dict], block) -> tuple[Optional[ModalDamping], tuple]:
    """(ModalDamping or None, TankDamping per damped tank) for the liquid block `block`
    (assemble/liquid.py LiquidBlock); None where no tank has a `[tanks.damping]` table."""
    tanks = scene.tanks
    if not any(t.damping is not None for t in tanks) or not block.liquid.nf or not block.tanks:
        return None, ()
    if block.vstructs or any(t.wall_spec is not None for t in tanks):
        i = next(i for i, t in enumerate(tanks) if t.damping is not None)
        raise SceneError(f"tanks[{i}].damping", "is not available with elastic tank walls or structures in the "
                                                "vessel's frame (their modes are not the liquid's alone)")
    params = params or {}
    reduced = tanks[0].reduction is not None
    parts, cs, table, offset = [], [], [], 0
    for i, (t, tb) in enumerate(zip(tanks, block.tanks)):
        model = tb.model
        if isinstance(model, FaceLiquid) and not reduced:      # full order: its lowest modes, on the free faces
            fm = face_modes(model, SPARSE_SEARCH)
            slosh = np.array([k == "sloshing" for k in fm.kind], dtype=bool)
            f = np.flatnonzero(model.free)
            omega, Phi = fm.omega[slosh], fm.fluxes[slosh].T                # Phi on all faces (wall integrals)
            n_t = f.size
            Bt = model.mass[f][:, f] @ Phi[f]
            where = f"the {SPARSE_SEARCH} lowest modes searched on this mesh hold {omega.size}"
        elif isinstance(model, FaceLiquid):      # on its modal basis
            V, omega_b, n_modes, (_, _, _, k0) = face_tank_basis(model, t.origin, t.reduction.modes,
                                                                 t.reduction.static_correction)
            n_t = V.shape[1]
            slosh = face_sloshing(model, V, n_modes)
            omega, Phi = omega_b[slosh], V[:, slosh]
            Bt = np.eye(n_t)[:, slosh]
            where = f"the reduced basis holds {slosh.size} ([tanks.reduction] modes = {t.reduction.modes})"
        elif model.traced:
            model = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed,
                                 scene.environment.gravity, element=t.fluid.element, geometry=t.geometry)
        if isinstance(model, FaceLiquid):
            pass        # done above
        elif reduced:
            basis = tank_basis(model, t.origin, t.reduction.modes, t.reduction.static_correction)
            n_t = basis.V.shape[1]
            slosh = np.flatnonzero(sloshing_share(model, basis.V[:, :basis.n_modes]))
            omega, Phi = basis.omega[slosh], basis.V[:, slosh]
            Bt = np.eye(n_t)[:, slosh]                  # V^T M Phi: the basis holds these modes as they are
            where = f"the reduced basis holds {slosh.size} ([tanks.reduction] modes = {t.reduction.modes})"
        else:
            omega, Phi = sloshing_modes(model)
            n_t = Phi.shape[0]
            Bt = free_matrices(model)[1] @ Phi
            Bt = np.asarray(Bt.todense() if sp.issparse(Bt) else Bt)
            if sp.issparse(model.stiffness):     # a large mesh: only its lowest modes are searched
                searched = min(n_t - 1, SPARSE_SEARCH)
                where = f"the {searched} lowest modes searched on this mesh hold {omega.size}"
            else:
                where = f"the mesh carries {omega.size}"
        if t.damping is None:
            offset += n_t
            continue
        ratio = params.get(f"tanks.{t.name}.damping.ratio", t.damping.ratio)
        listed = np.ndim(ratio) == 1
        L = len(ratio) if listed else 0
        if L > omega.size:
            raise SceneError(f"tanks[{i}].damping.ratio", f"gives {L} damping ratios, but {where} sloshing modes")
        k = L if listed and t.damping.viscosity == 0.0 else omega.size
        omega, Phi, Bt = omega[:k], Phi[:, :k], Bt[:, :k]
        zeta = jnp.concatenate([jnp.asarray(ratio, dtype=float), jnp.zeros(k - L)]) if listed \
            else jnp.full(k, 1.0) * jnp.asarray(ratio, dtype=float)
        zeta = zeta + boundary_layer_ratios(model, omega, Phi, t.damping.viscosity)
        parts.append((offset, Bt))
        cs.append(2.0 * zeta * omega)
        table.append(TankDamping(t.name, omega, zeta))
        offset += n_t
    B = np.zeros((offset, sum(b.shape[1] for _, b in parts)))
    col = 0
    for off, Bt in parts:
        B[off:off + Bt.shape[0], col:col + Bt.shape[1]] = Bt
        col += Bt.shape[1]
    if B.shape[0] != block.liquid.nf:
        raise AssertionError(f"damping rows {B.shape[0]} != liquid unknowns {block.liquid.nf}")
    return ModalDamping(B=jnp.asarray(B), c=jnp.concatenate(cs)), tuple(table)


def describe_damping(scene: Scene) -> list[str]:
    """`jaxslosh check`'s lines: each damped tank's sloshing modes, frequency and damping ratio
    (SceneError where the table does not fit the mesh, as a run would raise)."""
    if not any(t.damping is not None for t in scene.tanks) or not scene.effects.liquid:
        return []
    block = build_liquid_block(scene, None, scene.environment.gravity)
    lines = []
    for d in build_damping(scene, None, block)[1]:
        t = next(x for x in scene.tanks if x.name == d.name)
        zeta = np.asarray(d.zeta)
        shown = ", ".join(f"{w:.4g} rad/s {z:.4g}" for w, z in zip(d.omega[:12], zeta[:12]))
        more = f", ... ({len(zeta)} modes)" if len(zeta) > 12 else ""
        given = f"ratio {show(list(t.damping.ratio) if isinstance(t.damping.ratio, tuple) else t.damping.ratio)}"
        if t.damping.viscosity:
            given += f", viscosity {t.damping.viscosity:g} m^2/s"
        lines.append(f"damping of tank {d.name!r} ({given}), per sloshing mode: {shown}{more}")
    return lines
