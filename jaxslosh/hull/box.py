"""The box hull's closed surface (docs/guide/large-angles.md: `[vessel.hull]` length, beam, draft, kg, depth)."""
from __future__ import annotations

import numpy as np


def _grid(a, b, na, nb):
    """Triangles of the rectangle spanned by vectors a, b (from the origin) in na x nb cells,
    counter-clockwise about a x b."""
    s = np.linspace(0.0, 1.0, na + 1)
    t = np.linspace(0.0, 1.0, nb + 1)
    P = s[:, None, None] * a + t[None, :, None] * b           # (na+1, nb+1, 3)
    p00, p10, p01, p11 = P[:-1, :-1], P[1:, :-1], P[:-1, 1:], P[1:, 1:]
    t1 = np.stack([p00, p10, p11], axis=-2).reshape(-1, 3, 3)
    t2 = np.stack([p00, p11, p01], axis=-2).reshape(-1, 3, 3)
    return np.concatenate([t1, t2])


def box_surface(lo, hi, n=1):
    """The closed surface of the box [lo, hi] as triangles (m, 3, 3), outward normals, faces in the
    order z-, z+, y-, y+, x-, x+; `n` cells along every edge, or (nx, ny, nz) along x, y and z (the
    clipping is exact on any; the wave pressure's quadrature wants panels small against the wave
    length)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    nx, ny, nz = (int(n),) * 3 if np.ndim(n) == 0 else (int(k) for k in n)
    e = np.diag(hi - lo)
    ex, ey, ez = e[0], e[1], e[2]
    return np.concatenate([
        lo + _grid(ey, ex, ny, nx),                # z-
        lo + ez + _grid(ex, ey, nx, ny),           # z+
        lo + _grid(ex, ez, nx, nz),                # y-
        lo + ey + _grid(ez, ex, nz, nx),           # y+
        lo + _grid(ez, ey, nz, ny),                # x-
        lo + ex + _grid(ey, ez, ny, nz),           # x+
    ])


def box_hull(length, beam, kg, depth, n=1):
    """The box hull in the vessel frame (origin at the COG): x from -length/2 to length/2 (the COG
    amidships), y from -beam/2 to beam/2 (on the centre line), z from the keel at -kg up to the deck
    at depth - kg; `n` as `box_surface`."""
    return box_surface([-length / 2, -beam / 2, -kg], [length / 2, beam / 2, depth - kg], n)
