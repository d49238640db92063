"""The liquid's modal damping of a scene (`[tanks.damping]`, liquid/modal_damping.py) from its tanks'
sloshing modes (liquid/damping.py): full order on the stacked free dofs, or on the modal basis of a
reduced liquid (liquid/modal/build.py).

The modes come from the scene's values (as a reduced basis does): a traced fill depth or density
leaves them as they are, and a traced `tanks.<name>.damping.ratio` scales the damping of each.
"""
from __future__ import annotations

from typing import Optional

import jax
import jax.numpy as jnp
import numpy as np

from ..liquid.damping import boundary_layer_ratios, sloshing_basis
from ..liquid.modal_damping import ModalDamping, TankDamping
from ..scene.fields import show
from ..scene.types import Scene, SceneError
from ..staging import on_device
from .liquid import build_liquid_block


def build_damping(scene: Scene, params: Optional[dict], block) -> tuple[Optional[ModalDamping], tuple]:
    """(ModalDamping or None, TankDamping per damped tank) for the liquid block `block`
    (liquid/block.py LiquidBlock); None where no tank has a `[tanks.damping]` table."""
    tanks = scene.tanks
    if block.damping is not None:      # made with the block by its model's builder (the multimodal one)
        return block.damping
    if not any(t.damping is not None for t in tanks) or not block.liquid.nf or not block.tanks:
        return None, ()
    if block.vstructs or not all(t.form.dampable for t in tanks):
        i = next(i for i, t in enumerate(tanks) if t.damping is not None)
        raise SceneError(f"tanks[{i}].damping", "is not available with elastic tank walls or structures in the "
                                                "vessel's frame (their modes are not the liquid's alone)")
    params = params or {}
    parts, cs, table, offset = [], [], [], 0
    for i, (t, tb) in enumerate(zip(tanks, block.tanks)):
        model, n_t, omega, Phi, Bt, where = sloshing_basis(tb.model, t, scene.environment.gravity)
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
        # NumPy for the scene's own ratios (op by op in JAX each line compiled a tiny program)
        xp = jnp if any(isinstance(v, jax.core.Tracer) for v in jax.tree_util.tree_leaves(ratio)) else np
        zeta = xp.concatenate([xp.asarray(ratio, dtype=float), xp.zeros(k - L)]) if listed \
            else xp.full(k, 1.0) * xp.asarray(ratio, dtype=float)
        zeta = zeta + boundary_layer_ratios(model, omega, Phi, t.damping.viscosity)
        parts.append((offset, Bt))
        cs.append(2.0 * zeta * omega)
        table.append(TankDamping(t.name, omega, on_device(zeta)))
        offset += n_t
    B = np.zeros((offset, sum(b.shape[1] for _, b in parts)))
    col = 0
    for off, Bt in parts:
        B[off:off + Bt.shape[0], col:col + Bt.shape[1]] = Bt
        col += Bt.shape[1]
    if B.shape[0] != block.liquid.nf:
        raise AssertionError(f"damping rows {B.shape[0]} != liquid unknowns {block.liquid.nf}")
    c = jnp.concatenate(cs) if any(isinstance(x, jax.core.Tracer) for x in cs) else on_device(np.concatenate(cs))
    return ModalDamping(B=on_device(B), c=c), tuple(table)


def describe_damping(scene: Scene) -> list[str]:
    """`jaxslosh check`'s lines: each damped tank's sloshing modes, frequency and damping ratio
    (SceneError where the table does not fit the mesh, as a run would raise)."""
    if not any(t.damping is not None for t in scene.tanks) or not scene.effects.liquid:
        return []
    block = build_liquid_block(scene, None, scene.environment.gravity)
    lines = []
    for d in build_damping(scene, None, block)[1]:
        t = next(x for x in scene.tanks if x.name == d.name)
        omega, zeta = np.asarray(d.omega), np.asarray(d.zeta)
        shown = ", ".join(f"{w:.4g} rad/s {z:.4g}" for w, z in zip(omega[:12], zeta[:12]))
        more = f", ... ({len(zeta)} modes)" if len(zeta) > 12 else ""
        given = f"ratio {show(list(t.damping.ratio) if isinstance(t.damping.ratio, tuple) else t.damping.ratio)}"
        if t.damping.viscosity:
            given += f", viscosity {t.damping.viscosity:g} m^2/s"
        lines.append(f"damping of tank {d.name!r} ({given}), per sloshing mode: {shown}{more}")
    return lines
