"""The nodal liquid's block (term.py `NodalLiquid`) of a scene's tanks from their element models
(model.py): stacked dense, sparse on large meshes (sparse.py), or extended by elastic walls and
structures in the vessel's frame (liquid/walls.py)."""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
from jax.scipy.linalg import block_diag as jax_block_diag
from scipy.linalg import block_diag

from ...scene.types import SceneError
from ..block import LiquidBlock, TankBlock, VesselFrameStructure, host_block, rigid_part, slots
from ..walls import build_tank_with_walls
from .model import build_liquid, surface_bending_scale
from .sparse import host_sparse
from .term import NodalLiquid


def nodal_model(t, i, params, g, sparse):
    """One tank's nodal element model, at the values `params` (canonical keys) and `gravity` give,
    traced or not."""
    P = lambda k, d: params.get(f"tanks.{t.name}.{k}", d)  # noqa: E731
    if not t.geometry.plain_box and isinstance(P("fill_depth", t.fill_depth), jax.core.Tracer):
        raise SceneError(f"tanks[{i}].fill_depth", f"the fill depth of a {t.shape} tank (or one with baffles) "
                                                  "cannot be traced: its mesh follows the fill")
    m = build_liquid(t.size, P("fill_depth", t.fill_depth), t.mesh, P("fluid.density", t.fluid.density),
                     P("fluid.sound_speed", t.fluid.sound_speed), g, element=t.fluid.element,
                     sparse=sparse, geometry=t.geometry)
    if sparse and m.traced:
        raise SceneError(f"tanks[{i}]", "a traced tank value (fill depth, density, sound speed or gravity in "
                                        "params or a sweep) needs the dense liquid matrices; this mesh uses the "
                                        "sparse solver: set simulation.linear_solver = \"dense\" if they fit (element = "
                                        "\"rt\" takes a traced density, sound speed or gravity at any size)")
    return m


def nodal_block(tanks, models, sparse: bool, host_lu: bool) -> LiquidBlock:
    """Every tank's nodal liquid at full order, stacked block-diagonally: dense, or sparse (HostSparse
    matrices; the box grids for the fast-diagonalization inverse, boxsolve.py)."""
    traced = any(m.traced for m in models)
    xp = jnp if traced else np
    blocks, rs, Ms_list, K_list, free_list, Kdt_list, Ktt = [], [], [], [], [], [], xp.zeros((3, 3))
    coupled = False
    offset = 0
    for t, m in zip(tanks, models):
        N = m.nodes.shape[0]
        blocks.append(host_block(t, m, offset))
        rs.append(xp.asarray(m.nodes) + xp.asarray(t.origin)[None, :])
        free = np.flatnonzero(np.asarray(m.free))
        if sparse:
            Ms_list.append(m.mass)
            K_list.append(m.stiffness.tocsr()[free][:, free])
        else:
            Ms_list.append(xp.asarray(m.mass))
            K_list.append(xp.asarray(m.stiffness)[np.ix_(free, free)])
        if m.rotation_coupling is not None:
            coupled = True
            Kdt_list.append(xp.asarray(m.rotation_coupling)[free])
            Ktt = Ktt + xp.asarray(m.rotation_stiffness)
        else:
            Kdt_list.append(xp.zeros((free.size, 3)))
        free_list.append(free + 3 * offset)
        offset += N
    frames = None
    if any(m.frames is not None for m in models):       # shaped tanks: every node's frame (identity on boxes)
        frames = jnp.asarray(np.concatenate([np.tile(np.eye(3), (m.n_nodes, 1, 1)) if m.frames is None
                                             else np.asarray(m.frames) for m in models]))
    if sparse:
        Kdt = jnp.asarray(np.concatenate(Kdt_list)) if coupled else None
        boxes = all(m.geometry is None for m in models)     # the fast diagonalization needs box grids
        meshes = [tuple(m.mesh) for m in models]
        nodes_of = [np.arange(m.nodes.shape[0]) for m in models]
        free_of = [np.flatnonzero(np.asarray(m.free)) for m in models]
        layers = tuple(m.layers for m in models) if boxes else None
        liquid = NodalLiquid(r=jnp.asarray(np.concatenate(rs)),
                        Ms=host_sparse(sp.block_diag(Ms_list), tuple(zip(meshes, [1] * len(models), nodes_of))
                                       if boxes else None, layers),
                        K=host_sparse(sp.block_diag(K_list), tuple(zip(meshes, [3] * len(models), free_of))
                                      if boxes else None, layers),
                        free=jnp.asarray(np.concatenate(free_list)), n_nodes=offset,
                        slot=slots(np.concatenate(free_list), offset),
                        grids=tuple(m.mesh + (surface_bending_scale(m), m.element) for m in models) if boxes else None,
                        sparse=True, frames=frames, host_lu=host_lu)
        return LiquidBlock(liquid, tuple(blocks), (Kdt, jnp.asarray(Ktt)) if coupled else None)
    stack = jax_block_diag if traced else block_diag
    liquid = NodalLiquid(r=jnp.asarray(xp.concatenate(rs)), Ms=jnp.asarray(stack(*Ms_list)),
                    K=jnp.asarray(stack(*K_list)), free=jnp.asarray(np.concatenate(free_list)), n_nodes=offset,
                    frames=frames, slot=slots(np.concatenate(free_list), offset))
    penalty = (jnp.asarray(xp.concatenate(Kdt_list)), jnp.asarray(Ktt)) if coupled else None
    return LiquidBlock(liquid, tuple(blocks), penalty)


def walls_block(tanks, models, held=(), Kg=None) -> LiquidBlock:
    """The stacked deformable block of the vessel's frame when some tank has elastic walls
    (liquid/walls.py) or some structure has frame = "vessel" (`held`: the assembly's HeldStructure
    per structure, `Kg` their centrifugal stiffness): every tank's nodes (liquid, then its walls'),
    then those structures' nodes; the map from nodal dofs to unknowns (held ones map to the zero
    slot); the matrices on the unknowns."""
    blocks, rs, Ms_list, K_list, maps, reps, Kdt_list = [], [], [], [], [], [], []
    carried_idx = []      # (block index, first carried node): elastic walls and vessel-frame structures
    coupled = False
    Ktt = np.zeros((3, 3))
    node_off, free_off = 0, 0
    for t, m in zip(tanks, models):
        blocks.append(TankBlock(t.name, node_off, np.asarray(m.nodes), np.asarray(m.elements), m))
        if t.form.elastic:
            tw = build_tank_with_walls(t, m)
            nodes, Ms, K, dmap, rep, C = tw.nodes, tw.mass, tw.stiffness, tw.dof_map, tw.rep, tw.rotation_coupling
            carried_idx.append((len(rs), m.n_nodes))
        else:
            free = np.asarray(m.free).reshape(-1)
            dmap = np.where(free, np.cumsum(free) - 1, -1)
            rep = np.flatnonzero(free)
            nodes, Ms = np.asarray(m.nodes), np.asarray(m.mass)
            K = np.asarray(m.stiffness)[np.ix_(rep, rep)]
            C = None if m.rotation_coupling is None else np.asarray(m.rotation_coupling)[rep]
        rs.append(nodes + np.asarray(t.origin)[None, :])
        Ms_list.append(Ms)
        K_list.append(K)
        maps.append(np.where(dmap >= 0, dmap + free_off, -1))
        reps.append(rep + 3 * node_off)
        if C is not None:
            coupled = True
            Kdt_list.append(C)
            Ktt = Ktt + np.asarray(m.rotation_stiffness)
        else:
            Kdt_list.append(np.zeros((rep.size, 3)))
        node_off += nodes.shape[0]
        free_off += rep.size
    vstructs = []
    first_held = free_off
    for hs in held:
        nodes = hs.nodes
        fr = np.zeros(3 * nodes.shape[0], dtype=bool)
        fr[hs.free] = True
        dmap = np.where(fr, np.cumsum(fr) - 1, -1)
        vstructs.append(VesselFrameStructure(hs.name, node_off, nodes, hs.elements))
        carried_idx.append((len(rs), 0))
        rs.append(nodes + hs.origin[None, :])
        Ms_list.append(hs.mass)
        K_list.append(hs.stiffness)
        maps.append(np.where(dmap >= 0, dmap + free_off, -1))
        reps.append(hs.free + 3 * node_off)
        Kdt_list.append(np.zeros((hs.free.size, 3)))
        node_off += nodes.shape[0]
        free_off += hs.free.size
    dof_map = np.concatenate(maps)
    dof_map = np.where(dof_map >= 0, dof_map, free_off)          # the zero slot after the unknowns
    liquid = NodalLiquid(r=jnp.asarray(np.concatenate(rs)), Ms=jnp.asarray(block_diag(*Ms_list)),
                    K=jnp.asarray(block_diag(*K_list)), free=jnp.asarray(np.concatenate(reps)), n_nodes=node_off,
                    dof_map=jnp.asarray(dof_map))
    carried = tuple(rigid_part(Ms_list[k], rs[k][n0:], n0) for k, n0 in carried_idx)
    penalty = (jnp.asarray(np.concatenate(Kdt_list)), jnp.asarray(Ktt)) if coupled else None
    return LiquidBlock(liquid, tuple(blocks), penalty, Kg=None if Kg is None else jnp.asarray(Kg), Kg_offset=first_held,
                       vstructs=tuple(vstructs), carried=carried)
