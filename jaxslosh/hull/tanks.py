"""Each tank's closed inner surface as triangles (n, 3, 3), outward, in tank-local coordinates (from
its inner min corner): the container a level liquid fills at any heel (stability.py cuts it by a
plane that holds the liquid's volume).

* box: its six faces;
* prismatic: the y-z section with its chamfers, extruded along x;
* cylinder: a polygon of CYLINDER_SIDES sides of the circle's area (so the container holds the
  circle's volume), extruded along its axis;
* mesh: the boundary of the liquid's hexahedra at rest, with the walls that meet its free surface
  continued vertically up to the tank's height (size z): the file describes the liquid, not the
  tank above it (a mesh whose liquid fills its size to the top cannot shift).
Baffles are left out: the liquid is taken to communicate over and under them (a plate that cuts the
surface off at a large heel holds liquid on its high side, which this does not see)."""
from __future__ import annotations

import numpy as np

from ..fem.shapes import read_mesh
from ..fem.slip import boundary

#: sides of the polygon that stands for a cylinder's circle (area kept exact; the centroid of a
#: level segment is within (pi / sides)^2 / 3 of the circle's, relative)
CYLINDER_SIDES = 128


def prism_surface(polygon, length):
    """The closed surface of a prism: `polygon` (k, 2) counter-clockwise in the (y, z) plane seen
    from +x, extruded from x = 0 to x = length; (4k - 4, 3, 3) triangles, outward."""
    P = np.asarray(polygon, float)
    k = len(P)
    Q = np.roll(P, -1, axis=0)
    a0 = np.column_stack([np.zeros(k), P])
    b0 = np.column_stack([np.zeros(k), Q])
    a1 = np.column_stack([np.full(k, length), P])
    b1 = np.column_stack([np.full(k, length), Q])
    sides = np.concatenate([np.stack([a0, b0, b1], axis=1), np.stack([a0, b1, a1], axis=1)])
    fan = np.arange(1, k - 1)
    end = np.stack([a1[np.zeros(k - 2, int)], a1[fan], a1[fan + 1]], axis=1)       # x = length: +x
    start = np.stack([a0[np.zeros(k - 2, int)], a0[fan + 1], a0[fan]], axis=1)     # x = 0: -x
    return np.concatenate([sides, end, start])


def cyclic(tris, axis):
    """A prism built along x turned to lie along `axis` by a cyclic permutation of the coordinates
    (a rotation: orientation kept)."""
    if axis == "x":
        return tris
    if axis == "y":                  # (w, u, v) -> y = w, z = u, x = v
        return tris[..., [2, 0, 1]]
    return tris[..., [1, 2, 0]]      # z = w, x = u, y = v


def prismatic_section(size, chamfers):
    """The y-z section of a box or prismatic tank, counter-clockwise seen from +x."""
    _, b, H = size
    (cw, ch), (tw, th) = chamfers
    sec = [(cw, 0), (b - cw, 0), (b, ch), (b, H - th), (b - tw, H), (tw, H), (0, H - th), (0, ch)]
    out = []
    for p in sec:
        if not out or np.hypot(p[0] - out[-1][0], p[1] - out[-1][1]) > 1e-12 * max(b, H):
            out.append(p)
    if np.hypot(out[0][0] - out[-1][0], out[0][1] - out[-1][1]) <= 1e-12 * max(b, H):
        out.pop()
    return np.array(out, float)


def circle(center, radius, sides=CYLINDER_SIDES):
    """A regular polygon of the circle's area, counter-clockwise."""
    t = 2 * np.pi * np.arange(sides) / sides
    r = radius * np.sqrt(2 * np.pi / (sides * np.sin(2 * np.pi / sides)))
    return np.column_stack([center[0] + r * np.cos(t), center[1] + r * np.sin(t)])


def tank_surface(tank) -> np.ndarray:
    """The tank's closed inner surface (n, 3, 3), outward, tank-local (module docstring): its shape's
    (jaxslosh/geometry)."""
    return tank.geometry.surface()


def mesh_surface(path, height):
    nodes, elements = read_mesh(path)
    top = float(nodes[:, 2].max())
    bd = boundary(nodes, elements, top)
    walls = nodes[bd.wall_faces]                      # (w, 4, 3) outward
    lid = nodes[bd.top_faces].copy()                  # (t, 4, 3) facing up
    rise = max(height - top, 0.0)
    quads = [walls]
    if rise > 0:
        # the free surface's boundary edges (once among the top faces), each with the orientation
        # it has in its top face; continued up as a vertical wall facing out
        f = bd.top_faces
        edges = np.concatenate([f[:, [i, (i + 1) % 4]] for i in range(4)])
        key = np.sort(edges, axis=1)
        _, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        rim = edges[counts[inv.reshape(-1)] == 1]
        p, q = nodes[rim[:, 0]], nodes[rim[:, 1]]
        up = np.array([0.0, 0.0, rise])
        # the lid's edge p -> q runs counter-clockwise seen from above, the liquid on its left:
        # the wall (p, q, q + up, p + up) has the normal (q - p) x up, to the right: out
        quads.append(np.stack([p, q, q + up, p + up], axis=1))
        lid[..., 2] += rise
    quads.append(lid)
    Q = np.concatenate(quads)
    tris = np.concatenate([Q[:, [0, 1, 2]], Q[:, [0, 2, 3]]])
    area = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    return tris[area > 1e-14 * max(np.ptp(nodes, axis=0).max(), 1.0) ** 2]
