"""Clipping a closed triangulated surface by a plane (jaxslosh/hull/clip.py): volumes and centroids
against closed forms and an independent convex-hull computation, continuity as a vertex crosses the
plane, gradients against finite differences, vmap."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from jaxslosh.hull.box import box_surface
from jaxslosh.hull.clip import clip_below, pressure_force_moment, submerged

SIZE = np.array([3.0, 2.0, 1.5])
_submerged = jax.jit(submerged)


def _rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _box_halfspace_closed_form(size, n, t):
    """Volume of {x in [0, size]: n . x <= t} and the integral of (t - n . x) over it, by
    inclusion-exclusion over the corners (every n_i nonzero): sum (-1)^|e| (t - n . v_e)_+^k / (k! prod n)."""
    V = W = 0.0
    for e in range(8):
        bits = np.array([(e >> i) & 1 for i in range(3)])
        s = max(t - n @ (bits * size), 0.0)
        V += (-1) ** bits.sum() * s ** 3 / 6.0
        W += (-1) ** bits.sum() * s ** 4 / 24.0
    p = np.prod(n)
    return V / p, W / p


def _convex_clip(corners, n, t, edges=None):
    """Independent: the convex polytope (corners below) + (edge crossings), its volume and
    centroid from scipy's hull, split into tetrahedra about an inner point. `edges` (k, 2) index
    pairs (default: every pair, which adds points inside the cut but none outside it)."""
    d = corners @ n - t
    if edges is None:
        edges = np.array([(i, j) for i in range(len(corners)) for j in range(i + 1, len(corners))])
    i, j = edges[:, 0], edges[:, 1]
    cross = d[i] * d[j] < 0
    i, j = i[cross], j[cross]
    cuts = corners[i] + (d[i] / (d[i] - d[j]))[:, None] * (corners[j] - corners[i])
    pts = np.concatenate([corners[d <= 0], cuts])
    h = ConvexHull(pts)
    o = pts.mean(axis=0)
    T = pts[h.simplices]                                       # (f, 3, 3): tetrahedra (o, a, b, c)
    v = np.abs(np.linalg.det(T - o)) / 6.0
    return v.sum(), (v[:, None] * (T.sum(axis=1) + o) / 4.0).sum(axis=0)


def _icosphere(level):
    t = (1 + 5 ** 0.5) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
         [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
         [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    tris = np.array([[v[i] for i in tri] for tri in f], float)
    tris /= np.linalg.norm(tris, axis=-1, keepdims=True)
    for _ in range(level):
        a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
        ab, bc, ca = [(p + q) / np.linalg.norm(p + q, axis=-1, keepdims=True) for p, q in ((a, b), (b, c), (c, a))]
        tris = np.concatenate([np.stack(x, axis=1) for x in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    return tris


def test_box_at_random_poses_matches_closed_form_and_convex_hull():
    rng = np.random.default_rng(0)
    tris = box_surface([0, 0, 0], SIZE, n=2)
    for _ in range(12):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        corners = np.array([[(e >> i) & 1 for i in range(3)] for e in range(8)]) * SIZE
        h = corners @ n
        t = rng.uniform(h.min() + 0.05, h.max() - 0.05)
        V, M = (np.asarray(x) for x in _submerged(jnp.asarray(tris), jnp.asarray(n), t))
        # the closed form needs n_i > 0: mirror the box (x -> size - x) along negative components
        flip = n < 0
        n_pos = np.abs(n)
        t_pos = t + (n_pos * SIZE * flip).sum()
        Vc, Wc = _box_halfspace_closed_form(SIZE, n_pos, t_pos)
        assert V == pytest.approx(Vc, rel=1e-12)
        assert t * V - n @ M == pytest.approx(Wc, rel=1e-10, abs=1e-12)     # the moment along n
        Vh, Mh = _convex_clip(corners, n, t)
        assert V == pytest.approx(Vh, rel=1e-10)
        np.testing.assert_allclose(M / V, Mh / Vh, atol=1e-10)
        # after a rigid motion of both the body and the plane, the same volume, the centroid moved
        R, p = _rotation(rng), rng.normal(size=3)
        V2, M2 = _submerged(jnp.asarray(tris @ R.T + p), jnp.asarray(R @ n), t + (R @ n) @ p)
        assert float(V2) == pytest.approx(V, rel=1e-12)
        np.testing.assert_allclose(np.asarray(M2) / float(V2), R @ (M / V) + p, atol=1e-10)


def test_sphere_caps():
    """A fine icosphere (the polyhedron, so against its convex hull exactly, and against the sphere's
    caps to the polyhedron's own error)."""
    tris = _icosphere(4)
    verts, idx = np.unique(tris.reshape(-1, 3).round(14), axis=0, return_inverse=True)
    idx = idx.reshape(-1, 3)
    edges = np.unique(np.sort(np.concatenate([idx[:, [0, 1]], idx[:, [1, 2]], idx[:, [2, 0]]]), axis=1), axis=0)
    rng = np.random.default_rng(1)
    c = np.array([0.3, -0.2, 0.5])
    for h in (-0.7, 0.0, 0.45):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        t = n @ c + h
        V, M = (np.asarray(x) for x in _submerged(jnp.asarray(tris + c), jnp.asarray(n), t))
        Vh, Mh = _convex_clip(verts + c, n, t, edges)
        assert V == pytest.approx(Vh, rel=1e-10)
        np.testing.assert_allclose(M / V, Mh / Vh, atol=1e-10)
        # the cap of height a = 1 + h below the plane: V = pi a^2 (3 - a) / 3, centroid on the axis
        a = 1 + h
        Vs = np.pi * a * a * (3 - a) / 3
        zs = -3 * (2 - a) ** 2 / (4 * (3 - a))       # centroid from the centre, along n
        assert V == pytest.approx(Vs, rel=0.01)
        np.testing.assert_allclose(M / V, c + zs * n, atol=0.005)


def test_pressure_force_is_archimedes():
    rng = np.random.default_rng(2)
    tris = jnp.asarray(box_surface([0, 0, 0], SIZE))
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    t = 0.5 * (box_surface([0, 0, 0], SIZE).reshape(-1, 3) @ n).mean()
    point = jnp.array([0.2, 0.4, 0.9])
    # both in one program (eager, each operation of the clipping would compile on its own)
    (F, Mo), (V, S) = jax.jit(lambda n, t: (pressure_force_moment(tris, n, t, point, rho=1000.0, g=9.81),
                                            submerged(tris, n, t)))(jnp.asarray(n), t)
    np.testing.assert_allclose(F, 1000 * 9.81 * V * n, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(Mo, np.cross(S / V - point, 1000 * 9.81 * V * n), rtol=1e-12, atol=1e-8)


def test_continuity_as_a_vertex_crosses_the_plane():
    """The volume and moment through a corner's height: a jump would show as a difference far above
    the slope times the step."""
    tris = jnp.asarray(box_surface([0, 0, 0], SIZE))
    n = jnp.asarray(np.array([0.3, 0.5, 0.81]) / np.linalg.norm([0.3, 0.5, 0.81]))
    corner = jnp.asarray(SIZE * np.array([1, 0, 0]))
    t0 = float(corner @ n)
    f = jax.jit(lambda t: submerged(tris, n, t))
    for eps in (1e-4, 1e-7):
        Va, Ma = f(t0 - eps)
        Vb, Mb = f(t0 + eps)
        V0, _ = f(t0)
        area = (f(t0 + 1e-3)[0] - f(t0 - 1e-3)[0]) / 2e-3      # the lid's area, the slope
        assert abs(float(Vb - Va)) < 2 * eps * float(area) * 1.01
        assert abs(float(V0 - Va)) <= eps * float(area) * 1.01
        assert np.max(np.abs(np.asarray(Mb - Ma))) < 2 * eps * float(area) * 10


def test_gradients_agree_with_finite_differences_and_are_finite_on_the_plane():
    rng = np.random.default_rng(3)
    R = _rotation(rng)
    tris = jnp.asarray(box_surface([-1.5, -1, -0.75], [1.5, 1, 0.75]) @ R.T)

    @jax.jit
    def f(x):                       # a scalar of the pose: plane normal (3), offset, a shift of the body
        V, M = submerged(tris + x[4:7], x[:3], x[3])
        return V + 0.3 * M[0] - 0.7 * M[2]

    x0 = jnp.asarray([0.1, 0.2, 0.97, 0.05, 0.02, -0.03, 0.01])
    g = np.asarray(jax.grad(f)(x0))
    h = 1e-6
    fd = np.array([(f(x0.at[i].add(h)) - f(x0.at[i].add(-h))) / (2 * h) for i in range(7)])
    np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-8)
    # a vertex (and a whole face) exactly on the plane: finite gradients
    flat = jnp.asarray(box_surface([0, 0, 0], SIZE))
    # (jitted: eager, each operation of the clipping's gradient would compile on its own)
    g = jax.jit(jax.grad(lambda t: submerged(flat, jnp.array([0.0, 0.0, 1.0]), t)[0] + 0.0))(jnp.asarray(SIZE[2]))
    assert np.isfinite(g)
    gt = jax.jit(jax.grad(lambda tr: submerged(tr, jnp.array([0.0, 0.0, 1.0]), 0.0)[1].sum()))(flat)
    assert np.all(np.isfinite(np.asarray(gt)))


def test_vmap_and_static_shapes():
    tris = jnp.asarray(box_surface([0, 0, 0], SIZE))
    assert clip_below(tris, jnp.array([0.0, 0.0, 1.0]), 0.5).shape == (12, 2, 3, 3)
    ts = jnp.linspace(-0.5, 2.0, 7)
    V, M = jax.jit(jax.vmap(lambda t: submerged(tris, jnp.array([0.0, 0.0, 1.0]), t)))(ts)
    np.testing.assert_allclose(V, SIZE[0] * SIZE[1] * np.clip(ts, 0, SIZE[2]), atol=1e-12)
    np.testing.assert_allclose(M[:, 2], SIZE[0] * SIZE[1] * np.clip(ts, 0, SIZE[2]) ** 2 / 2, atol=1e-12)
