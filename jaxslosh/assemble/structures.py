"""Flexible structures in their own floating frames (physics/structures.py), from the scene: each
tied at its `attach` face to an interface frame that the vessel (or another structure) is tied to."""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax.numpy as jnp
import numpy as np

from ..fem.mesh import box_mesh, face_nodes
from ..fem.structure import assemble, box_element, build_structure, centrifugal_stiffness
from ..physics.structures import Body, Interface, Side, Structures
from ..scene.types import Scene


class StructureBlock(NamedTuple):
    """Host-side data of one structure: its model (structure.StructureModel) and where its modal
    coordinates sit in the stacked eta."""
    name: str
    index: int
    eta_offset: int
    model: object


def build_structures(scene: Scene):
    """Each structure in its own floating frame (origin at its COG), tied at its `attach` face to an
    interface frame that the vessel is tied to as well (localized multipliers on both sides)."""
    bodies, interfaces, blocks, models = [], [], [], {}
    offset = 0
    own = [st for st in scene.structures if st.frame == "own"]
    for i, st in enumerate(own):
        mat = st.material
        m = build_structure(st.size, st.mesh, mat.young, mat.poisson, mat.density)
        models[st.name] = (i, m, np.asarray(st.origin, dtype=float))
        Kg = None
        if st.stiffening == "centrifugal":   # spin about axes through the vessel's COG, modal form
            held = np.zeros(m.n_nodes, dtype=bool)
            held[face_nodes(m.nodes, m.size, st.attach)] = True
            sizes = np.tile(np.asarray([a / n for a, n in zip(m.size, m.mesh)]), (m.elements.shape[0], 1))
            Kg = jnp.asarray(np.stack([m.Phi.T @ k @ m.Phi for k in centrifugal_stiffness(
                m.nodes, m.elements, sizes, m.stiffness, m.mass, held, mat.young, mat.poisson,
                axis_point=-np.asarray(st.origin, dtype=float))]))
        bodies.append(Body(r=jnp.asarray(m.r), Ms=jnp.asarray(m.mass), Phi=jnp.asarray(m.Phi),
                           omega2=jnp.asarray(m.omega ** 2), mass=jnp.asarray(m.total_mass),
                           c0=jnp.asarray(models[st.name][2] + m.cog), Kg=Kg))
        blocks.append(StructureBlock(st.name, i, offset, m))
        offset += m.Phi.shape[1]
    for i, st in enumerate(own):
        _, m, origin = models[st.name]
        nodes = face_nodes(m.nodes, m.size, st.attach)
        points = origin[None, :] + m.nodes[nodes]           # vessel frame, from the vessel's COG
        if st.attach_to is None:                             # tied to the vessel
            other = Side(-1, jnp.asarray(nodes), jnp.asarray(points))
            m_ref = m.total_mass
        else:                                                # tied to another structure's coincident nodes
            j, mo, oo = models[st.attach_to]
            theirs = oo[None, :] + mo.nodes
            match = np.argmin(np.linalg.norm(points[:, None, :] - theirs[None, :, :], axis=2), axis=1)
            other = Side(j, jnp.asarray(match), jnp.asarray(points))
            m_ref = min(m.total_mass, mo.total_mass)
        L_ref = float(max(max(st.size), np.abs(points).max()))
        interfaces.append(Interface(sides=(other, Side(i, jnp.asarray(nodes), jnp.asarray(points))),
                                    m_ref=jnp.asarray(m_ref), L_ref=L_ref))
    return Structures(bodies=tuple(bodies), interfaces=tuple(interfaces)), tuple(blocks)


class HeldStructure(NamedTuple):
    """A structure with frame = "vessel" as the vessel-frame block takes it (the nodal liquid's
    liquid/nodal/build.py walls_block, the face-normal one's liquid/face/build.py): its deformation in the
    vessel's frame on its nodal dofs, the attachment face held."""
    name: str
    origin: np.ndarray      # (3,) its min corner in the vessel frame
    nodes: np.ndarray       # (N, 3) block-local, from its min corner
    elements: np.ndarray    # (E, 8)
    mass: np.ndarray        # (N, N) scalar consistent mass
    stiffness: np.ndarray   # (n, n) on the free dofs
    free: np.ndarray        # (n,) the free dofs' indices in its node-major 3 N vector
    density: float
    Kg: Optional[list] = None   # 6 (n, n) centrifugal stiffness parts (stiffening = "centrifugal")


def held_structure(st) -> HeldStructure:
    """The hexahedra of a structure in the vessel's frame, held at its `attach` face; with
    `stiffening = "centrifugal"` the geometric stiffness of a spin about axes through the vessel's
    COG (fem/structure.py centrifugal_stiffness)."""
    mat = st.material
    nodes, elements = box_mesh(st.size, st.mesh)
    hs = tuple(a / n for a, n in zip(st.size, st.mesh))
    Ke, Mse = box_element(*hs, mat.young, mat.poisson, mat.density)
    Kfull, Ms = assemble(nodes, elements, Ke, Mse)
    held = np.zeros(nodes.shape[0], dtype=bool)
    held[face_nodes(nodes, st.size, st.attach)] = True
    free = np.flatnonzero(~np.repeat(held, 3))
    Kg = None
    if st.stiffening == "centrifugal":
        sizes = np.tile(np.asarray(hs), (elements.shape[0], 1))
        Kg = [k[np.ix_(free, free)] for k in centrifugal_stiffness(nodes, elements, sizes, Kfull, Ms, held, mat.young,
                                                                    mat.poisson, axis_point=-np.asarray(st.origin,
                                                                                                        dtype=float))]
    return HeldStructure(st.name, np.asarray(st.origin, dtype=float), nodes, elements, Ms, Kfull[np.ix_(free, free)],
                         free, float(mat.density), Kg)


def held_spin_stiffness(parts) -> Optional[np.ndarray]:
    """(6, n, n) the centrifugal stiffness of the held structures `parts` (stacked in order, their
    free dofs last among the unknowns), zero for those without; None when none has it."""
    if all(p.Kg is None for p in parts):
        return None
    n = sum(p.free.size for p in parts)
    Kg = np.zeros((6, n, n))
    off = 0
    for p in parts:
        k = p.free.size
        if p.Kg is not None:
            for c in range(6):
                Kg[c, off:off + k, off:off + k] = p.Kg[c]
        off += k
    return Kg
