"""The box hull's closed surface (SPEC section 8: `[vessel.hull]` length, beam, draft, kg, depth)."""
from __future__ import annotations

import numpy as np

# the 8 corners of the unit cube by bits (x, y, z), and its 6 faces counter-clockwise from outside
_CORNERS = np.array([[(i >> 0) & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=float)
_FACES = np.array([
    [0, 2, 3, 1],   # z-
    [4, 5, 7, 6],   # z+
    [0, 1, 5, 4],   # y-
    [2, 6, 7, 3],   # y+
    [0, 4, 6, 2],   # x-
    [1, 3, 7, 5],   # x+
])


def box_surface(lo, hi, n=1):
    """The closed surface of the box [lo, hi] as (12 n^2, 3, 3) triangles, outward normals; each
    face cut into n x n squares (a finer surface only for tests and figures: the clipping is exact
    on any)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    s = np.linspace(0.0, 1.0, n + 1)
    tris = []
    for f in _FACES:
        c = _CORNERS[f]                        # 4 corners of the face, counter-clockwise
        o, u, v = c[0], c[1] - c[0], c[3] - c[0]
        for i in range(n):
            for j in range(n):
                p = [o + s[i] * u + s[j] * v, o + s[i + 1] * u + s[j] * v,
                     o + s[i + 1] * u + s[j + 1] * v, o + s[i] * u + s[j + 1] * v]
                tris += [[p[0], p[1], p[2]], [p[0], p[2], p[3]]]
    return lo + np.asarray(tris) * (hi - lo)


def box_hull(length, beam, kg, depth):
    """The box hull in the vessel frame (origin at the COG): x from -length/2 to length/2 (the COG
    amidships), y from -beam/2 to beam/2 (on the centre line), z from the keel at -kg to the deck
    at depth - kg."""
    return box_surface([-length / 2, -beam / 2, -kg], [length / 2, beam / 2, depth - kg])
