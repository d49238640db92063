"""Liquid in an elastic tank: the liquid block extended by the walls' elastic hexahedra.

The walls (structure.build_walls: an open box one element thick, tied to the hull at its attachment
face, by default the underside of the bottom) are built into the hull, so they share the vessel's
floating frame: their attachment face moves rigidly with it, their deformation is measured in it,
and they need no projector (the held face removes their rigid modes). The liquid slides along them:
at every wetted node the wall-normal component of the liquid's displacement equals the wall's
(normal-only ties), the tangential ones are free. These ties are linear and constant in the body
frame, so they are imposed exactly in null-space form: the liquid's wall-normal dof is slaved to the
wall's dof of the same direction at the coincident node (a 0/1 map T from the block's unknowns to all
nodal dofs, full = T z). That is the elimination of the normal-only Lagrange multipliers: the
multiplier of a tie, the normal force between liquid and wall, is the liquid's share of the slaved
dof's residual. Mass and stiffness on the unknowns are T^T M T and T^T K T: constant, symmetric,
factored once like the rigid tank's.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl

from ..fem.mesh import box_elements
from .modes import classify
from ..fem.structure import assemble_cells


@dataclass(frozen=True, eq=False)
class WallModel:
    """The walls of an elastic tank: an open box (bottom and four sides, no lid) of hexahedra one
    element thick, around the cavity [0, a] x [0, b] x [0, H] (tank-local coordinates). The node
    planes inside the cavity's span include the liquid mesh's, so that every liquid node on a wetted
    wall coincides with a wall node (`wetted`)."""
    nodes: np.ndarray          # (Nw, 3) tank-local
    elements: np.ndarray       # (Ew, 8)
    mass: np.ndarray           # (Nw, Nw) scalar
    stiffness: np.ndarray      # (3Nw, 3Nw)
    held: np.ndarray           # (Nw,) bool: the attachment face, tied to the hull
    total_mass: float


def _planes(inner, t):
    return np.concatenate([[-t], inner, [inner[-1] + t]])


def wall_planes(size, fill_depth, liquid_mesh, thickness, wall_mesh=None):
    """(xs, ys, zs) node planes of the wall shell: the liquid mesh's planes (refined by the integer
    factors that `wall_mesh` implies along x and y), in z the liquid's planes up to the fill depth
    and planes of the same spacing above it up to the tank height, plus the outer planes at -t (and
    a + t, b + t). Raises ValueError when `wall_mesh` does not nest the liquid mesh."""
    a, b, H = (float(s) for s in size)
    nx, ny, nz = liquid_mesh
    h = float(fill_depth)
    if wall_mesh is None:
        mx, my = nx, ny
        dz = h / nz
        above = int(np.ceil((H - h) / dz - 1e-9)) if H > h * (1 + 1e-12) else 0
        zs = np.concatenate([np.linspace(0.0, h, nz + 1), np.linspace(h, H, above + 1)[1:]]) if above else \
            np.linspace(0.0, h, nz + 1)
    else:
        mx, my, mz = (int(m) for m in wall_mesh)
        if mx % nx or my % ny:
            raise ValueError(f"the wall mesh's counts along x and y ({mx}, {my}) must be multiples of the "
                             f"liquid mesh's ({nx}, {ny})")
        zs = np.linspace(0.0, H, mz + 1)
        liquid_z = np.linspace(0.0, h, nz + 1)
        if np.min(np.abs(zs[None, :] - liquid_z[:, None]), axis=1).max() > 1e-9 * H:
            raise ValueError(f"the wall mesh's {mz} layers over the height {H:g} m put no node plane at some of the "
                             f"liquid's {nz} layers up to {h:g} m")
    xs = np.linspace(0.0, a, mx + 1)
    ys = np.linspace(0.0, b, my + 1)
    t = float(thickness)
    return _planes(xs, t), _planes(ys, t), np.concatenate([[-t], zs])


def shell_mesh(size, fill_depth, liquid_mesh, thickness, wall_mesh=None, attach="z-"):
    """(nodes, elements, element sizes, held) of the open box shell (see WallModel), no assembly."""
    xs, ys, zs = wall_planes(size, fill_depth, liquid_mesh, thickness, wall_mesh)
    a, b, H = (float(s) for s in size)
    all_nodes = np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), axis=-1).reshape(-1, 3)
    elements = box_elements(len(xs) - 1, len(ys) - 1, len(zs) - 1)
    lo, hi = all_nodes[elements[:, 0]], all_nodes[elements[:, 6]]       # opposite corners
    c = 0.5 * (lo + hi)
    solid = ~((c[:, 0] > 0) & (c[:, 0] < a) & (c[:, 1] > 0) & (c[:, 1] < b) & (c[:, 2] > 0))  # the cavity, open top
    elements, hs = elements[solid], (hi - lo)[solid]
    used = np.unique(elements)
    renum = -np.ones(len(all_nodes), dtype=int)
    renum[used] = np.arange(len(used))
    nodes, elements = all_nodes[used], renum[elements]
    axis = "xyz".index(attach[0])
    target = (xs, ys, zs)[axis][0 if attach[1] == "-" else -1]
    held = np.abs(nodes[:, axis] - target) <= 1e-9 * max(a, b, H)
    return nodes, elements, hs, held


def build_walls(size, fill_depth, liquid_mesh, thickness, young, poisson, density, wall_mesh=None,
                attach="z-") -> WallModel:
    nodes, elements, hs, held = shell_mesh(size, fill_depth, liquid_mesh, thickness, wall_mesh, attach)
    K, Ms = assemble_cells(nodes, elements, hs, young, poisson, density)
    return WallModel(nodes=nodes, elements=elements, mass=Ms, stiffness=K, held=held, total_mass=float(Ms.sum()))


@dataclass(frozen=True, eq=False)
class TankWithWalls:
    """Host-side coupled model of one elastic tank (tank-local coordinates)."""
    liquid: object             # liquid.NodalModel
    walls: object              # structure.WallModel
    nodes: np.ndarray          # (N_l + N_w, 3): liquid nodes, then wall nodes
    mass: np.ndarray           # (N, N) scalar: block diagonal
    dof_map: np.ndarray        # (3N,) index of each nodal dof's unknown, -1 where it is held (zero)
    rep: np.ndarray            # (nf,) one nodal dof per unknown (the wall's for a slaved pair)
    stiffness: np.ndarray      # (nf, nf) T^T K T
    mass_ff: np.ndarray        # (nf, nf) T^T kron(mass, I3) T
    rotation_coupling: object  # (nf, 3) T^T of the liquid's d-theta penalty block, or None
    n_liquid_unknowns: int     # the first unknowns are the liquid's own (interior and tangential)

    @property
    def nf(self) -> int:
        return int(self.rep.shape[0])

    def T(self) -> np.ndarray:
        n = self.dof_map.shape[0]
        T = np.zeros((n, self.nf))
        on = self.dof_map >= 0
        T[np.flatnonzero(on), self.dof_map[on]] = 1.0
        return T


def build_tank_with_walls(tank, liquid_model) -> TankWithWalls:
    """Couple a tank's liquid model (built for rigid walls: its wall-normal dofs are the ones `free`
    marks False) with its elastic walls."""
    ws = tank.wall_spec
    m = liquid_model
    w = build_walls(tank.size, tank.fill_depth, tank.mesh, ws.thickness, ws.material.young, ws.material.poisson,
                    ws.material.density, wall_mesh=ws.mesh)
    Nl, Nw = m.n_nodes, w.nodes.shape[0]
    lfree = np.asarray(m.free).reshape(Nl, 3)
    dof_map = -np.ones(3 * (Nl + Nw), dtype=int)
    k = 0
    rep = []
    for n, c in zip(*np.nonzero(lfree)):                       # the liquid's own unknowns first
        dof_map[3 * n + c] = k
        rep.append(3 * n + c)
        k += 1
    n_liquid = k
    for n in range(Nw):                                        # the walls' unknowns
        if w.held[n]:
            continue
        for c in range(3):
            dof_map[3 * (Nl + n) + c] = k
            rep.append(3 * (Nl + n) + c)
            k += 1
    # slave each wall-normal liquid dof to the coincident wall node's dof of that direction
    scale = max(tank.size)
    lnodes = np.asarray(m.nodes)
    for n, c in zip(*np.nonzero(~lfree)):
        d = np.linalg.norm(w.nodes - lnodes[n], axis=1)
        j = int(np.argmin(d))
        if d[j] > 1e-9 * scale:
            raise ValueError(f"liquid node {lnodes[n]} has no wall node")
        dof_map[3 * n + c] = dof_map[3 * (Nl + j) + c]        # -1 if the wall node is held
    rep = np.array(rep, dtype=int)
    T = np.zeros((3 * (Nl + Nw), k))
    on = dof_map >= 0
    T[np.flatnonzero(on), dof_map[on]] = 1.0
    Kfull = np.zeros((3 * (Nl + Nw), 3 * (Nl + Nw)))
    Kfull[:3 * Nl, :3 * Nl] = np.asarray(m.stiffness)
    Kfull[3 * Nl:, 3 * Nl:] = w.stiffness
    Ms = np.zeros((Nl + Nw, Nl + Nw))
    Ms[:Nl, :Nl] = np.asarray(m.mass)
    Ms[Nl:, Nl:] = w.mass
    K = T.T @ Kfull @ T
    M = T.T @ np.kron(Ms, np.eye(3)) @ T
    C = None
    if m.rotation_coupling is not None:
        Cfull = np.zeros((3 * (Nl + Nw), 3))
        Cfull[:3 * Nl] = np.asarray(m.rotation_coupling)
        C = T.T @ Cfull
    return TankWithWalls(liquid=m, walls=w, nodes=np.concatenate([lnodes, w.nodes]), mass=Ms, dof_map=dof_map,
                         rep=rep, stiffness=0.5 * (K + K.T), mass_ff=0.5 * (M + M.T), rotation_coupling=C,
                         n_liquid_unknowns=n_liquid)


@dataclass(frozen=True, eq=False)
class TankModes:
    omega: np.ndarray
    kind: tuple                 # "sloshing" | "wall" | "acoustic" | "circulation" | "spurious"
    free_surface_share: np.ndarray
    wall_share: np.ndarray      # share of the potential energy in the walls' strain
    shapes: np.ndarray          # (n, nf) on the block's unknowns, mass-normalised


def tank_modes(tw: TankWithWalls, n=10) -> TankModes:
    """Modes of the liquid and its walls together (the hull held still), classified: "wall" when
    the walls' strain holds most of the potential energy, else as the liquid's (modes.py)."""

    n = int(min(n, tw.nf))
    # the lowest modes as the largest of M x = (1 / lambda) K x: stiff walls put eigenvalues many
    # orders above the sloshing band, and eigh(K, M) resolves the low ones only to eps times the
    # largest, while eigh(M, K) resolves them to eps times themselves (K is positive definite: the
    # walls are held at their attachment, the liquid's circulation held by its penalty)
    mu, X = sl.eigh(tw.mass_ff, tw.stiffness, subset_by_index=[tw.nf - n, tw.nf - 1])
    lam, X = 1.0 / mu[::-1], X[:, ::-1]
    omega = np.sign(lam) * np.sqrt(np.abs(lam))
    T = tw.T()
    full = (T @ X).T                                            # (n, 3N)
    Nl = tw.liquid.n_nodes
    Kw = tw.walls.stiffness
    wall_e = np.einsum("ij,jk,ik->i", full[:, 3 * Nl:], Kw, full[:, 3 * Nl:])
    total = np.einsum("ij,jk,ik->i", X.T, tw.stiffness, X.T)
    wall_share = np.clip(wall_e / np.where(total > 0, total, np.inf), 0.0, 1.0)
    share, kinds = classify(tw.liquid, full[:, :3 * Nl])
    # the liquid's measures are shares of its own energy: rescale to the whole
    share = share * (1.0 - wall_share)
    kinds = tuple("wall" if ws > 0.5 else k for k, ws in zip(kinds, wall_share))
    return TankModes(omega, kinds, share, wall_share, X.T)
