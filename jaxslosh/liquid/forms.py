"""Which liquid model a scene's tanks take, decided once: each tank's element model (the nodal one
of nodal/model.py, or the face-normal one of face/element.py, by `tanks.fluid.element`), then the
one form of the stacked block they go into together (nodal, face-normal, on modal bases, or with
elastic walls and structures in the vessel's frame), after the checks that their keys go together.
Each form's builder lives in its model's sub-package."""
from __future__ import annotations

from ..scene.types import FACE_FORMS, SceneError
from .face.element import FaceModel
from .face.stack import face_block, face_model
from .modal.build import reduced_block
from .nodal.build import nodal_block, nodal_model, walls_block


def tank_models(scene, tanks, params: dict, g, sparse: bool) -> list:
    """Each tank's element model at the values `params` (canonical keys) and `g` give: a face-normal
    tank's at the scene's own values (its blocks scale to traced ones), a nodal one's at them."""
    return [face_model(scene, t, i, params) if t.fluid.element in FACE_FORMS else nodal_model(t, i, params, g, sparse)
            for i, t in enumerate(tanks)]


def block_form(tanks, models, in_vessel_frame: bool, sparse: bool):
    """The builder of the stacked block, (scene, tanks, models, params, g, sparse, held, Kg) ->
    LiquidBlock, with `held` the structures in the vessel's frame and `Kg` their spin stiffness;
    SceneError, naming the key, where the tanks' forms do not go together."""
    faces = bool(models) and all(isinstance(m, FaceModel) for m in models)
    reduced = [t.reduction is not None for t in tanks]
    elastic = [t.wall_spec is not None for t in tanks]
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
    if any(isinstance(m, FaceModel) for m in models):
        return _face
    return _nodal


def _check_walls(tanks, models, reduced, elastic, sparse):
    """Elastic walls and vessel-frame structures with nodal tanks: every tank's liquid nodal, on a box
    grid, full order, dense and at the scene's own values."""
    for i, t in enumerate(tanks):
        if isinstance(models[i], FaceModel):
            other = next(m.element for m in models if not isinstance(m, FaceModel))
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


def _nodal(scene, tanks, models, params, g, sparse, held, Kg):
    return nodal_block(tanks, models, sparse, scene.simulation.linear_solver == "sparse-host")
