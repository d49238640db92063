"""Natural modes of a scene's tank liquid or flexible structure, the vessel held fixed (`jaxslosh modes`)."""
from __future__ import annotations


from ..fem.mesh import face_nodes
from ..fem.structure import build_structure, clamped_modes
from ..liquid.forms import tank_liquid
from ..scene.types import Scene


def sloshing_modes(scene: Scene, tank=None, n: int = 10):
    """The first n modes of a tank's liquid: `Modes(omega, kind, free_surface_share, shapes)`, as
    the model that runs the tank's form computes them (liquid/base.py `AbstractLiquid.sloshing_modes`:
    a multimodal tank's linear modes, a finite-element tank's natural modes, with its elastic walls
    where it has them)."""
    t = scene.tank(tank) if tank is not None else scene.tanks[0]
    return tank_liquid(t).sloshing_modes(t, scene.environment.gravity, n)


def structure_modes(scene: Scene, structure: str, n: int = 10):
    """The first n modes of a flexible structure held at its attachment face (the vessel, or the
    structure it is attached to, held fixed): `StructureModes(omega, kind, shares, shapes)`; each mode
    named by the pattern of its cross-sections that holds most of its kinetic energy (bending along
    an axis, torsion, axial, other)."""
    st = scene.structure(structure)
    m = build_structure(st.size, st.mesh, st.material.young, st.material.poisson, st.material.density)
    return clamped_modes(m, face_nodes(m.nodes, m.size, st.attach), n=n)
