"""The face-normal liquid's block of a scene's tanks: each tank's element model (element.py) and the
stacked full-order liquid (build.py), with elastic walls and structures in the vessel's frame; on a
modal basis it is liquid/modal/build.py's."""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ...scene.types import SceneError
from ..block import LiquidBlock, VesselFrameStructure, host_block, rigid_part
from ..walls import shell_mesh
from .build import RT_SPARSE_AUTO, face_full_liquid
from .element import FaceModel, build_face_liquid


def face_model(scene, t, i, params):
    """The face-normal liquid of one tank (element.py), with the scene's own values: runs take it
    on its modal basis (liquid/modal/build.py) or at full order (build.py), scaled to traced values
    by `face_scales`."""
    if isinstance(params.get(f"tanks.{t.name}.fill_depth"), jax.core.Tracer):
        if not t.geometry.plain_box:
            raise SceneError(f"tanks[{i}].fill_depth", f"the fill depth of a {t.shape} tank (or one with baffles) "
                                                      f"with element {t.fluid.element!r} cannot be traced: its mesh "
                                                      "follows the fill (a plain box's can, at full order)")
        if t.form.reduced:
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


def face_sparse(scene, models, depths) -> bool:
    """Whether full-order face-normal tanks take the blocks without dense matrices on the faces
    (build.py sparse_tank_blocks; density, sound speed and gravity from params, traced or not, scale
    them: `stack_sparse`): no elastic walls or structures in the vessel's frame (their dense blocks),
    no traced fill depth (a plain box's depth reshapes its blocks: the dense `traced_depth_blocks`),
    and `simulation.linear_solver` "sparse" or "sparse-host", or "auto" above RT_SPARSE_AUTO free faces."""
    if any(t.form.elastic for t in scene.tanks) or any(s.frame == "vessel" for s in scene.structures):
        return False                    # elastic walls, structures in the vessel's frame: their dense blocks
    if any(d is not None for d in depths):
        return False
    choice = scene.simulation.linear_solver
    faces = sum(int(np.count_nonzero(m.free)) for m in models)
    return choice in ("sparse", "sparse-host") or (choice == "auto" and faces > RT_SPARSE_AUTO)


def face_block(scene, tanks, models, params, g, held=(), Kg=None) -> LiquidBlock:
    """Face-normal tanks at full order (build.py): every tank's, none of the nodal ones; then the
    structures in the vessel's frame (`held`: the assembly's HeldStructure per structure, `Kg` their
    centrifugal stiffness), their nodal dofs after every tank's unknowns."""
    scales = [face_scales(scene, t, params, g) for t in tanks]
    depths = [params.get(f"tanks.{t.name}.fill_depth", t.fill_depth) / t.fill_depth
              if isinstance(params.get(f"tanks.{t.name}.fill_depth"), jax.core.Tracer) else None for t in tanks]
    sparse = face_sparse(scene, models, depths)
    for i, m in enumerate(models):
        if not isinstance(m, FaceModel):
            raise SceneError(f"tanks[{i}].fluid.element", "a full-order \"rt\" tank goes with other \"rt\" tanks "
                                                          "only: give this one element = \"rt\" too, or give every "
                                                          "tank a [tanks.reduction] table")
        traced = any(isinstance(v, jax.core.Tracer) for v in scales[i]) or depths[i] is not None
        if held and traced:
            raise SceneError(f"tanks[{i}]", "structures in the vessel's frame need the liquid with the scene's own "
                                            "values (no traced fill depth, density, sound speed or gravity in params "
                                            "or a sweep)")
    blocks, offset = [], 0
    for t, m in zip(tanks, models):
        blocks.append(host_block(t, m, offset))
        offset += m.n_nodes + (wall_node_count(t) if t.form.elastic else 0)    # a tank's walls follow its liquid
    liquid, penalty, walls = face_full_liquid(tanks, models, scales, depths, sparse, held)
    carried = tuple(rigid_part(w.mass, w.nodes + np.asarray(t.origin)[None, :]) for t, w in zip(tanks, walls)
                    if w is not None)           # the walls are part of the ship's mass (docs/reference/scene.md)
    vstructs = []
    for hs in held:                             # after every tank's nodes, in the stacked nodal fields
        vstructs.append(VesselFrameStructure(hs.name, offset, hs.nodes, hs.elements))
        carried += (rigid_part(hs.mass, hs.nodes + hs.origin[None, :]),)
        offset += hs.nodes.shape[0]
    n_held = sum(hs.free.size for hs in held)
    return LiquidBlock(liquid, tuple(blocks), penalty, Kg=None if Kg is None else jnp.asarray(Kg),
                       Kg_offset=liquid.nf - n_held, vstructs=tuple(vstructs), carried=carried)


def wall_node_count(t) -> int:
    """The nodes of a tank's elastic walls (liquid/walls.py shell_mesh)."""
    return int(shell_mesh(t.size, t.fill_depth, t.mesh, t.wall_spec.thickness, t.wall_spec.mesh)[0].shape[0])
