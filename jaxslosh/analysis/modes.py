"""Natural modes of a scene's tank liquid or flexible structure, the vessel held fixed (`jaxslosh modes`)."""
from __future__ import annotations

import numpy as np

from ..assemble.effects import free_liquid_dofs, modal_modes
from ..liquid.multimodal.build3d import sample_points
from ..liquid.nodal.model import build_liquid
from ..liquid.face.element import build_face_liquid, face_modes
from ..fem.mesh import face_nodes
from ..liquid.modes import Modes, liquid_modes
from ..fem.structure import build_structure, clamped_modes
from ..liquid.walls import build_tank_with_walls, tank_modes
from ..liquid.face.walls import build_face_tank_with_walls, face_tank_modes
from ..liquid.multimodal.modes import DiskBase, RectangleBase
from ..scene.types import Scene
from ..liquid.nodal.sparse import SPARSE_AUTO


def sloshing_modes(scene: Scene, tank=None, n: int = 10):
    """The first n modes of a tank's liquid: `Modes(omega, kind, free_surface_share, shapes)`."""
    t = scene.tank(tank) if tank is not None else scene.tanks[0]
    if t.multimodal:
        return _multimodal_modes(scene, t, n)
    if t.face_normal:
        return _face_modes(scene, t, n)
    # large meshes as the simulation takes them: sparse matrices and shift-invert Lanczos (a dense
    # generalized eigh needs every matrix dense, and crashed OpenBLAS at 20 x 20 x 12)
    # (tanks of other shapes too: their walls' frames make the dense mass full, shift-invert is quicker)
    large = t.wall_spec is None and (free_liquid_dofs(t) > SPARSE_AUTO or not t.geometry.plain_box)
    model = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed,
                         scene.environment.gravity, element=t.fluid.element, sparse=large, geometry=t.geometry)
    if t.wall_spec is not None:       # the liquid and its elastic walls together (kinds add "wall")
        return tank_modes(build_tank_with_walls(t, model), n=n)
    return liquid_modes(model, n=n)


def _multimodal_modes(scene: Scene, t, n: int) -> Modes:
    """A multimodal tank's own linear modes, at most as many as it runs on, omega^2 = g k tanh(k h),
    each a free-surface mode, in frequency order: a two-dimensional box's standing waves along its
    length, k_i = i pi / L (liquid/multimodal/term.py); a three-dimensional box's k = pi sqrt((i / L)^2 +
    (j / B)^2), an upright cylinder's k = j'_{m,s} / R (the zeros of the Bessel functions' derivatives),
    the base's lowest modes completed to whole degenerate pairs (liquid/multimodal/modes.py). The
    shapes are the surface elevation at sample points: along x in two dimensions; round the walls and
    at the centre in three (liquid/multimodal/build3d.py)."""
    modes = modal_modes(t)
    if t.three_dimensional:
        base = t.geometry.modal_base(RectangleBase, DiskBase)
        k = base.wavenumbers(modes)
        order = np.argsort(k, kind="stable")[:n]
        x, y = sample_points(t, 33)
        k, shapes = k[order], base.values([modes[i] for i in order], x, y)[0].T
    else:
        k = np.array([i for i, _ in modes[:n]]) * np.pi / t.size[0]
        shapes = np.cos(np.outer(k, np.linspace(0.0, t.size[0], 33)))
    n = len(k)
    return Modes(omega=np.sqrt(scene.environment.gravity * k * np.tanh(k * t.fill_depth)), kind=("sloshing",) * n,
                 free_surface_share=np.ones(n), shapes=shapes)


def _face_modes(scene: Scene, t, n: int) -> Modes:
    """The face-normal element's modes (liquid/face/element.py): the circulation modes, all at zero
    frequency, are left out and counted (`Modes.circulation`); shapes are nodal fields, each node the
    mean of its elements' displacements there."""
    tm = t.geometry.mesh(t.fill_depth, t.mesh)
    model = build_face_liquid(tm.nodes, tm.elements, tm.depth, t.fluid.density, t.fluid.sound_speed,
                              scene.environment.gravity)
    if t.wall_spec is not None:       # the liquid and its elastic walls together (kinds add "wall")
        return face_tank_modes(build_face_tank_with_walls(t, model), n=n)
    fm = face_modes(model, n)
    shapes = model.nodal_fields(fm.fluxes).reshape(len(fm.omega), -1)
    return Modes(omega=fm.omega, kind=fm.kind, free_surface_share=fm.free_surface_share, shapes=shapes,
                 circulation=fm.circulation)


def structure_modes(scene: Scene, structure: str, n: int = 10):
    """The first n modes of a flexible structure held at its attachment face (the vessel, or the
    structure it is attached to, held fixed): `StructureModes(omega, kind, shares, shapes)`; each mode
    named by the pattern of its cross-sections that holds most of its kinetic energy (bending along
    an axis, torsion, axial, other)."""
    st = scene.structure(structure)
    m = build_structure(st.size, st.mesh, st.material.young, st.material.poisson, st.material.density)
    return clamped_modes(m, face_nodes(m.nodes, m.size, st.attach), n=n)
