"""The mesh of a tank whose y-z section is the same along x: the box and the prismatic tank (a box
whose section has its bottom and top corners cut by chamfers, width along y and height along z),
with or without baffles. Functions of the numbers (size, chamfers, baffles), shared by geometry/box.py
and geometry/prismatic.py.

Layer k of the mesh sits at a height chosen so that every kink of the section (the chamfers' ends,
a baffle's edge) lies on a layer, each band between kinks with two layers or more, the layers
thinner toward the surface for the face-normal element (`_heights`); across, the nodes of a layer are spread evenly between the
section's walls at that height. Chamfers that meet at the centre line give a V bottom: the bottom
row of nodes of each x station then merges into one node (those elements are wedges, hexahedra with
a collapsed face). Baffles are thin plates across the tank on a plane of the mesh, standing on the
bottom or hanging from the roof: the mesh's nodes on the plate are doubled, one for each side, so
the liquid slides along both faces and flows round the plate's free edge.
"""
from __future__ import annotations

import numpy as np

from ..fem.mesh import box_elements, count_nodes, grid_index
from ..fem.shapes import BAND_LAYERS, TankMesh, breaks, finish, merge_coincident, surface_layers
from ..fem.slip import FEATURE_ANGLE

#: a box's section: no corner cut
NO_CHAMFERS = ((0.0, 0.0), (0.0, 0.0))


def section_mesh(size, chamfers, baffles, h: float, counts: tuple, graded: bool = True) -> TankMesh:
    """The liquid at rest of a box or prismatic tank filled to h on counts = (nx, ny, nz); `graded`:
    layers thinner toward the surface where the section has kinks (AbstractShape.mesh)."""
    nx, ny, nz = counts
    nodes = _layered(size, chamfers, baffles, h, counts, graded)
    elements = box_elements(nx, ny, nz)
    pairs = _extra_pairs(size, chamfers, baffles, h, counts, nodes)
    nodes, elements = _baffles(size, baffles, counts, nodes, elements)
    nodes, elements = merge_coincident(nodes, elements, count_nodes(counts))
    return finish(nodes, elements, counts, h, pairs)


def section_walls(size, chamfers, z):
    """(y_lo, y_hi) of the section at height z (a box: (0, b))."""
    a, b, H = size
    (cw, ch), (tw, th) = chamfers
    lo = 0.0
    if ch > 0 and z < ch:
        lo = cw * (1.0 - z / ch)
    if th > 0 and z > H - th:
        lo = max(lo, tw * (z - (H - th)) / th)
    return lo, b - lo


def section_outline(size, chamfers) -> list:
    """The section at both ends and the lines along its corners."""
    a, b, H = size
    (cw, ch), (tw, th) = chamfers
    sec = [(cw, 0), (b - cw, 0), (b, ch), (b, H - th), (b - tw, H), (tw, H), (0, H - th), (0, ch)]
    sec = [p for i, p in enumerate(sec) if i == 0 or np.hypot(*np.subtract(p, sec[i - 1])) > 1e-12]
    sec = np.array(sec + [sec[0]], dtype=float)
    lines = [np.column_stack([np.full(len(sec), x), sec]) for x in (0.0, a)]
    return lines + [np.array([[0.0, y, z], [a, y, z]]) for y, z in sec[:-1]]


def _layered(size, chamfers, baffles, h, mesh, graded=True):
    nx, ny, nz = mesh
    a, b, H = size
    zb = [chamfers[0][1], H - chamfers[1][1]]          # a box's (0 and H) are no breaks
    xb = [bf.at for bf in baffles if bf.normal == "x"]
    yb = [bf.at for bf in baffles if bf.normal == "y"]
    for bf in baffles:
        zb.append(bf.height if bf.mount == "bottom" else H - bf.height)
    xs = breaks(0.0, a, xb, nx, "mesh[0]")
    zs = _heights(size, chamfers, baffles, h, zb, nz, graded)
    # across: a node on every y-baffle's plane (box tanks only), the same counts on every layer
    ys_rest = breaks(0.0, b, yb, ny, "mesh[1]")
    g = grid_index(nx, ny, nz)
    lo_hi = np.array([section_walls(size, chamfers, z) for z in zs])       # (nz + 1, 2)
    lo, hi = lo_hi[g[:, 2], 0], lo_hi[g[:, 2], 1]
    t = ys_rest[g[:, 1]] / b
    if yb:                                                 # box: the walls are at 0 and b on every layer
        y = ys_rest[g[:, 1]]
    else:
        y = lo + t * (hi - lo)
    z = zs[g[:, 2]]
    if low_hopper(size, chamfers, baffles, h):
        # the layers up to the top chamfer's kink (else the surface) follow the bottom: columns
        # between the vertical walls, each from the bottom up (see low_hopper)
        th = chamfers[1][1]
        zt = H - th if 0 < th and H - th < h else h
        below = z <= zt * (1.0 + 1e-12)
        y = np.where(below, t * b, y)
        zb = _hopper_bottom(size, chamfers, y)
        z = np.where(below, zb + (zt - zb) * z / zt, z)
    return np.stack([xs[g[:, 0]], y, z], axis=1)


def _heights(size, chamfers, baffles, h, kinks, nz, graded):
    """The layers' heights: with no kink below the surface (a plain box, a prismatic tank filled within
    its hopper) even; else graded toward the surface (fem/shapes.py `surface_layers`) or, not
    `graded`, spread in proportion to the bands between the kinks (`breaks`). With baffles (kinks at
    their edges) the face-normal element's layers are proportional too, two or more a band: graded
    toward the surface they thicken at a hanging plate's edge, where the flow is singular, and its
    first mode moves further off (docs/design/liquid-element.md, "Layers")."""
    inside = [z for z in kinks if 1e-9 * h < z < h * (1 - 1e-9)]
    if not graded or not inside:
        return breaks(0.0, h, kinks, nz, "mesh[2]")
    if baffles:
        return breaks(0.0, h, kinks, nz, "mesh[2]", BAND_LAYERS)
    lo, hi = section_walls(size, chamfers, h)
    below = max(inside)
    lo_k, hi_k = section_walls(size, chamfers, below)
    sloped = abs((hi - lo) - (hi_k - lo_k)) > 1e-9 * size[1]
    return surface_layers(h, inside, nz, hi - lo, sloped)


def _hopper_bottom(size, chamfers, y):
    """The height of the bottom (the hopper chamfers' floor) at y."""
    a, b, H = size
    cw, ch = chamfers[0]
    return ch * np.clip(np.maximum(1.0 - y / cw, (y - (b - cw)) / cw), 0.0, None)


def low_hopper(size, chamfers, baffles, h) -> bool:
    """A bottom chamfer flatter than slip.FEATURE_ANGLE, filled above its top, meshed with its layers
    following the bottom. Layered as a steeper hopper is (the bottom layer between the chamfers,
    its corner node on the kink), the element at the kink would have its floor and its chamfer face
    on one smooth wall (fem/slip.py), a node there sliding with no energy of the stabilized element,
    and the penalty that holds it (liquid_element.FLAT_CORNER_PENALTY) locks the liquid: an 8 m
    section with (1.0, 0.3) chamfers filled to 1.2 m had its first mode 41 % high on 2x16x4. With
    the layers following the bottom the kink's node is shared by two elements' floors, and the
    corner at the wall is a box's corner (no extra constraint: `_extra_pairs` adds none); a flat V
    bottom (chamfers meeting) is meshed the same way, with no collapsed row at its apex. Not with
    baffles (their edges lie on flat layers), nor filled to within the hopper (the surface would
    meet the floor in a collapsed column): those keep the layers flat."""
    cw, ch = chamfers[0]
    a, b, H = size
    return (0 < cw <= b / 2 * (1 + 1e-12) and 0 < ch < h and np.degrees(np.arctan2(ch, cw)) < FEATURE_ANGLE
            and ch < H - chamfers[1][1] and not baffles)


def _baffles(size, baffles, mesh, nodes, elements):
    """Double the nodes on each plate (below its free edge), the copies for the elements on its far side."""
    nx, ny, nz = mesh
    if not baffles:
        return nodes, elements
    g = grid_index(nx, ny, nz)
    H = size[2]
    ei = np.stack(np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"), -1).reshape(-1, 3)
    nodes = list(nodes)
    elements = elements.copy()
    scale = max(size)
    for bf in baffles:
        ax = 0 if bf.normal == "x" else 1
        coord = np.asarray(nodes)[:len(g), ax]
        z = np.asarray(nodes)[:len(g), 2]
        if bf.mount == "bottom":
            on = (np.abs(coord - bf.at) < 1e-9 * scale) & (z < bf.height - 1e-9 * scale)
        else:
            on = (np.abs(coord - bf.at) < 1e-9 * scale) & (z > H - bf.height + 1e-9 * scale)
        idx = np.flatnonzero(on)
        plane = g[idx[0], ax] if idx.size else None
        copy = {}
        for n in idx:
            copy[n] = len(nodes)
            nodes.append(np.asarray(nodes[n]))
        if plane is None:
            continue
        far = np.flatnonzero(ei[:, ax] == plane)
        for e in far:
            elements[e] = [copy.get(n, n) for n in elements[e]]
    return np.asarray(nodes), elements


def _extra_pairs(size, chamfers, baffles, h, mesh, nodes):
    """The box scheme's count of constraints, kept (liquid/nodal/model.py `_rotation_pairs`): the one-point
    divergence and the axial curl leave exactly as many free fields as the box has sloshing modes,
    so every wall constraint beyond the box's removes a whole mode (a pinned line of nodes inside
    the liquid locks it: measured, a 5 m tank's first mode went from 2.29 to 3.43 rad/s). Each line
    of nodes that a shape pins once more than the box does -- the foot of a standing baffle, the kink
    where a bottom (hopper) chamfer meets the vertical wall -- gets, for each element along it, the
    curl rows about the line's direction of the two elements across it replaced by their difference
    (one constraint less), as `_rotation_pairs` does for odd rows. (The kink of a top chamfer needs
    none: with one there, a spurious mode enters below the first; tests/fem/test_shapes.py.)"""
    nx, ny, nz = mesh
    eid = lambda i, j, k: (i * ny + j) * nz + k           # noqa: E731
    pairs = []
    for bf in baffles:
        if bf.mount != "bottom":
            continue                                   # a hanging plate pins nothing more than it doubles
        ax = 0 if bf.normal == "x" else 1
        coords = nodes[: (nx + 1) * (ny + 1) * (nz + 1)].reshape(nx + 1, ny + 1, nz + 1, 3)
        line = coords[:, 0, 0, 0] if ax == 0 else coords[0, :, 0, 1]
        p = int(np.argmin(np.abs(line - bf.at)))
        if ax == 0:
            pairs += [(eid(p - 1, j, 0), eid(p, j, 0), 1) for j in range(ny)]
        else:
            pairs += [(eid(i, p - 1, 0), eid(i, p, 0), 0) for i in range(nx)]
    a, b, H = size
    (cw, ch), (tw, th) = chamfers
    zs = nodes[: nz + 1, 2]
    kinks = [ch] if 0 < cw < b / 2 * (1 - 1e-12) and ch < h and not low_hopper(size, chamfers, baffles, h) else []
    for z in kinks:
        k = int(np.argmin(np.abs(zs - z)))
        if 0 < k < nz:
            pairs += [(eid(i, j, k - 1), eid(i, j, k), 0) for i in range(nx) for j in (0, ny - 1)]
    return pairs
