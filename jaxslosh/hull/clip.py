"""A closed triangulated surface cut by a plane, in pure JAX (docs/guide/large-angles.md).

Triangles are an array (n, 3, 3): n triangles, 3 vertices, xyz; counter-clockwise seen from
outside, so that (b - a) x (c - a) points outward. The plane keeps the points with
normal . x <= offset ("below"; for the sea, `normal` is the inertial up direction written in the
frame of the triangles and `offset` the height of the water plane along it).

Each triangle's part below the plane is at most a quadrilateral, returned as two triangles: the
array of pieces has the static shape (n, 2, 3, 3) whatever the pose (zero-area pieces pad it), so
functions of it jit and vmap. The pieces' vertices move continuously with the pose (no panel is
switched on or off by its centroid), and every division is guarded twice (`jnp.where` on the
denominator, not only on the result), so gradients stay finite when a vertex lies on the plane.

The integrals run in a coordinate-major layout, `panels(tris)` (3, 3, n) (vertex, coordinate,
triangle): every step is an elementwise operation on arrays (n,) and a single sum over n at the
end, which XLA fuses into a few loops over the triangles. Laid out (n, 3, 3), the same arithmetic
is a few dozen separate passes (gathers, small products) that the CPU does not vectorise, each
clipping costing several times more.

The displaced volume and its first moment come from the divergence theorem on the closed clipped
body (wetted pieces and the lid, the body's section by the plane):
    V     = 1/3 int x . N dS           (div x = 3)
    int x = 1/4 int x (x . N) dS       (div (x_a x) = 4 x_a)
On a flat piece x . N is constant (the panel's), so each wetted piece gives its area times that
constant (times its centroid); on the lid x . N = offset, so the lid adds offset A / 3 and
offset s / 4 with its area A and first moment s. The lid is the polygon that the cut segments
bound: a fan from the point offset n of the plane gives A, s and the second moment J, each cut
triangle adding one triangle of the fan (a planar polygon's integrals from its oriented boundary).
A wetted part is a whole panel (all below), the small triangle at the odd vertex (one below), or
the whole panel less it (two below): the small triangle has the panel's normal and its area
scales by t1 t2 (its edges are t1 and t2 of the panel's). Exact (up to rounding) for any pose.
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np

__all__ = ["clip_below", "submerged", "submerged_and_cut", "pressure_force_moment", "integrate_pressure",
           "area_vectors", "triangulate_quads", "panels", "cross3", "lid_integrals", "cut_pieces", "MIDPOINT_RULE"]

#: barycentric points and weights (summing to 1) of the degree-2 rule on a triangle (edge midpoints);
#: NumPy constants, not jnp arrays: a module imported before the entry point switches on float64
#: would otherwise keep them float32 (1e-8 relative error in every clipped integral)
MIDPOINT_RULE = (np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]]),
                 np.array([1.0, 1.0, 1.0]) / 3.0)


def _unit_plane(normal, offset):
    normal = jnp.asarray(normal)
    s = jnp.linalg.norm(normal)
    return normal / s, jnp.asarray(offset) / s


def triangulate_quads(quads):
    """(m, 4, 3) quadrilaterals (counter-clockwise from outside) as (2m, 3, 3) triangles."""
    quads = jnp.asarray(quads)
    a = quads[:, [0, 1, 2]]
    b = quads[:, [0, 2, 3]]
    return jnp.concatenate([a, b], axis=0)


def panels(tris):
    """Triangles (n, 3, 3) in the coordinate-major layout (3, 3, n): vertex, coordinate, triangle."""
    return jnp.moveaxis(jnp.asarray(tris), 0, -1)


def _dot(x, u):
    """x . u over the coordinate axis (second to last) of x (..., 3, n); u (3,) or (3, n)."""
    return x[..., 0, :] * u[0] + x[..., 1, :] * u[1] + x[..., 2, :] * u[2]


def cross3(a, b, xp=jnp):
    """a x b for coordinate-major vectors (3, ...)."""
    return xp.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _split(P, d, xp=jnp):
    """The cut of each triangle of P (3, 3, n) with signed heights d (3, n): its vertices rotated so
    that v0 is the odd one (below when one is, above when two are; orientation kept), their
    heights, the fractions t1, t2 of the edges v0 v1 and v0 v2 where the plane cuts them (0 when it
    does not), and the flags (one below, two below, three below)."""
    below = d <= 0.0
    count = below.sum(axis=0)
    one, two = count == 1, count == 2
    odd = xp.where(one, below, ~below)
    s0, s1 = odd[0], odd[1]

    def rotate(x):
        x0, x1, x2 = x[0], x[1], x[2]
        return (xp.where(s0, x0, xp.where(s1, x1, x2)), xp.where(s0, x1, xp.where(s1, x2, x0)),
                xp.where(s0, x2, xp.where(s1, x0, x1)))
    v, dd = rotate(P), rotate(d)
    cut = one | two
    # in the cut cases d0 lies strictly on the other side of d1 and d2 (or on the plane with them
    # above), so d0 - d1 and d0 - d2 do not vanish; elsewhere the safe 1 keeps gradients finite
    t1 = xp.where(cut, dd[0] / xp.where(cut, dd[0] - dd[1], 1.0), 0.0)
    t2 = xp.where(cut, dd[0] / xp.where(cut, dd[0] - dd[2], 1.0), 0.0)
    return v, t1, t2, (one, two, count == 3)


def cut_pieces(P, u, off):
    """Each triangle's part where u . x <= off as two triangles, coordinate-major: ((a0, a1, a2),
    (b0, b1, b2), wa, wb): the vertices (3, n) of the two pieces and their weights (n,) (1 where
    the piece is part of the wetted surface, 0 where it pads). u (3,) or per triangle (3, n), off ()
    or (n,), u of unit length. One vertex below: the triangle (v0, I01, I02); two: the
    quadrilateral (I01, v1, v2, I02) as two triangles; three: the triangle itself."""
    v, t1, t2, (one, two, three) = _split(P, _dot(P, u) - off)
    v0, v1, v2 = v
    i01 = v0 + t1 * (v1 - v0)
    i02 = v0 + t2 * (v2 - v0)
    a = (jnp.where(two, i01, v0), jnp.where(one, i01, v1), jnp.where(one, i02, v2))
    dtype = P.dtype
    return a, (i01, v2, i02), (one | two | three).astype(dtype), two.astype(dtype)


def lid_integrals(P, u, off, second=True, xp=jnp):
    """(V, m, A, s, J) of the closed surface P (3, 3, n) (`panels`) cut by the plane u . x = off (u
    of unit length): the volume below and its first moment int x dV, the area, first moment and
    second moment int x x^T dA of the lid; J is None when `second` is False. See the module's
    docstring. `xp=np` evaluates it in NumPy (concrete inputs: a build step's hull at rest, which
    op by op in JAX compiled some sixty tiny programs)."""
    v, t1, t2, (one, two, three) = _split(P, _dot(P, u) - off, xp)
    v0, v1, v2 = v
    p0, p1, p2 = P[0], P[1], P[2]
    k = _dot(p0, cross3(p1 - p0, p2 - p0, xp)) / 6.0           # 1/3 (x . N) dS over the whole panel
    # the small triangle at v0 has the fraction t1 t2 of the panel's area; two below: the panel less it
    small = xp.where(one, t1 * t2, xp.where(two, -t1 * t2, 0.0))
    whole = (two | three).astype(P.dtype)
    i01 = v0 + t1 * (v1 - v0)
    i02 = v0 + t2 * (v2 - v0)
    # the lid's boundary runs i02 -> i01 where one vertex is below, i01 -> i02 where two are; the
    # fan triangle (o, start, end) from o = off u has the area u . (start x end) / 2
    half = xp.where(one, 0.5, xp.where(two, -0.5, 0.0))
    a = half * _dot(cross3(i02, i01, xp), u)
    o = off * u
    ends = i01 + i02
    rows = [((whole + small) * k)[None], (whole * (p0 + p1 + p2) + small * (v0 + i01 + i02)) * (0.25 * k),
            a[None], a * ends]
    if second:
        pairs = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
        f = o[:, None] + ends
        rows.append(xp.stack([a * (i01[i] * i01[j] + i02[i] * i02[j] + f[i] * f[j]) for i, j in pairs]))
    # the sums over the triangles as one product with ones: XLA's CPU reduction of the stacked rows
    # along n cost as much as the clipping before it (a quarter of the call with the second moments)
    rows = xp.concatenate(rows)
    tot = rows @ xp.ones(rows.shape[-1], rows.dtype)
    A = tot[4]
    s = (A * o + tot[5:8]) / 3.0
    V = tot[0] + off * A / 3.0
    m = tot[1:4] + off * s / 4.0
    if not second:
        return V, m, A, s, None
    j = tot[8:14]
    J = (xp.stack([xp.stack([j[0], j[3], j[4]]), xp.stack([j[3], j[1], j[5]]), xp.stack([j[4], j[5], j[2]])])
         + A * xp.outer(o, o)) / 12.0
    return V, m, A, s, J


def clip_below(tris, normal, offset):
    """Each triangle's part where normal . x <= offset, as two triangles: (n, 2, 3, 3).

    One vertex below: the triangle (v0, I01, I02) and a zero piece; two below: the quadrilateral
    (I01, v1, v2, I20) as two triangles; three: the triangle (its vertices rotated) and a zero
    piece; none: two zero pieces (v0 is the odd vertex, after a rotation of the vertex order that
    keeps orientation). When a vertex reaches the plane the two cases it separates give the same
    region, so the pieces are continuous in the vertices, the normal and the offset."""
    n, off = _unit_plane(normal, offset)
    a, b, wa, wb = cut_pieces(panels(tris), n, off)
    pieces = jnp.stack([jnp.stack(a) * wa, jnp.stack(b) * wb])      # (2, 3, 3, n)
    return jnp.moveaxis(pieces, -1, 0)


def area_vectors(tris):
    """Outward area vectors (..., 3) of triangles (..., 3, 3): half the cross product."""
    return 0.5 * jnp.cross(tris[..., 1, :] - tris[..., 0, :], tris[..., 2, :] - tris[..., 0, :])


def _quadrature_points(tris, rule=MIDPOINT_RULE):
    lam, w = rule
    return jnp.einsum("qk,...kx->...qx", lam, tris), w


def submerged(tris, normal, offset):
    """(volume, first_moment (3,)) of the closed body's part where normal . x <= offset.

    `tris` the closed surface (n, 3, 3), outward; the centre of that volume is first_moment /
    volume. Exact (up to rounding) for any pose: see the module's docstring."""
    n, off = _unit_plane(normal, offset)
    V, m, _, _, _ = lid_integrals(panels(tris), n, off, second=False)
    return V, m


def submerged_and_cut(tris, normal, offset):
    """(volume, first_moment (3,), cut_area) below the plane: `submerged` and the area of the
    body's section by the plane (the lid), which is d volume / d offset."""
    n, off = _unit_plane(normal, offset)
    V, m, A, _, _ = lid_integrals(panels(tris), n, off, second=False)
    return V, m, A


def integrate_pressure(pieces, pressure, point, rule=MIDPOINT_RULE):
    """Force and moment about `point` of a pressure on surface pieces (..., 3, 3), outward:
    F = -int p N dS, M = -int (x - point) x p N dS. `pressure` maps points (..., 3) to values
    (...); the rule (barycentric points, weights summing to one) must integrate p (x - point)
    exactly for the result to be exact."""
    pieces = jnp.asarray(pieces).reshape(-1, 3, 3)
    a = area_vectors(pieces)                                       # (m, 3)
    x, w = _quadrature_points(pieces, rule)                        # (m, q, 3)
    p = pressure(x)                                                # (m, q)
    pw = p * w
    force = -jnp.einsum("mq,mx->x", pw, a)
    r = x - jnp.asarray(point)
    moment = -jnp.sum(jnp.cross(jnp.einsum("mq,mqx->mx", pw, r), a), axis=0)
    return force, moment


def pressure_force_moment(tris, normal, offset, point, rho=1025.0, g=9.81):
    """Force and moment about `point` of the still-water pressure p = rho g (-zeta) on the part of
    the closed surface below the plane (zeta = normal . x - offset, the depth below it negated):
    in the frame of the triangles. By the divergence theorem these are the buoyancy rho g V normal
    acting at the centre of buoyancy; the lid, where p = 0, adds nothing."""
    n, off = _unit_plane(normal, offset)
    pieces = clip_below(tris, n, off)
    return integrate_pressure(pieces, lambda x: -rho * g * (x @ n - off), point)
