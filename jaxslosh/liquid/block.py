"""The deformable block of the vessel's frame as the assembly receives it from a liquid model's
builder (nodal/build.py, face/stack.py, modal/build.py): the liquid term and what comes with it
(where each tank sits, the rotation penalty, the structures carried in the vessel's frame)."""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np

from ..fem.mesh import grid_nodes
from .base import AbstractLiquid


class LiquidBlock(NamedTuple):
    """The deformable block of the vessel's frame and what comes with it."""
    liquid: AbstractLiquid
    tanks: tuple = ()                   # TankBlock per tank
    penalty: Optional[tuple] = None     # (K_dt, K_tt) of the stabilized element's rotation penalty
    Kg: Optional[jax.Array] = None      # (6, n, n) centrifugal stiffening of vessel-frame structures
    Kg_offset: int = 0                  # on the unknowns Kg_offset ... (the structures', after the liquid's)
    vstructs: tuple = ()                # VesselFrameStructure per structure in the vessel's frame
    carried: tuple = ()                 # rigid_part of the elastic walls and vessel-frame structures
    # What a model whose unknowns are not a mesh's nodal field makes from the scene (the multimodal
    # one, multimodal/build.py): the tanks a result keeps (its surface meshes), each tank's rows of
    # `surface_heave`, the probes' weights on its coordinates (P, nf, 3) and its modal damping.
    # None: the finite-element block's, read from `tanks` and the probes' nodal weights
    kept: Optional[tuple] = None
    tops: Optional[tuple] = None
    probe_rows: Optional[jax.Array] = None
    damping: Optional[tuple] = None     # (ModalDamping or None, TankDamping per damped tank)

    def result_tanks(self) -> tuple:
        """The tanks a result keeps the fields of (TankBlock, or the multimodal ModalSurface)."""
        return self.tanks if self.kept is None else self.kept

    def surfaces(self) -> tuple:
        """Per tank, the indices of its free surface that the liquid's `surface_heave` reads (the
        run's validity watch): a tank block's top nodes, in the stacked nodal field."""
        if self.tops is not None:
            return self.tops
        return tuple(jnp.asarray(t.node_offset + np.flatnonzero(np.isclose(t.nodes[:, 2], t.nodes[:, 2].max())))
                     for t in self.tanks)

    def probe_modal(self, weights):
        """The probes' weights on the liquid's coordinates (P, m, 3) from their nodal `weights`, or
        None where the probes read the nodal field (AbstractLiquid.probe_modal)."""
        return self.liquid.probe_modal(weights) if self.probe_rows is None else self.probe_rows


class TankBlock(NamedTuple):
    """Where one tank's liquid sits in the stacked liquid block, for probes and result fields."""
    name: str
    node_offset: int
    nodes: np.ndarray      # (N_t, 3) tank-local
    elements: np.ndarray   # (E_t, 8) tank-local node indices
    model: object          # the tank's element model (nodal/model.NodalModel, face/element.FaceModel)


class VesselFrameStructure(NamedTuple):
    """A structure with frame = "vessel" inside the vessel-frame block: its nodes (block-local from
    its min corner) start at `node_offset`."""
    name: str
    node_offset: int
    nodes: np.ndarray
    elements: np.ndarray


def rigid_part(Ms, r, n0=0):
    """(mass, first moment, inertia about the origin) of the nodes n0... of a block with scalar mass Ms
    (consistent: the inertia a rigid motion of the nodes has in the dynamics)."""
    Ms = np.asarray(Ms)[n0:, n0:]
    r = np.asarray(r)
    mn = Ms.sum(axis=1)
    G = r.T @ Ms @ r                                                 # sum_ij Ms_ij r_i r_j^T
    return float(mn.sum()), mn @ r, np.trace(G) * np.eye(3) - G


def host_block(t, m, offset) -> TankBlock:
    """The tank's block for probes and result fields, with the mesh at the scene's fill depth: a
    probe keeps its place relative to the mesh whatever a traced fill depth says."""
    if m.geometry is not None or (not m.traced and m.depth == t.fill_depth):
        nodes = np.asarray(m.nodes)
    else:
        nodes = grid_nodes((t.size[0], t.size[1], t.fill_depth), m.mesh)
    return TankBlock(t.name, offset, nodes, np.asarray(m.elements), m)


def slots(free, n_nodes):
    """nodal/term.NodalLiquid.slot: the position of each of the 3 n_nodes nodal dofs among the free ones,
    len(free) where held."""
    slot = np.full(3 * n_nodes, len(free), dtype=np.int32)
    slot[np.asarray(free)] = np.arange(len(free), dtype=np.int32)
    return jnp.asarray(slot)
