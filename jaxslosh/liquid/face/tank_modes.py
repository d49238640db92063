"""One tank's face-normal liquid held fixed: its full-order unknowns and its natural modes (with its
elastic walls, where it has them), the face-normal model's share of the liquid contract
(liquid/base.py `AbstractLiquid.tank_unknowns`, `sloshing_modes`)."""
from __future__ import annotations

from ..modes import Modes
from .element import build_face_liquid, face_modes
from .mesh import free_face_count
from .walls import build_face_tank_with_walls, face_tank_modes


def face_unknowns(tank) -> int:
    """The free faces: the interior ones and the free surface's (liquid/face/element.py)."""
    nx, ny, nz = tank.mesh
    if tank.geometry.plain_box:         # interior faces along x, y and z, and the nx ny top faces
        return 3 * nx * ny * nz - ny * nz - nx * nz
    tm = tank.geometry.mesh(tank.fill_depth, tuple(tank.mesh))
    return free_face_count(tm.nodes, tm.elements, tm.depth)


def face_sloshing_modes(tank, g: float, n: int) -> Modes:
    """The face-normal element's modes (liquid/face/element.py): the circulation modes, all at zero
    frequency, are left out and counted (`Modes.circulation`); shapes are nodal fields, each node the
    mean of its elements' displacements there. With elastic walls, the liquid's and theirs together
    (kinds add "wall")."""
    tm = tank.geometry.mesh(tank.fill_depth, tank.mesh)
    model = build_face_liquid(tm.nodes, tm.elements, tm.depth, tank.fluid.density, tank.fluid.sound_speed, g)
    if tank.form.elastic:
        return face_tank_modes(build_face_tank_with_walls(tank, model), n=n)
    fm = face_modes(model, n)
    shapes = model.nodal_fields(fm.fluxes).reshape(len(fm.omega), -1)
    return Modes(omega=fm.omega, kind=fm.kind, free_surface_share=fm.free_surface_share, shapes=shapes,
                 circulation=fm.circulation)
