"""The stacked liquid block of a scene's tanks (physics/system.py `Liquid`), from their finite-element
models (fem/liquid.py): dense, sparse (large meshes, solve/sparse.py), reduced to modes
(assemble/reduced.py), or extended by elastic walls and structures in the vessel's frame."""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
from jax.scipy.linalg import block_diag as jax_block_diag
from scipy.linalg import block_diag

from ..fem.liquid import build_liquid, surface_bending_scale
from ..fem.liquid_rt import FaceLiquid, build_face_liquid
from ..fem.mesh import grid_nodes
from ..fem.walls import build_tank_with_walls, shell_mesh
from ..physics.liquid import AbstractLiquid, Liquid, NoLiquid
from ..scene.types import FACE_FORMS, Scene, SceneError
from ..solve.sparse import SPARSE_AUTO, host_sparse
from .effects import liquid_unknowns
from .face_liquid import RT_SPARSE_AUTO, face_full_liquid
from .reduced import reduce_liquid
from .structures import held_spin_stiffness, held_structure


class LiquidBlock(NamedTuple):
    """The deformable block of the vessel's frame and what comes with it."""
    liquid: AbstractLiquid
    tanks: tuple = ()                   # TankBlock per tank
    penalty: Optional[tuple] = None     # (K_dt, K_tt) of the stabilized element's rotation penalty
    Kg: Optional[jax.Array] = None      # (6, n, n) centrifugal stiffening of vessel-frame structures
    Kg_offset: int = 0                  # on the unknowns Kg_offset ... (the structures', after the liquid's)
    vstructs: tuple = ()                # VesselFrameStructure per structure in the vessel's frame
    carried: tuple = ()                 # rigid_part of the elastic walls and vessel-frame structures


class TankBlock(NamedTuple):
    """Where one tank's liquid sits in the stacked liquid block, for probes and result fields."""
    name: str
    node_offset: int
    nodes: np.ndarray      # (N_t, 3) tank-local
    elements: np.ndarray   # (E_t, 8) tank-local node indices
    model: object          # liquid.LiquidModel


def build_liquid_block(scene: Scene, params: Optional[dict] = None, gravity=None, include_liquid=True):
    """The stacked liquid block of all tanks. `params` (canonical keys) may replace each tank's
    fill depth, density and sound speed, and `gravity` the scene's, by traced values: then the
    matrices are JAX values (the integer mesh, the free dofs and the probes' host-side geometry
    stay NumPy).

    The host-side tank blocks (`TankBlock.nodes`, used for the probes' interpolation weights and the
    result's undeformed mesh) are the mesh at the scene's fill depth, whatever the params say: a
    probe keeps its place relative to the mesh (one at the scene's fill depth stays on the free
    surface), so its weights do not depend on a traced fill depth."""
    rigid = [t for t in scene.tanks] if include_liquid else []
    in_vessel_frame = [s for s in scene.structures if s.frame == "vessel"]
    if not rigid and not in_vessel_frame:
        return LiquidBlock(NoLiquid())

    params = params or {}
    g = scene.environment.gravity if gravity is None else gravity
    sparse = wants_sparse(scene)
    models = []
    for i, t in enumerate(rigid):
        if t.fluid.element in FACE_FORMS:
            models.append(_face_model(scene, t, i, params, g))
            continue
        P = lambda k, d: params.get(f"tanks.{t.name}.{k}", d)  # noqa: E731
        if not t.geometry.plain_box and isinstance(P("fill_depth", t.fill_depth), jax.core.Tracer):
            raise SceneError(f"tanks[{i}].fill_depth", f"the fill depth of a {t.shape} tank (or one with baffles) "
                                                      "cannot be traced: its mesh follows the fill")
        models.append(build_liquid(t.size, P("fill_depth", t.fill_depth), t.mesh, P("fluid.density", t.fluid.density),
                                   P("fluid.sound_speed", t.fluid.sound_speed), g, element=t.fluid.element,
                                   sparse=sparse, geometry=t.geometry))
        if sparse and models[-1].traced:
            raise SceneError(f"tanks[{i}]", "a traced tank value (fill depth, density, sound speed or gravity in "
                                            "params or a sweep) needs the dense liquid matrices; this mesh uses the "
                                            "sparse solver: set simulation.linear_solver = \"dense\" if they fit (element = "
                                            "\"rt\" takes a traced density, sound speed or gravity at any size)")
    traced = any(m.traced for m in models)
    xp = jnp if traced else np
    reduced = [t.reduction is not None for t in rigid]
    elastic = [t.wall_spec is not None for t in rigid]
    faces = bool(models) and all(isinstance(m, FaceLiquid) for m in models)
    if (any(elastic) or in_vessel_frame) and faces:     # "rt": fem/walls_rt.py, assemble/face_liquid.py, full order
        for i, t in enumerate(rigid):
            if reduced[i]:
                raise SceneError(f"tanks[{i}].walls" if elastic[i] else f"tanks[{i}].reduction",
                                 "elastic walls, and structures in the vessel's frame, need the full-order liquid "
                                 "(no [tanks.reduction] in any tank)")
    elif any(elastic) or in_vessel_frame:
        for i, t in enumerate(rigid):
            if isinstance(models[i], FaceLiquid):
                other = next(m.element for m in models if not isinstance(m, FaceLiquid))
                raise SceneError(f"tanks[{i}].fluid.element",
                                 f"{t.fluid.element!r} takes elastic walls and structures in the vessel's frame only "
                                 f"when every tank is \"rt\" (another tank's is {other!r}): give every tank the "
                                 "same element")
            if models[i].frames is not None:
                raise SceneError(f"tanks[{i}].shape", f"structures in the vessel's frame go with the {t.fluid.element!r} "
                                                      "element in box tanks (and shapes whose liquid touches only walls "
                                                      "along the axes) only: element = \"rt\" takes them in any tank")
            if reduced[i] or sparse or models[i].traced:
                raise SceneError(f"tanks[{i}].walls" if elastic[i] else f"tanks[{i}]",
                                 "elastic walls, and structures in the vessel's frame, need the full-order dense "
                                 "liquid with the scene's own values (no [tanks.reduction], no sparse solver, no "
                                 "traced tank values)")
        return _liquid_with_walls(rigid, models, in_vessel_frame)
    scales = [face_scales(scene, t, params, g) if isinstance(m, FaceLiquid) else None for t, m in zip(rigid, models)]
    if any(reduced):
        return _reduced_liquid(scene, rigid, models, reduced, g, scales)
    if any(isinstance(m, FaceLiquid) for m in models):
        depths = [params.get(f"tanks.{t.name}.fill_depth", t.fill_depth) / t.fill_depth
                  if isinstance(m, FaceLiquid) and isinstance(params.get(f"tanks.{t.name}.fill_depth"), jax.core.Tracer)
                  else None for t, m in zip(rigid, models)]
        return _face_full(rigid, models, scales, depths, face_sparse(scene, models, scales, depths),
                          [held_structure(st) for st in in_vessel_frame])

    blocks, rs, Ms_list, K_list, free_list, Kdt_list, Ktt = [], [], [], [], [], [], xp.zeros((3, 3))
    coupled = False
    offset = 0
    for t, m in zip(rigid, models):
        N = m.nodes.shape[0]
        blocks.append(_host_block(t, m, offset))
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
        liquid = Liquid(r=jnp.asarray(np.concatenate(rs)),
                        Ms=host_sparse(sp.block_diag(Ms_list), tuple(zip(meshes, [1] * len(models), nodes_of))
                                       if boxes else None, layers),
                        K=host_sparse(sp.block_diag(K_list), tuple(zip(meshes, [3] * len(models), free_of))
                                      if boxes else None, layers),
                        free=jnp.asarray(np.concatenate(free_list)), n_nodes=offset,
                        slot=_slots(np.concatenate(free_list), offset),
                        grids=tuple(m.mesh + (surface_bending_scale(m), m.element) for m in models) if boxes else None,
                        sparse=True, frames=frames, host_lu=scene.simulation.linear_solver == "sparse-host")
        return LiquidBlock(liquid, tuple(blocks), (Kdt, jnp.asarray(Ktt)) if coupled else None)
    stack = jax_block_diag if traced else block_diag
    liquid = Liquid(r=jnp.asarray(xp.concatenate(rs)), Ms=jnp.asarray(stack(*Ms_list)),
                    K=jnp.asarray(stack(*K_list)), free=jnp.asarray(np.concatenate(free_list)), n_nodes=offset,
                    frames=frames, slot=_slots(np.concatenate(free_list), offset))
    penalty = (jnp.asarray(xp.concatenate(Kdt_list)), jnp.asarray(Ktt)) if coupled else None
    return LiquidBlock(liquid, tuple(blocks), penalty)


def _slots(free, n_nodes):
    """Liquid.slot: the position of each of the 3 n_nodes nodal dofs among the free ones, len(free)
    where held."""
    slot = np.full(3 * n_nodes, len(free), dtype=np.int32)
    slot[np.asarray(free)] = np.arange(len(free), dtype=np.int32)
    return jnp.asarray(slot)


def _liquid_with_walls(tanks, models, structures=()):
    """The stacked deformable block of the vessel's frame when some tank has elastic walls
    (fem/walls.py) or some structure has frame = "vessel": every tank's nodes (liquid, then its
    walls'), then those structures' nodes; the map from nodal dofs to unknowns (held ones map to the
    zero slot); the matrices on the unknowns; and the structures' centrifugal stiffness."""
    blocks, rs, Ms_list, K_list, maps, reps, Kdt_list = [], [], [], [], [], [], []
    carried_idx = []      # (block index, first carried node): elastic walls and vessel-frame structures
    coupled = False
    Ktt = np.zeros((3, 3))
    node_off, free_off = 0, 0
    for t, m in zip(tanks, models):
        blocks.append(TankBlock(t.name, node_off, np.asarray(m.nodes), np.asarray(m.elements), m))
        if t.wall_spec is not None:
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
    vstructs, held = [], [held_structure(st) for st in structures]
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
    Kg = held_spin_stiffness(held)
    liquid = Liquid(r=jnp.asarray(np.concatenate(rs)), Ms=jnp.asarray(block_diag(*Ms_list)),
                    K=jnp.asarray(block_diag(*K_list)), free=jnp.asarray(np.concatenate(reps)), n_nodes=node_off,
                    dof_map=jnp.asarray(dof_map))
    carried = tuple(rigid_part(Ms_list[k], rs[k][n0:], n0) for k, n0 in carried_idx)
    penalty = (jnp.asarray(np.concatenate(Kdt_list)), jnp.asarray(Ktt)) if coupled else None
    return LiquidBlock(liquid, tuple(blocks), penalty, Kg=None if Kg is None else jnp.asarray(Kg), Kg_offset=first_held,
                       vstructs=tuple(vstructs), carried=carried)


def rigid_part(Ms, r, n0=0):
    """(mass, first moment, inertia about the origin) of the nodes n0... of a block with scalar mass Ms
    (consistent: the inertia a rigid motion of the nodes has in the dynamics)."""
    Ms = np.asarray(Ms)[n0:, n0:]
    r = np.asarray(r)
    mn = Ms.sum(axis=1)
    G = r.T @ Ms @ r                                                 # sum_ij Ms_ij r_i r_j^T
    return float(mn.sum()), mn @ r, np.trace(G) * np.eye(3) - G


class VesselFrameStructure(NamedTuple):
    """A structure with frame = "vessel" inside the vessel-frame block: its nodes (block-local from
    its min corner) start at `node_offset`."""
    name: str
    node_offset: int
    nodes: np.ndarray
    elements: np.ndarray


def _face_model(scene, t, i, params, g):
    """The face-normal liquid of one tank (fem/liquid_rt.py), with the scene's own values: runs take it
    on its modal basis (assemble/reduced.py) or at full order (assemble/face_liquid.py)."""
    if isinstance(params.get(f"tanks.{t.name}.fill_depth"), jax.core.Tracer):
        if not t.geometry.plain_box:
            raise SceneError(f"tanks[{i}].fill_depth", f"the fill depth of a {t.shape} tank (or one with baffles) "
                                                      f"with element {t.fluid.element!r} cannot be traced: its mesh "
                                                      "follows the fill (a plain box's can, at full order)")
        if t.reduction is not None:
            raise SceneError(f"tanks[{i}].fill_depth", f"a traced fill depth with element {t.fluid.element!r} runs "
                                                      "at full order only (its modes are the scene's fill's): "
                                                      "leave out [tanks.reduction]")
    tm = t.geometry.mesh(t.fill_depth, t.mesh)
    return build_face_liquid(tm.nodes, tm.elements, tm.depth, t.fluid.density, t.fluid.sound_speed,
                             scene.environment.gravity, geometry=None if t.geometry.plain_box else t.geometry)


def face_scales(scene, t, params, g):
    """(rho, rho c^2, rho g) of a face-normal tank over the scene's values, for traced density, sound
    speed and gravity: its model (and basis) is built at the scene's values, and its mass, compression
    and free-surface blocks scale with these (the element's matrices are linear in each)."""
    f = t.fluid
    rho = params.get(f"tanks.{t.name}.fluid.density", f.density)
    c = params.get(f"tanks.{t.name}.fluid.sound_speed", f.sound_speed)
    g0 = scene.environment.gravity
    return rho / f.density, rho * c * c / (f.density * f.sound_speed ** 2), rho * g / (f.density * g0)


def face_sparse(scene, models, scales, depths) -> bool:
    """Whether full-order face-normal tanks take the blocks without dense matrices on the faces
    (assemble/face_liquid.py sparse_tank_blocks; density, sound speed and gravity from params, traced
    or not, scale them: `stack_sparse`): no elastic walls or structures in the vessel's frame (their
    dense blocks), no traced fill depth (a plain box's depth reshapes its blocks: the dense
    `traced_depth_blocks`), and `simulation.linear_solver` "sparse" or "sparse-host", or "auto" above
    RT_SPARSE_AUTO free faces."""
    if any(t.wall_spec is not None for t in scene.tanks) or any(s.frame == "vessel" for s in scene.structures):
        return False                    # elastic walls, structures in the vessel's frame: their dense blocks
    if any(d is not None for d in depths):
        return False
    choice = scene.simulation.linear_solver
    faces = sum(int(np.count_nonzero(m.free)) for m in models)
    return choice in ("sparse", "sparse-host") or (choice == "auto" and faces > RT_SPARSE_AUTO)


def _face_full(tanks, models, scales, depths=None, sparse=False, structures=()):
    """Face-normal tanks at full order (assemble/face_liquid.py): every tank's, none of the nodal ones;
    then the structures in the vessel's frame (assemble/structures.py HeldStructure), their nodal
    dofs after every tank's unknowns."""
    for i, m in enumerate(models):
        if not isinstance(m, FaceLiquid):
            raise SceneError(f"tanks[{i}].fluid.element", "a full-order \"rt\" tank goes with other \"rt\" tanks "
                                                          "only: give this one element = \"rt\" too, or give every "
                                                          "tank a [tanks.reduction] table")
        traced = any(isinstance(v, jax.core.Tracer) for v in (scales[i] or ())) or (depths or [None] * len(models))[i] \
            is not None
        if structures and traced:
            raise SceneError(f"tanks[{i}]", "structures in the vessel's frame need the liquid with the scene's own "
                                            "values (no traced fill depth, density, sound speed or gravity in params "
                                            "or a sweep)")
    blocks, offset = [], 0
    for t, m in zip(tanks, models):
        blocks.append(_host_block(t, m, offset))
        offset += m.n_nodes + (0 if t.wall_spec is None else wall_node_count(t))    # a tank's walls follow its liquid
    liquid, penalty, walls = face_full_liquid(tanks, models, scales, depths, sparse, structures)
    carried = tuple(rigid_part(w.mass, w.nodes + np.asarray(t.origin)[None, :]) for t, w in zip(tanks, walls)
                    if w is not None)           # the walls are part of the ship's mass (docs/reference/scene.md)
    vstructs = []
    for hs in structures:                       # after every tank's nodes, in the stacked nodal fields
        vstructs.append(VesselFrameStructure(hs.name, offset, hs.nodes, hs.elements))
        carried += (rigid_part(hs.mass, hs.nodes + hs.origin[None, :]),)
        offset += hs.nodes.shape[0]
    Kg = held_spin_stiffness(structures)
    n_held = sum(hs.free.size for hs in structures)
    return LiquidBlock(liquid, tuple(blocks), penalty, Kg=None if Kg is None else jnp.asarray(Kg),
                       Kg_offset=liquid.nf - n_held, vstructs=tuple(vstructs), carried=carried)


def _host_block(t, m, offset) -> TankBlock:
    """The tank's block for probes and result fields, with the mesh at the scene's fill depth: a
    probe keeps its place relative to the mesh whatever a traced fill depth says."""
    if m.geometry is not None or (not m.traced and m.depth == t.fill_depth):
        nodes = np.asarray(m.nodes)
    else:
        nodes = grid_nodes((t.size[0], t.size[1], t.fill_depth), m.mesh)
    return TankBlock(t.name, offset, nodes, np.asarray(m.elements), m)


def _reduced_liquid(scene: Scene, tanks, models, reduced, g, scales):
    """Every tank's liquid on its modal basis (reduction.py); the bases come from the scene's values."""
    for i, (t, r) in enumerate(zip(tanks, reduced)):
        if not r:
            raise SceneError(f"tanks[{i}].reduction", "reduce every tank or none: another tank has a "
                                                       "[tanks.reduction] table and this one has not")
    concrete = []
    for t, m in zip(tanks, models):
        if getattr(m, "traced", False) or (isinstance(g, jax.core.Tracer) and not isinstance(m, FaceLiquid)):
            m = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed,
                             scene.environment.gravity, element=t.fluid.element, geometry=t.geometry)
        concrete.append(m)
    offsets, blocks, offset = [], [], 0
    for t, m in zip(tanks, models):
        offsets.append(offset)
        blocks.append(_host_block(t, m, offset))
        offset += m.n_nodes
    liquid, penalty = reduce_liquid(models, concrete, [t.origin for t in tanks], offsets,
                                    [(t.reduction.modes, t.reduction.static_correction) for t in tanks], scales)
    return LiquidBlock(liquid, tuple(blocks), penalty)



def wants_sparse(scene) -> bool:
    """Whether the scene's liquid goes the sparse way (`simulation.linear_solver`)."""
    choice = scene.simulation.linear_solver
    if choice != "auto":
        return choice in ("sparse", "sparse-host")
    if any(t.wall_spec is not None for t in scene.tanks):
        return False             # elastic walls have dense blocks of their own
    return liquid_unknowns(scene) > SPARSE_AUTO


def outline_liquid_block(scene: Scene, include_liquid: bool = True) -> LiquidBlock:
    """`build_liquid_block`'s terms without their arrays (None), for `jaxslosh check` (assemble/
    check.py), whatever the mesh's size: no mesh is assembled. The liquid (its class the nodal one
    whatever the element: only its description is read), the rotation penalty that tank liquid of
    every element form brings, and the vessel-frame structures' spin stiffening."""
    tanks = list(scene.tanks) if include_liquid else []
    in_vessel_frame = [s for s in scene.structures if s.frame == "vessel"]
    if not tanks and not in_vessel_frame:
        return LiquidBlock(NoLiquid())
    stiffened = any(s.stiffening == "centrifugal" for s in in_vessel_frame)
    return LiquidBlock(Liquid(r=None, Ms=None, K=None, free=None, n_nodes=0), penalty=(None, None) if tanks else None,
                       Kg=np.zeros((6, 0, 0)) if stiffened else None)


def wall_node_count(t) -> int:
    """The nodes of a tank's elastic walls (fem/walls.py shell_mesh)."""
    return int(shell_mesh(t.size, t.fill_depth, t.mesh, t.wall_spec.thickness, t.wall_spec.mesh)[0].shape[0])
