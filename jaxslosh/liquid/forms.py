"""Which liquid model a scene's tanks take, decided once from each tank's form (scene/liquids.py
`Tank.form`, made by the loader from its keys): the final liquid class that runs a tank
(`tank_liquid`, which answers its unknowns and modes), each tank's element model (the nodal one of
nodal/model.py, or the face-normal one of face/element.py), then the one form of the stacked block
they go into together (nodal, face-normal, on modal bases, or with elastic walls and structures in
the vessel's frame), after the checks that their keys go together. Each form's builder lives in its
model's sub-package."""
from __future__ import annotations

import numpy as np

from ..scene.liquids import FaceForm, MultimodalForm, NodalForm
from ..scene.types import SceneError
from .base import AbstractLiquid, NoLiquid
from .block import LiquidBlock
from .face.stack import face_block, face_model
from .face.term import FaceLiquid
from .modal.build import reduced_block
from .modal.term import ModalLiquid
from .multimodal.build import multimodal_block, outline_multimodal
from .multimodal.liquid import MultimodalLiquid
from .nodal.build import nodal_block, nodal_model, walls_block
from .nodal.term import NodalLiquid

#: the final liquid that runs each form at full order (with rigid or elastic walls)
FULL_ORDER = {NodalForm: NodalLiquid, FaceForm: FaceLiquid, MultimodalForm: MultimodalLiquid}


def tank_liquid(tank) -> type[AbstractLiquid]:
    """The final liquid class that runs the tank's form: its `tank_unknowns` and `sloshing_modes`
    answer for the tank before any block is built (a reduced tank's: ModalLiquid)."""
    return ModalLiquid if tank.form.reduced else FULL_ORDER[type(tank.form)]


def tank_models(scene, tanks, params: dict, g, sparse: bool) -> list:
    """Each tank's element model at the values `params` (canonical keys) and `g` give: a face-normal
    tank's at the scene's own values (its blocks scale to traced ones), a nodal one's at them; a
    multimodal tank has none (None)."""
    return [None if t.form.multimodal else face_model(scene, t, i, params) if t.form.face_normal
            else nodal_model(t, i, params, g, sparse) for i, t in enumerate(tanks)]


def block_form(tanks, models, in_vessel_frame: bool, sparse: bool):
    """The builder of the stacked block, (scene, tanks, models, params, g, sparse, held, Kg) ->
    LiquidBlock, with `held` the structures in the vessel's frame and `Kg` their spin stiffness;
    SceneError, naming the key, where the tanks' forms do not go together."""
    if tanks and tanks[0].form.multimodal:       # the loader has made every tank multimodal, or none
        return _multimodal
    faces = bool(tanks) and all(t.form.face_normal for t in tanks)
    reduced = [t.form.reduced for t in tanks]
    elastic = [t.form.elastic for t in tanks]
    if (any(elastic) or in_vessel_frame) and faces:     # "rt": face/walls.py, face/build.py, full order
        for i in range(len(tanks)):
            if reduced[i]:
                raise SceneError(f"tanks[{i}].walls" if elastic[i] else f"tanks[{i}].reduction",
                                 "elastic walls, and structures in the vessel's frame, need the full-order liquid "
                                 "(no [tanks.reduction] in any tank)")
        return _face
    if any(elastic) or in_vessel_frame:
        _check_walls(tanks, models, reduced, elastic, sparse)
        return _walls
    if any(reduced):
        return _reduced
    if any(t.form.face_normal for t in tanks):
        return _face
    return _nodal


def _check_walls(tanks, models, reduced, elastic, sparse):
    """Elastic walls and vessel-frame structures with nodal tanks: every tank's liquid nodal, on a box
    grid, full order, dense and at the scene's own values."""
    for i, t in enumerate(tanks):
        if t.form.face_normal:
            other = next(u.form.element for u in tanks if not u.form.face_normal)
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


def _face(scene, tanks, models, params, g, sparse, held, Kg):
    return face_block(scene, tanks, models, params, g, held, Kg)


def _walls(scene, tanks, models, params, g, sparse, held, Kg):
    return walls_block(tanks, models, held, Kg)


def _reduced(scene, tanks, models, params, g, sparse, held, Kg):
    return reduced_block(scene, tanks, models, params, g)


def _multimodal(scene, tanks, models, params, g, sparse, held, Kg):
    return multimodal_block(scene, params, g)


def outline_block(tanks, in_vessel_frame, g) -> LiquidBlock:
    """`block_form`'s block without its arrays (None), for `jaxslosh check` (assemble/check.py),
    whatever the mesh's size: no mesh is assembled. The liquid (a finite-element tank's the nodal
    one whatever the element: only its description is read), the rotation penalty that their tank
    liquid of every element form brings, and the vessel-frame structures' spin stiffening."""
    if not tanks and not in_vessel_frame:
        return LiquidBlock(NoLiquid())
    if tanks and tanks[0].form.multimodal:
        return outline_multimodal(g)
    stiffened = any(s.stiffening == "centrifugal" for s in in_vessel_frame)
    return LiquidBlock(NodalLiquid(r=None, Ms=None, K=None, free=None, n_nodes=0), penalty=(None, None) if tanks else None,
                       Kg=np.zeros((6, 0, 0)) if stiffened else None)


def _nodal(scene, tanks, models, params, g, sparse, held, Kg):
    return nodal_block(tanks, models, sparse, scene.simulation.linear_solver == "sparse-host")
