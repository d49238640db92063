"""Hexahedral meshes of 2-D tank sections, two elements thick, for comparing the liquid elements
with the 2-D reference (tests/sloshing_reference.py): the section in the y-z plane, extruded along x.

Written for the tests (no jaxslosh imports): a structured grid of the section, rows at the levels
``zs``, each row's columns at ``s_rows[k]`` (so that rows can follow sloping walls), the cells
``keep`` kept (a U-tube drops the cells above its duct), and thin plates as slits: the nodes on a
plate doubled, one copy for the cells on each side, except at its free edge.
"""
from __future__ import annotations

import numpy as np


def section_hex(s_rows, zs, keep=None, slits=(), thickness=0.2, nx=2):
    """(nodes (N, 3), elements (E, 8)) of the section extruded along x over [0, thickness].

    ``s_rows`` (nz + 1, ny + 1) the y of each row's nodes; ``zs`` (nz + 1,) the rows' levels;
    ``keep`` (nz, ny) bool; ``slits``: (j, k0, k1, tips) a plate along column j from row k0 to row
    k1, ``tips`` the ends (k0 and/or k1) that are free edges (not doubled)."""
    s_rows = np.asarray(s_rows, dtype=float)
    zs = np.asarray(zs, dtype=float)
    nz, ny = s_rows.shape[0] - 1, s_rows.shape[1] - 1
    keep = np.ones((nz, ny), dtype=bool) if keep is None else np.asarray(keep, dtype=bool)
    # 2-D node ids, then doubled ones
    ids = np.arange((nz + 1) * (ny + 1)).reshape(nz + 1, ny + 1)
    pts = [np.stack([s_rows.ravel(), np.repeat(zs, ny + 1)], axis=1)]
    cell_nodes = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], axis=-1)  # (nz, ny, 4) ccw
    count = ids.size
    for j, k0, k1, tips in slits:
        for k in range(k0, k1 + 1):
            if k in tips:
                continue
            node = ids[k, j]
            right = np.zeros((nz, ny), dtype=bool)
            right[:, j:] = True
            cell_nodes = np.where((cell_nodes == node) & right[:, :, None], count, cell_nodes)
            pts.append(pts[0][[node]])
            count += 1
    p2 = np.concatenate(pts)
    quads = cell_nodes[keep]
    used = np.unique(quads)
    remap = np.full(len(p2), -1)
    remap[used] = np.arange(len(used))
    p2, quads = p2[used], remap[quads]
    n2 = len(p2)
    xs = np.linspace(0.0, thickness, nx + 1)
    nodes = np.concatenate([np.column_stack([np.full(n2, x), p2]) for x in xs])
    hexes = []
    for i in range(nx):
        a, b = i * n2, (i + 1) * n2
        q = quads
        hexes.append(np.stack([q[:, 0] + a, q[:, 0] + b, q[:, 1] + b, q[:, 1] + a,
                               q[:, 3] + a, q[:, 3] + b, q[:, 2] + b, q[:, 2] + a], axis=1))
    elements = np.concatenate(hexes)
    X = nodes[elements]
    vol = np.einsum("ei,ei->e", X[:, 1] - X[:, 0], np.cross(X[:, 3] - X[:, 0], X[:, 4] - X[:, 0]))
    flip = vol < 0
    elements[flip] = elements[flip][:, [0, 3, 2, 1, 4, 7, 6, 5]]
    return nodes, elements


def _spread(lo, hi, n):
    return lo + (hi - lo) * np.arange(n + 1) / n


def u_tube_hex(length, reservoir, duct, fill, ny, nz, thickness=0.2, nx=2):
    """A U-tube's liquid (sloshing_reference.u_tube): ``ny`` elements along its length and ``nz``
    up the fill, spread over the reservoirs, the duct and the levels in proportion to their size
    (a row at the duct's roof, columns at the reservoirs' inner walls)."""
    nr = max(1, round(ny * reservoir / length))
    nd = ny - 2 * nr
    ys = np.concatenate([_spread(0, reservoir, nr), _spread(reservoir, length - reservoir, nd)[1:],
                         _spread(length - reservoir, length, nr)[1:]])
    kd = max(1, round(nz * duct / fill))
    zs = np.concatenate([_spread(0, duct, kd), _spread(duct, fill, nz - kd)[1:]])
    keep = np.ones((nz, ny), dtype=bool)
    keep[kd:, nr:nr + nd] = False
    return section_hex(np.tile(ys, (nz + 1, 1)), zs, keep, thickness=thickness, nx=nx)


def hopper_baffle_hex(b, chamfer, fill, baffle_s, baffle_height, ny, nz, thickness=0.2, nx=2):
    """A section b wide with 45-degree bottom chamfers ``chamfer`` wide and high (hopper), filled
    to ``fill``, and a standing plate at s = ``baffle_s`` (on the flat bottom) ``baffle_height``
    high. Rows at the chamfers' top and the plate's edge; each row's nodes spread between its walls
    and the plate's column, in proportion to the widths at the bottom row."""
    levels = sorted({0.0, chamfer, baffle_height, fill})
    counts = np.diff(levels) / fill * nz
    counts = np.maximum(1, np.round(counts).astype(int))
    counts[np.argmax(counts)] += nz - counts.sum()
    zs = np.concatenate([[0.0]] + [_spread(a, c, m)[1:] for a, c, m in zip(levels[:-1], levels[1:], counts)])
    kb = int(np.argmin(np.abs(zs - baffle_height)))
    nl = max(1, round(ny * baffle_s / b))
    rows = []
    for z in zs:
        lo = chamfer * (1 - z / chamfer) if z < chamfer else 0.0
        hi = b - lo
        rows.append(np.concatenate([_spread(lo, baffle_s, nl), _spread(baffle_s, hi, ny - nl)[1:]]))
    slits = [(nl, 0, kb, (kb,))]
    return section_hex(np.array(rows), zs, slits=slits, thickness=thickness, nx=nx)
