"""One tank's nodal liquid held fixed: its full-order unknowns and its natural modes (with its
elastic walls, where it has them), the nodal model's share of the liquid contract
(liquid/base.py `AbstractLiquid.tank_unknowns`, `sloshing_modes`)."""
from __future__ import annotations

from ..modes import liquid_modes
from ..walls import build_tank_with_walls, tank_modes
from .model import build_liquid
from .sparse import SPARSE_AUTO


def nodal_unknowns(tank) -> int:
    """The nodal element's three dofs per node, less the wall-normal ones the slip walls hold."""
    if not tank.geometry.plain_box:
        return tank.geometry.free_count(tank.fill_depth, tuple(tank.mesh))
    nx, ny, nz = tank.mesh
    nodes = (nx + 1) * (ny + 1) * (nz + 1)
    return 3 * nodes - (2 * (ny + 1) * (nz + 1) + 2 * (nx + 1) * (nz + 1) + (nx + 1) * (ny + 1))


def nodal_sloshing_modes(tank, g: float, n: int):
    """The n lowest modes of the tank's liquid (`liquid/modes.Modes`), or of the liquid and its
    elastic walls together (`liquid/walls.TankModes`: kinds add "wall")."""
    # large meshes as the simulation takes them: sparse matrices and shift-invert Lanczos (a dense
    # generalized eigh needs every matrix dense, and crashed OpenBLAS at 20 x 20 x 12)
    # (tanks of other shapes too: their walls' frames make the dense mass full, shift-invert is quicker)
    large = not tank.form.elastic and (nodal_unknowns(tank) > SPARSE_AUTO or not tank.geometry.plain_box)
    model = build_liquid(tank.size, tank.fill_depth, tank.mesh, tank.fluid.density, tank.fluid.sound_speed, g,
                         element=tank.fluid.element, sparse=large, geometry=tank.geometry)
    if tank.form.elastic:
        return tank_modes(build_tank_with_walls(tank, model), n=n)
    return liquid_modes(model, n=n)
