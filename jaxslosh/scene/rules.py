"""Rules over a whole scene that the loader applies once its tables are read: the scenes an option
needs (`simulation.energy_projection`), and the elements known to lock in a tank's shape."""
from __future__ import annotations

from .types import ELEMENT_FORMS, Scene, SceneError


def locking_elements(tanks, warnings: list[str]) -> None:
    """A nodal element (given: the loader never chooses one there) in a tank with re-entrant edges
    locks: every line of held nodes along such an edge removes a whole mode (a U-tube has no U-tube
    mode, a baffle's mode is too stiff), with no error to show for it (docs/guide/liquid-element.md)."""
    for i, t in enumerate(tanks):
        if t.model != "fem" or t.fluid.element not in ELEMENT_FORMS:
            continue
        reentrant, what = t.geometry.reentrant(t.fill_depth)
        if reentrant:
            warnings.append(f'tanks[{i}] ({t.name!r}): element = "{t.fluid.element}" locks in this tank ({what}): '
                            'its nodal displacements lose whole sloshing modes there (a U-tube\'s U-tube mode, the '
                            'modes a baffle shapes); element = "rt" (face-normal) holds there, and is the default '
                            'where tanks.fluid.element is left out')


def conservative(scene: Scene) -> None:
    """`simulation.energy_projection` holds the total energy at its initial value: only right when
    nothing in the scene adds or removes energy and the equations are those of that energy."""
    v, e = scene.vessel, scene.effects
    why = []
    if v.forced is not None:
        why.append("[vessel.forced] prescribes motion (it does work)")
    if scene.waves is not None or v.hydrodynamics is not None or v.hull is not None:
        why.append("waves and hull hydrodynamics add and radiate energy")
    if any(t.damping is not None for t in scene.tanks + tuple(t for b in scene.bodies for t in b.tanks)):
        why.append("[tanks.damping] removes energy")
    if scene.structures:
        why.append("flexible structures are not covered by the projection")
    if any(b.viscous_damping is not None for b in scene.bodies) or any(c.damping for c in scene.connections):
        why.append("the bodies' viscous damping and the connections' damping remove energy")
    if any(b.hydrostatics.moment != "conservative" for b in scene.bodies):
        why.append('a body\'s hydrostatics.moment = "paper" is not the gradient of a potential')
    if v.hydrostatics is not None and v.hydrostatics.moment != "conservative":
        why.append('vessel.hydrostatics.moment = "paper" is not the gradient of a potential')
    off = [k for k in ("coriolis", "centrifugal", "gravity_turning") if not getattr(e, k)]
    if off:
        why.append(f"effects {', '.join(off)} off: the equations are no longer those of the total energy")
    if why:
        raise SceneError("simulation.energy_projection",
                         "needs a conservative scene (the total energy must stay constant), but " + "; ".join(why))
