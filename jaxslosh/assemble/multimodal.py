"""The multimodal liquid of a scene (physics/multimodal.py): one ModalTank per tank, its probes (the
free-surface elevation at their point), its damping and the sample points of the surface that the
run's validity watch reads."""
from __future__ import annotations

from typing import Optional

import jax.numpy as jnp
import numpy as np

from ..physics.damping import ModalDamping
from ..physics.multimodal import MultimodalLiquid, modal_tank
from ..scene.types import Scene, SceneError

#: surface samples per tank for the validity watch (walls included, where the extremes are)
SAMPLES = 33


def multimodal_scene(scene: Scene) -> bool:
    return bool(scene.tanks) and scene.tanks[0].model == "multimodal"


def build_multimodal(scene: Scene, params: Optional[dict], gravity) -> MultimodalLiquid:
    params = params or {}
    tanks, rows = [], []
    for t in scene.tanks:
        P = lambda k, d: params.get(f"tanks.{t.name}.{k}", d)  # noqa: E731
        tanks.append(modal_tank(t.size[0], t.size[1], P("fill_depth", t.fill_depth), P("fluid.density", t.fluid.density),
                                t.origin, t.modes, D=t.size[2]))
        rows.append(np.cos(np.outer(np.linspace(0.0, t.size[0], SAMPLES), np.arange(1, t.modes + 1) * np.pi / t.size[0])))
    nf = sum(t.modes for t in scene.tanks)
    samples = np.zeros((SAMPLES * len(tanks), nf))
    off = 0
    for i, (t, r) in enumerate(zip(scene.tanks, rows)):
        samples[i * SAMPLES:(i + 1) * SAMPLES, off:off + t.modes] = r
        off += t.modes
    return MultimodalLiquid(tanks=tuple(tanks), sizes=tuple(t.modes for t in scene.tanks),
                            samples=jnp.asarray(samples), gravity=jnp.asarray(gravity, dtype=float))


def surfaces(scene: Scene) -> tuple:
    """Per tank, its rows of the liquid's surface samples."""
    return tuple(jnp.arange(i * SAMPLES, (i + 1) * SAMPLES) for i in range(len(scene.tanks)))


def probe_modal(scene: Scene) -> jnp.ndarray:
    """(P, nf, 3): a probe at its tank's fill depth rises and falls with the free surface there; any other
    follows the tank (the multimodal method resolves the surface, not the particles)."""
    offsets, off = {}, 0
    for t in scene.tanks:
        offsets[t.name] = off
        off += t.modes
    out = np.zeros((len(scene.probes), off, 3))
    for p_i, p in enumerate(scene.probes):
        if p.tank is None:
            continue
        t = scene.tank(p.tank)
        if abs(p.point[2] - t.fill_depth) <= 1e-6 * max(t.size):
            k = np.arange(1, t.modes + 1) * np.pi / t.size[0]
            out[p_i, offsets[t.name]:offsets[t.name] + t.modes, 2] = np.cos(k * p.point[0])
    return jnp.asarray(out)


def multimodal_damping(scene: Scene, params: Optional[dict], liquid: MultimodalLiquid) -> Optional[ModalDamping]:
    """`[tanks.damping] ratio` on each modal coordinate: 2 zeta_n omega_n times its modal mass (the
    damping ratio of each linear mode), ModalDamping's C = B diag(c) B^T with B = diag(sqrt(mass))."""
    if not any(t.damping is not None for t in scene.tanks):
        return None
    params = params or {}
    Bs, cs = [], []
    for i, (t, mt) in enumerate(zip(scene.tanks, liquid.tanks)):
        Bs.append(jnp.sqrt(mt.modal_mass()))
        if t.damping is None:
            cs.append(jnp.zeros(t.modes))
            continue
        ratio = params.get(f"tanks.{t.name}.damping.ratio", t.damping.ratio)
        if np.ndim(ratio) == 1:
            if len(ratio) > t.modes:
                raise SceneError(f"tanks[{i}].damping.ratio", f"gives {len(ratio)} damping ratios, but the "
                                                              f"multimodal tank has {t.modes} modes")
            zeta = jnp.concatenate([jnp.asarray(ratio, dtype=float), jnp.zeros(t.modes - len(ratio))])
        else:
            zeta = jnp.full(t.modes, 1.0) * jnp.asarray(ratio, dtype=float)
        cs.append(2.0 * zeta * mt.omega_linear(liquid.gravity))
    return ModalDamping(B=jnp.diag(jnp.concatenate(Bs)), c=jnp.concatenate(cs))
