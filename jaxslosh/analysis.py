"""Modal analysis of a tank's liquid with the vessel held fixed (`jaxslosh modes`)."""
from __future__ import annotations

from .scene_types import Scene


def sloshing_modes(scene: Scene, tank=None, n: int = 10):
    """The first n modes of a tank's liquid: `Modes(omega, kind, free_surface_share, shapes)`."""
    from .liquid import build_liquid
    from .modes import liquid_modes
    t = scene.tank(tank) if tank is not None else scene.tanks[0]
    model = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed,
                         scene.environment.gravity, element=t.fluid.element)
    return liquid_modes(model, n=n)
