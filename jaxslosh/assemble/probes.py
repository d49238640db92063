"""Probes: material points recorded in the result (docs/guide/tanks-and-shapes.md), as interpolation weights over
the liquid's nodes (or a structure's), computed once."""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np

from ..fem.mesh import HEX_CORNERS
from ..scene.types import Scene


class Probes(NamedTuple):
    names: tuple
    points: jnp.ndarray    # (P, 3) undeformed positions in the vessel frame
    weights: jnp.ndarray   # (P, N) interpolation of the liquid displacement (zero rows: the probe follows the tank)
    on_structures: tuple = ()   # StructureProbes per structure that has probes
    modal: Optional[jnp.ndarray] = None   # (P, m, 3) weights @ basis, with a reduced liquid: probes from eta
    on_bodies: tuple = ()       # BodyProbes per body whose tanks have probes


class StructureProbes(NamedTuple):
    """Probes on structure `index`: rows `rows` of the probe table, points `r` in its frame (from its
    COG) and trilinear weights `W` (k, N_s) over its nodes."""
    index: int
    rows: np.ndarray
    r: jnp.ndarray
    W: jnp.ndarray


class BodyProbes(NamedTuple):
    """Probes in the tanks of body `index` (of [[bodies]]): rows `rows` of the probe table, points `r`
    in its frame (from its COG) and their weights on its tanks' modal coordinates `modal` (k, m, 3),
    which are the bodies' tanks' unknowns offset ... offset + n."""
    index: int
    rows: np.ndarray
    r: jnp.ndarray
    modal: jnp.ndarray
    offset: int
    n: int


def tank_weights(p, t, b) -> np.ndarray:
    """The trilinear weights (N_t,) of probe `p` in tank `t` over its tank block `b`'s nodes (liquid/block.py
    TankBlock): a box's rule (probe_weights) or a shaped tank's (mapped_weights)."""
    if getattr(b.model, "geometry", None) is not None:
        return mapped_weights(np.asarray(p.point), t.fill_depth, b.nodes, b.elements)
    return probe_weights(np.asarray(p.point), t.size, t.fill_depth, b.nodes, b.elements)


def body_modal(bt, tank, found) -> jnp.ndarray:
    """(k, m, 3): the weights of the probes `found` ((t, p) per probe, in the scene's order) in the
    tanks of one body on its liquid `tank`'s coordinates, by the vessel's rule: their nodal
    interpolation over the tank blocks the liquid's builder made (`bt.block`, none for a liquid
    without a mesh), turned into modal weights by the block (LiquidBlock.probe_modal: a reduced
    liquid's basis, or the rows a model's builder made from the probes itself); where the liquid
    reads the nodal field (full order), its probe displacement, linear in d."""
    W = np.zeros((len(found), tank.n_nodes))
    meshes = {b.name: b for b in bt.block.tanks}
    for k, (t, p) in enumerate(found):
        b = meshes.get(t.name)
        if b is not None:
            W[k, b.node_offset:b.node_offset + b.nodes.shape[0]] = tank_weights(p, t, b)
    modal = bt.block.probe_modal(jnp.asarray(W))
    if modal is None:        # (k, 3, nf) -> (k, nf, 3)
        modal = jax.jacfwd(lambda d: tank.probe_displacements(jnp.asarray(W), None, d))(jnp.zeros(tank.nf))
        modal = jnp.swapaxes(modal, 1, 2)
    return modal


def build_probes(scene: Scene, tanks, liquid, structures=(), vstructs=(), body_tanks=(), bodies=None) -> Probes:
    """The probes' weights; `body_tanks` (assemble/bodies.BodyTanks) and `bodies` (the Bodies term):
    the tanks the bodies carry, whose probes follow their body."""
    names, pts, W = [], [], []
    N = liquid.n_nodes
    by_name = {b.name: b for b in tanks}
    on_struct, on_body = {}, {}
    carried = {t.name: (s, t) for s, body in enumerate(scene.bodies) for t in body.tanks}
    for i, p in enumerate(scene.probes):
        w = np.zeros(N)
        if p.tank is not None and p.tank in carried:      # in a body's tank: it follows that body
            s, t = carried[p.tank]
            r = np.asarray(t.origin) + np.asarray(p.point)
            pts.append(r)
            on_body.setdefault(s, []).append((i, r, t, p))
        elif p.tank is not None:
            t = scene.tank(p.tank)
            pts.append(np.asarray(t.origin) + np.asarray(p.point))
            b = by_name.get(t.name)
            if b is not None:
                w[b.node_offset:b.node_offset + b.nodes.shape[0]] = tank_weights(p, t, b)
        elif scene.structure(p.structure).frame == "vessel":     # in the vessel-frame block, like a liquid point
            st = scene.structure(p.structure)
            pts.append(np.asarray(st.origin) + np.asarray(p.point))
            vb = next(b for b in vstructs if b.name == st.name)
            w[vb.node_offset:vb.node_offset + vb.nodes.shape[0]] = block_weights(np.asarray(p.point), vb.nodes,
                                                                                 vb.elements)
        else:
            st = scene.structure(p.structure)
            pts.append(np.asarray(st.origin) + np.asarray(p.point))
            blk = next(b for b in structures if b.name == st.name)
            on_struct.setdefault(blk.index, []).append((i, np.asarray(p.point) - blk.model.cog,
                                                        block_weights(np.asarray(p.point), blk.model.nodes,
                                                                      blk.model.elements)))
        names.append(p.name)
        W.append(w)
    sp = tuple(StructureProbes(k, np.array([e[0] for e in v]), jnp.asarray(np.array([e[1] for e in v])),
                               jnp.asarray(np.array([e[2] for e in v]))) for k, v in sorted(on_struct.items()))
    bp = tuple(_body_probes(s, v, body_tanks, bodies) for s, v in sorted(on_body.items()))
    return Probes(tuple(names), jnp.asarray(np.array(pts).reshape(-1, 3)),
                  jnp.asarray(np.array(W, dtype=float).reshape(len(W), N)), sp, on_bodies=bp)


def _body_probes(s, found, body_tanks, bodies) -> BodyProbes:
    """The probes `found` ((row, point, tank, probe) each) in the tanks of body `s`; without its
    liquid built ([effects] liquid = false) they follow the body."""
    bt = next((x for x in body_tanks if x.body == s), None)
    rows, r = np.array([e[0] for e in found]), jnp.asarray(np.array([e[1] for e in found]))
    if bt is None:
        return BodyProbes(s, rows, r, jnp.zeros((len(found), 0, 3)), 0, 0)
    tank = bodies.bodies[s].tank
    return BodyProbes(s, rows, r, body_modal(bt, tank, [(e[2], e[3]) for e in found]), bt.offset, tank.nf)


def block_weights(point, nodes, elements, tol=1e-9):
    """Trilinear weights (N,) of a point of a meshed block (any point inside or on it)."""
    scale = np.ptp(nodes, axis=0).max()
    w = np.zeros(nodes.shape[0])
    for el in elements:
        X = nodes[el]
        lo, hi = X.min(axis=0), X.max(axis=0)
        if np.all(point >= lo - tol * scale) and np.all(point <= hi + tol * scale):
            xi = np.clip((point - lo) / (hi - lo), 0.0, 1.0)
            for k, node in enumerate(el):
                corner = (X[k] - lo) / (hi - lo)
                w[node] = np.prod(np.where(corner > 0.5, xi, 1.0 - xi))
            return w
    return w


def probe_weights(point, size, depth, nodes, elements, eps=1e-9):
    """docs/guide/tanks-and-shapes.md: a probe at the fill depth follows the free surface (even at a wall), a probe
    inside the liquid follows the liquid particle, a probe on the bottom or on a wall below the
    surface (or in the air above the liquid) follows the tank. Between nodes, the hexahedron's
    trilinear shape functions interpolate."""
    x, y, z = point
    a, b = size[0], size[1]
    scale = max(a, b, depth)
    tol = eps * scale + 1e-12
    w = np.zeros(nodes.shape[0])
    at_surface = abs(z - depth) <= 1e-6 * scale
    if z > depth and not at_surface:
        return w
    on_wall = min(x, a - x, y, b - y, z) <= tol
    if on_wall and not at_surface:
        return w
    for el in elements:
        X = nodes[el]
        lo, hi = X.min(axis=0), X.max(axis=0)
        p = np.array([x, y, min(z, depth)])
        if np.all(p >= lo - tol) and np.all(p <= hi + tol):
            xi = np.clip((p - lo) / (hi - lo), 0.0, 1.0)
            for k, node in enumerate(el):
                corner = (X[k] - lo) / (hi - lo)     # 0 or 1 per axis
                w[node] = np.prod(np.where(corner > 0.5, xi, 1.0 - xi))
            return w
    return w


def mapped_weights(point, depth, nodes, elements, tol=1e-9):
    """`probe_weights` in a tank of another shape (jaxslosh/geometry): the trilinear weights of the point in
    the hexahedron that holds it (its reference coordinates by Newton's method), a point at the fill
    depth on the free surface; outside the liquid (in the air, in a wall): zeros, the probe follows
    the tank. (Unlike the box, a point on a wall below the surface follows the liquid there.)"""
    scale = float(np.ptp(nodes, axis=0).max())
    p = np.array(point, dtype=float)
    if p[2] > depth + 1e-6 * scale:
        return np.zeros(nodes.shape[0])
    p[2] = min(p[2], depth)
    C = HEX_CORNERS
    for el in elements:
        X = nodes[el]
        if np.any(p < X.min(axis=0) - tol * scale) or np.any(p > X.max(axis=0) + tol * scale):
            continue
        xi = np.zeros(3)
        for _ in range(30):
            N = np.prod(1 + C * xi, axis=1) / 8.0
            dN = np.stack([C[:, k] * np.prod(np.where(np.arange(3) == k, 1.0, 1 + C * xi), axis=1)
                           for k in range(3)], axis=1) / 8.0
            r = N @ X - p
            J = X.T @ dN
            if abs(np.linalg.det(J)) < 1e-300:
                break
            step = np.linalg.solve(J, r)
            xi = np.clip(xi - step, -1.5, 1.5)
            if np.abs(step).max() < 1e-13:
                break
        if np.all(np.abs(xi) <= 1 + 1e-7):
            w = np.zeros(nodes.shape[0])
            np.add.at(w, el, np.prod(1 + C * np.clip(xi, -1, 1), axis=1) / 8.0)
            return w
    return np.zeros(nodes.shape[0])
