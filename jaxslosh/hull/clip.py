"""A closed triangulated surface cut by a plane, in pure JAX (PHYSICS section 5).

Triangles are an array (n, 3, 3): n triangles, 3 vertices, xyz; counter-clockwise seen from
outside, so that (b - a) x (c - a) points outward. The plane keeps the points with
normal . x <= offset ("below"; for the sea, `normal` is the inertial up direction written in the
frame of the triangles and `offset` the height of the water plane along it).

Each triangle's part below the plane is at most a quadrilateral, returned as two triangles: the
array of pieces has the static shape (n, 2, 3, 3) whatever the pose (zero-area pieces pad it), so
functions of it jit and vmap. The pieces' vertices move continuously with the pose (no panel is
switched on or off by its centroid), and every division is guarded twice (`jnp.where` on the
denominator, not only on the result), so gradients stay finite when a vertex lies on the plane.

Volume integrals over the closed body's part below the plane come from surface integrals over the
wetted pieces alone: in the plane's coordinate zeta = normal . x - offset (zero on the plane,
negative below), every field used is proportional to zeta, so its flux through the unmeshed lid
vanishes:
    V        = int_S zeta (n . N) dS                         (div(zeta n) = 1)
    int zeta = int_S zeta^2 / 2 (n . N) dS                   (div(zeta^2/2 n) = zeta)
    int x    = int_S x zeta (n . N) dS - n int zeta dV       (div(x_a zeta n) = x_a + n_a zeta)
with N the outward unit normal of the surface, n the plane's unit normal. The integrands are
polynomials of degree <= 2 on each flat piece; the three-edge-midpoint rule integrates them exactly.
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np

__all__ = ["clip_below", "submerged", "submerged_and_cut", "pressure_force_moment", "integrate_pressure",
           "area_vectors", "triangulate_quads", "MIDPOINT_RULE"]

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


def clip_below(tris, normal, offset):
    """Each triangle's part where normal . x <= offset, as two triangles: (n, 2, 3, 3).

    One vertex below: the triangle (v0, I01, I02) and a zero piece; two below: the quadrilateral
    (I01, v1, v2, I20) as two triangles; three: the triangle and a zero piece; none: two zero
    pieces (v0 is the odd vertex, after a rotation of the vertex order that keeps orientation).
    When a vertex reaches the plane the two cases it separates give the same region, so the pieces
    are continuous in the vertices, the normal and the offset."""
    tris = jnp.asarray(tris)
    n, off = _unit_plane(normal, offset)
    d = tris @ n - off                                        # (n, 3) signed heights
    below = d <= 0.0
    count = below.sum(axis=1)
    # the odd vertex: the one below when one is, the one above when two are
    odd = jnp.where(count == 1, jnp.argmax(below, axis=1), jnp.argmax(~below, axis=1))
    order = (odd[:, None] + jnp.arange(3)[None, :]) % 3       # rotation: orientation is kept
    v = jnp.take_along_axis(tris, order[:, :, None], axis=1)
    dd = jnp.take_along_axis(d, order, axis=1)
    v0, v1, v2 = v[:, 0], v[:, 1], v[:, 2]
    d0, d1, d2 = dd[:, 0], dd[:, 1], dd[:, 2]
    cut = (count == 1) | (count == 2)
    # in the cut cases d0 lies strictly on the other side of d1 and d2 (or on the plane with them
    # above), so d0 - d1 and d0 - d2 do not vanish; elsewhere the safe 1 keeps gradients finite
    den1 = jnp.where(cut, d0 - d1, 1.0)
    den2 = jnp.where(cut, d0 - d2, 1.0)
    t1 = jnp.where(cut, d0 / den1, 0.0)[:, None]
    t2 = jnp.where(cut, d0 / den2, 0.0)[:, None]
    i01 = v0 + t1 * (v1 - v0)
    i02 = v0 + t2 * (v2 - v0)
    zero = jnp.zeros_like(v)
    one_a = jnp.stack([v0, i01, i02], axis=1)
    two_a = jnp.stack([i01, v1, v2], axis=1)
    two_b = jnp.stack([i01, v2, i02], axis=1)
    c = count[:, None, None]
    a = jnp.where(c == 3, tris, jnp.where(c == 1, one_a, jnp.where(c == 2, two_a, zero)))
    b = jnp.where(c == 2, two_b, zero)
    return jnp.stack([a, b], axis=1)


def area_vectors(tris):
    """Outward area vectors (..., 3) of triangles (..., 3, 3): half the cross product."""
    return 0.5 * jnp.cross(tris[..., 1, :] - tris[..., 0, :], tris[..., 2, :] - tris[..., 0, :])


def _quadrature_points(tris, rule=MIDPOINT_RULE):
    lam, w = rule
    return jnp.einsum("qk,...kx->...qx", lam, tris), w


def submerged(tris, normal, offset):
    """(volume, first_moment (3,)) of the closed body's part where normal . x <= offset.

    `tris` the closed surface (n, 3, 3), outward; the centre of that volume is first_moment /
    volume. Exact (up to rounding) for any pose: see the module's docstring for the fields."""
    volume, moment, _ = submerged_and_cut(tris, normal, offset)
    return volume, moment


def submerged_and_cut(tris, normal, offset):
    """(volume, first_moment (3,), cut_area) below the plane: `submerged` and the area of the
    body's section by the plane (the unmeshed lid), which is d volume / d offset. The lid's area
    comes from the wetted pieces too: the flux of the constant field n through the closed clipped
    body vanishes, so the lid's n . N dS (= dS) is minus the wetted pieces' sum."""
    n, off = _unit_plane(normal, offset)
    pieces = clip_below(tris, n, off).reshape(-1, 3, 3)
    an = area_vectors(pieces) @ n                                  # (n . N) dS per piece
    x, w = _quadrature_points(pieces)                              # (m, 3, 3), (3,)
    zeta = x @ n - off                                             # (m, 3)
    volume = jnp.sum(an * (zeta @ w))
    m_zeta = jnp.sum(an * ((0.5 * zeta ** 2) @ w))
    m_x = jnp.einsum("m,mq,mqx,q->x", an, zeta, x, w)
    return volume, m_x - n * m_zeta, -jnp.sum(an)


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
