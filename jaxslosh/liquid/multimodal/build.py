"""The multimodal liquid of a scene (liquid/multimodal/liquid.py): one ModalTank per tank, its probes (the
free-surface elevation at their point), its damping and the sample points of the surface that the
run's validity watch reads."""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax.numpy as jnp
import numpy as np

from ..block import LiquidBlock
from ..modal_damping import ModalDamping, TankDamping
from .liquid import MultimodalLiquid
from .term import modal_tank
from .expansion import third_order
from ...scene.types import Scene, SceneError
from .modes import modal_modes
from .build3d import probe_row, sample_points, tank_3d, three_dimensional

#: surface samples per tank for the validity watch (walls included, where the extremes are)
SAMPLES = 33


def multimodal_scene(scene: Scene) -> bool:
    return bool(scene.tanks) and scene.tanks[0].form.multimodal


def multimodal_block(scene: Scene, params: Optional[dict], gravity) -> LiquidBlock:
    """The multimodal liquid's block (liquid/forms.py block_form): the liquid, the surface meshes a
    result keeps, the surface samples the validity watch reads, the probes' rows and the damping."""
    liquid = build_multimodal(scene, params, gravity)
    return LiquidBlock(liquid, kept=surface_meshes(scene), tops=surfaces(scene), probe_rows=probe_modal(scene, liquid),
                       damping=multimodal_damping(scene, params, liquid))


def outline_multimodal(gravity) -> LiquidBlock:
    """`multimodal_block`'s liquid without its arrays, for `jaxslosh check` (only its lines are read)."""
    return LiquidBlock(MultimodalLiquid(tanks=(), sizes=(), samples=None, gravity=gravity))


def build_multimodal(scene: Scene, params: Optional[dict], gravity) -> MultimodalLiquid:
    params = params or {}
    tanks, rows = [], []
    for t in scene.tanks:
        P = lambda k, d: params.get(f"tanks.{t.name}.{k}", d)  # noqa: E731
        if three_dimensional(t):         # waves across the whole base (liquid/multimodal/tank3d.py)
            tanks.append(tank_3d(t, P("fill_depth", t.fill_depth), P("fluid.density", t.fluid.density)))
            rows.append(tanks[-1].surface_rows(*sample_points(t, SAMPLES)))
            continue
        tanks.append(modal_tank(t.size[0], t.size[1], P("fill_depth", t.fill_depth), P("fluid.density", t.fluid.density),
                                t.origin, t.modes, D=t.size[2]))
        rows.append(np.cos(np.outer(np.linspace(0.0, t.size[0], SAMPLES), np.arange(1, t.modes + 1) * np.pi / t.size[0])))
    # the third-order system's coefficients are the exact tank's derivatives at rest
    tanks = [third_order(mt) if t.form.third_order else mt for t, mt in zip(scene.tanks, tanks)]
    sizes = tuple(r.shape[1] for r in rows)
    samples = np.zeros((SAMPLES * len(tanks), sum(sizes)))
    off = 0
    for i, r in enumerate(rows):
        samples[i * SAMPLES:(i + 1) * SAMPLES, off:off + r.shape[1]] = r
        off += r.shape[1]
    return MultimodalLiquid(tanks=tuple(tanks), sizes=sizes,
                            samples=jnp.asarray(samples), gravity=jnp.asarray(gravity, dtype=float),
                            fields=jnp.asarray(surface_fields(scene, tanks, sizes)))


#: elements of a multimodal tank's surface mesh along its base's longest side (at least 4 per
#: wavelength of its shortest mode)
SURFACE_CELLS = 24


class ModalSurface(NamedTuple):
    """A multimodal tank as a result keeps it (its `tanks/NAME` fields, which `plot --surface` draws
    and `export --paraview` writes): one layer of hexahedra from the bottom to the fill depth over
    its base, the top nodes displaced by the free surface's elevation reconstructed from the modal
    coordinates, the bottom ones at rest (the modes say nothing of the particles' paths)."""
    name: str
    nodes: np.ndarray             # (N, 3) tank-local, at rest
    elements: np.ndarray          # (E, 8) hex8, the top face the last four corners
    node_offset: int
    model: object = None          # no finite-element model (analysis/coupled.py reads a model's parts)


def _surface_counts(t) -> tuple:
    if not three_dimensional(t):          # waves along x: one element across
        return (max(SURFACE_CELLS, 4 * t.modes), 1, 1)
    top = max(max(m[:2]) for m in modal_modes(t))
    n = max(SURFACE_CELLS, 4 * top)
    L, B = t.size[0], t.size[1]
    return (max(2, round(n * L / max(L, B))), max(2, round(n * B / max(L, B))), 1)


def surface_meshes(scene: Scene) -> tuple:
    """Per multimodal tank, its surface mesh (ModalSurface), the nodes numbered on across tanks."""
    out, off = [], 0
    for t in scene.tanks:
        m = t.geometry.mesh(t.fill_depth, _surface_counts(t))
        out.append(ModalSurface(t.name, np.asarray(m.nodes), np.asarray(m.elements), off))
        off += m.nodes.shape[0]
    return tuple(out)


def surface_fields(scene: Scene, tanks, sizes) -> np.ndarray:
    """(N, nf): each surface mesh node's vertical displacement per modal coordinate: the elevation's
    rows at its (x, y), times z / fill depth (1 on the free surface, 0 on the bottom)."""
    meshes = surface_meshes(scene)
    F = np.zeros((sum(m.nodes.shape[0] for m in meshes), int(sum(sizes))))
    off = 0
    for t, mt, n, m in zip(scene.tanks, tanks, sizes, meshes):
        x, y, z = m.nodes.T
        rows = (mt.surface_rows(x, y) if three_dimensional(t)
                else np.cos(np.outer(x, np.arange(1, n + 1) * np.pi / t.size[0])))
        F[m.node_offset:m.node_offset + len(x), off:off + n] = (z / t.fill_depth)[:, None] * rows
        off += n
    return F


def surfaces(scene: Scene) -> tuple:
    """Per tank, its rows of the liquid's surface samples."""
    return tuple(jnp.arange(i * SAMPLES, (i + 1) * SAMPLES) for i in range(len(scene.tanks)))


def probe_modal(scene: Scene, liquid: MultimodalLiquid) -> jnp.ndarray:
    """(P, nf, 3): a probe at its tank's fill depth rises and falls with the free surface there; any other
    follows the tank (the multimodal method resolves the surface, not the particles)."""
    offsets, off = {}, 0
    for t, n in zip(scene.tanks, liquid.sizes):
        offsets[t.name] = off
        off += n
    out = np.zeros((len(scene.probes), off, 3))
    for p_i, p in enumerate(scene.probes):
        if p.tank is None:
            continue
        i, t = next((i, t) for i, t in enumerate(scene.tanks) if t.name == p.tank)
        if abs(p.point[2] - t.fill_depth) <= 1e-6 * max(t.size):
            n = liquid.sizes[i]
            if three_dimensional(t):
                row = probe_row(liquid.tanks[i], p.point)
            else:
                row = np.cos(np.arange(1, n + 1) * np.pi / t.size[0] * p.point[0])
            out[p_i, offsets[t.name]:offsets[t.name] + n, 2] = row
    return jnp.asarray(out)


def multimodal_damping(scene: Scene, params: Optional[dict], liquid: MultimodalLiquid) -> tuple:
    """`[tanks.damping] ratio` on each modal coordinate: 2 zeta_n omega_n times its modal mass (the
    damping ratio of each linear mode), ModalDamping's C = B diag(c) B^T with B = diag(sqrt(mass));
    (None, ()) without a damped tank. With it, TankDamping per damped tank (`check`'s lines: its
    linear modes' frequencies and ratios), as assemble/damping.py build_damping gives them."""
    if not any(t.damping is not None for t in scene.tanks):
        return None, ()
    params = params or {}
    Bs, cs, table = [], [], []
    for i, (t, mt) in enumerate(zip(scene.tanks, liquid.tanks)):
        Bs.append(jnp.sqrt(mt.modal_mass()))
        n = mt.n
        if t.damping is None:
            cs.append(jnp.zeros(n))
            continue
        ratio = params.get(f"tanks.{t.name}.damping.ratio", t.damping.ratio)
        if np.ndim(ratio) == 1:
            if len(ratio) > n:
                raise SceneError(f"tanks[{i}].damping.ratio", f"gives {len(ratio)} damping ratios, but the "
                                                              f"multimodal tank has {n} modes")
            zeta = jnp.concatenate([jnp.asarray(ratio, dtype=float), jnp.zeros(n - len(ratio))])
        else:
            zeta = jnp.full(n, 1.0) * jnp.asarray(ratio, dtype=float)
        omega = mt.omega_linear(liquid.gravity)
        cs.append(2.0 * zeta * omega)
        table.append(TankDamping(t.name, omega, zeta))
    return ModalDamping(B=jnp.diag(jnp.concatenate(Bs)), c=jnp.concatenate(cs)), tuple(table)
