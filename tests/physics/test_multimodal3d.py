"""The three-dimensional multimodal liquid (liquid/multimodal/tank3d.py) of box tanks and upright circular
cylinders: linear frequencies against g k tanh(k h), the two-dimensional tank's coefficients where the
flow is planar, the integrals against SciPy's adaptive quadrature of the exact modes, the vortical
flows' curl and wall flux by finite differences, the kinetic energy against a direct quadrature of the
velocity field, and Galilean invariance."""
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, special

from jaxslosh.liquid.multimodal.modes import DiskBase
from jaxslosh.liquid.multimodal.term import modal_tank
from jaxslosh.liquid.multimodal.tank3d import box_tank3d, cylinder_tank

G = 9.81
Z3 = jnp.zeros(3)
GB = jnp.array([0.0, 0.0, -G])


@eqx.filter_jit
def _linear(t):
    z = jnp.zeros(t.n)
    r = lambda be, bdd: t.rows(Z3, Z3, be, z, Z3, Z3, bdd, GB)[2]  # noqa: E731
    return jax.jacfwd(lambda a: r(z, a))(z), jax.jacfwd(lambda be: r(be, z))(z)


_mass = eqx.filter_jit(lambda t, be: t.mass_matrix(be))


def _square():
    return box_tank3d(1.0, 1.0, 0.5, 1000.0, (-0.5, -0.5, -0.2), 5, D=0.9)


def _cylinder():
    return cylinder_tank(0.5, 0.4, 1000.0, (-0.5, -0.5, -0.2), 5, D=0.9)


def test_mode_sets_hold_the_swirling_pairs():
    assert _square().modes == ((1, 0), (0, 1), (1, 1), (2, 0), (0, 2))
    assert _cylinder().modes == ((1, 1, 0), (1, 1, 1), (2, 1, 0), (2, 1, 1), (0, 1, 0))
    # a count that splits a degenerate group takes the whole group
    assert box_tank3d(1.0, 1.0, 0.5, 1000.0, Z3, 1).modes == ((1, 0), (0, 1))


@pytest.mark.parametrize("make, k", [
    (_square, np.pi * np.array([1.0, 1.0, np.sqrt(2.0), 2.0, 2.0])),
    (lambda: box_tank3d(1.0, 0.6, 0.3, 1000.0, Z3, 4), None),
    (_cylinder, np.array([special.jnp_zeros(1, 1)[0]] * 2 + [special.jnp_zeros(2, 1)[0]] * 2
                         + [special.jnp_zeros(0, 1)[0]]) / 0.5),
])
def test_small_amplitude_frequencies_are_linear_theory(make, k):
    t = make()
    if k is None:        # L = 1, B = 0.6: (1, 0), (0, 1), (1, 1), (2, 0)
        k = np.pi * np.array([1.0, 1 / 0.6, np.hypot(1.0, 1 / 0.6), 2.0])
        k.sort()
    M, K = _linear(t)
    w = np.sort(np.sqrt(np.linalg.eigvals(np.linalg.solve(M, K)).real))
    h = float(t.h)
    np.testing.assert_allclose(w, np.sqrt(G * k * np.tanh(k * h)), rtol=5e-3)
    np.testing.assert_allclose(w, np.sqrt(G * k * np.tanh(k * h)), rtol=1e-9)


def test_planar_modes_are_the_two_dimensional_tank():
    """On the (i, 0) modes a box's liquid is the two-dimensional tank's (an independent code, its own
    quadrature): its mass matrix in surge, heave, pitch and the modes at a large deflection. Roll and
    yaw differ: the two-dimensional tank turns its liquid with the tank across its length."""
    o = (-0.3, -0.2, -0.1)
    t3 = box_tank3d(1.0, 0.4, 0.5, 1000.0, o, modes=[(1, 0), (2, 0), (3, 0)], D=0.8)
    t2 = modal_tank(1.0, 0.4, 0.5, 1000.0, o, 3, D=0.8)
    be = jnp.array([0.05, -0.02, 0.01])
    M3, M2 = np.asarray(_mass(t3, be)), np.asarray(_mass(t2, be))
    idx = [0, 1, 2, 4, 6, 7, 8]
    A, B = M3[np.ix_(idx, idx)], M2[np.ix_(idx, idx)]
    # the pitch inertia holds the vortical flow's series, truncated at fewer terms here
    assert A[3, 3] == pytest.approx(B[3, 3], rel=1e-4)
    A[3, 3] = B[3, 3]
    np.testing.assert_allclose(A, B, rtol=0, atol=1e-6 * np.abs(M2).max())


def _dblquad_liquid(f, kind, size, h_of, R=None):
    """SciPy's adaptive quadrature of f(x, y, z) over the liquid under z = h_of(x, y)."""
    if kind == "box":
        return integrate.tplquad(lambda z, y, x: f(x, y, z), 0.0, size[0], 0.0, size[1], 0.0,
                                 lambda x, y: h_of(x, y), epsabs=1e-11, epsrel=1e-9)[0]
    # polar: x = R + r cos t, y = R + r sin t
    return integrate.tplquad(lambda z, r, th: r * f(R + r * np.cos(th), R + r * np.sin(th), z), 0.0, 2 * np.pi,
                             0.0, R, 0.0, lambda th, r: h_of(R + r * np.cos(th), R + r * np.sin(th)),
                             epsabs=1e-11, epsrel=1e-9)[0]


@pytest.mark.parametrize("kind", ["box", "cylinder"])
def test_integrals_against_scipy_quadrature_of_the_exact_modes(kind):
    """A_n, A_nk and the first moment at a large, swirling deflection, the modes written out here
    from their closed forms (cosines; Bessel functions J_m(j'_m1 r / R))."""
    if kind == "box":
        t = box_tank3d(1.0, 0.7, 0.4, 1000.0, Z3, modes=[(1, 0), (0, 1), (1, 1)])
        modes = [lambda x, y, i=i, j=j: np.cos(i * np.pi * x) * np.cos(j * np.pi * y / 0.7)
                 for i, j in ((1, 0), (0, 1), (1, 1))]
        R = None
    else:
        t = cylinder_tank(0.5, 0.4, 1000.0, Z3, modes=[(1, 1, 0), (1, 1, 1), (0, 1, 0)])
        R = 0.5

        def bessel(m, c):
            z = special.jnp_zeros(m, 1)[0]
            return lambda x, y: (special.jv(m, z * np.hypot(x - R, y - R) / R) / special.jv(m, z)
                                 * (np.cos, np.sin)[c](m * np.arctan2(y - R, x - R)))
        modes = [bessel(1, 0), bessel(1, 1), bessel(0, 0)]
    beta = np.array([0.06, 0.04, -0.03])
    I = t.integrals(jnp.asarray(beta))
    k, h = np.asarray(t.k), 0.4
    H = lambda x, y: h + sum(b * f(x, y) for b, f in zip(beta, modes))  # noqa: E731
    phi = lambda n, x, y, z: modes[n](x, y) * np.cosh(k[n] * z) / np.cosh(k[n] * h)  # noqa: E731

    def grad(n, x, y, z, e=1e-6):
        return np.array([(phi(n, x + e, y, z) - phi(n, x - e, y, z)) / (2 * e),
                         (phi(n, x, y + e, z) - phi(n, x, y - e, z)) / (2 * e),
                         (phi(n, x, y, z + e) - phi(n, x, y, z - e)) / (2 * e)])
    size = np.asarray(t.size)
    assert float(I.An[0]) == pytest.approx(_dblquad_liquid(lambda x, y, z: phi(0, x, y, z), kind, size, H, R),
                                           rel=1e-7, abs=1e-10)
    for n, m in ((0, 0), (0, 1), (2, 1)):
        ref = _dblquad_liquid(lambda x, y, z: grad(n, x, y, z) @ grad(m, x, y, z), kind, size, H, R)
        assert float(I.Ank[n, m]) == pytest.approx(ref, rel=1e-6, abs=1e-8)
    ref = _dblquad_liquid(lambda x, y, z: x * y, kind, size, H, R)
    assert float(I.m2[0, 1]) == pytest.approx(ref, rel=1e-8)


@pytest.mark.parametrize("make", [_square, _cylinder])
def test_vortical_flows_make_the_rotation_irrotational_and_keep_to_the_walls(make):
    """curl w_l = -2 e_l inside (finite differences) and w_l . n = 0 on the walls, floor and roof."""
    t = make()
    L, B, D = (float(v) for v in (t.size[0], t.size[1], t.D))
    rng = np.random.default_rng(0)
    if t.base.name == "box":
        p = rng.uniform([0.1, 0.1, 0.1], [0.9 * L, 0.9 * B, 0.9 * D], (20, 3))
    else:
        r, th = 0.45 * rng.uniform(0.1, 0.9, 20), rng.uniform(0, 2 * np.pi, 20)
        p = np.stack([0.5 * L + r * np.cos(th), 0.5 * L + r * np.sin(th), rng.uniform(0.1, 0.9 * D, 20)], -1)
    w = lambda q: np.asarray(t.vortical(q[:, 0], q[:, 1], q[:, 2]))  # noqa: E731   (3, P, 3)
    e = 1e-5
    d = [(w(p + e * np.eye(3)[c]) - w(p - e * np.eye(3)[c])) / (2 * e) for c in range(3)]   # d/dx_c
    curl = np.stack([d[1][..., 2] - d[2][..., 1], d[2][..., 0] - d[0][..., 2], d[0][..., 1] - d[1][..., 0]], -1)
    np.testing.assert_allclose(curl, np.broadcast_to(-2.0 * np.eye(3)[:, None, :], curl.shape), atol=1e-4)
    # the walls
    s = rng.uniform(0.05, 0.95, (30, 2))
    if t.base.name == "box":
        walls = [(np.stack([np.zeros(30), s[:, 0] * B, s[:, 1] * D], -1), [1, 0, 0]),
                 (np.stack([s[:, 0] * L, np.full(30, B), s[:, 1] * D], -1), [0, 1, 0])]
    else:
        th = 2 * np.pi * s[:, 0]
        R = 0.5 * L
        walls = [(np.stack([R + R * np.cos(th), R + R * np.sin(th), s[:, 1] * D], -1),
                  np.stack([np.cos(th), np.sin(th), np.zeros(30)], -1))]
    walls.append((np.stack([0.1 + 0.3 * s[:, 0], 0.1 + 0.3 * s[:, 1], np.full(30, D)], -1), [0, 0, 1]))
    walls.append((np.stack([0.1 + 0.3 * s[:, 0], 0.1 + 0.3 * s[:, 1], np.zeros(30)], -1), [0, 0, 1]))
    for q, n in walls:
        flux = np.einsum("lpc,pc->lp", w(q), np.broadcast_to(np.asarray(n, float), q.shape))
        np.testing.assert_allclose(flux, 0.0, atol=2e-3)


@pytest.mark.parametrize("make", [_square, _cylinder])
def test_kinetic_energy_is_the_velocity_fields(make):
    """With the vessel's translation at rest, T = rho / 2 times the integral of |omega x r + grad phi +
    omega_l w_l|^2, R from the kinematic condition, by a finer tensor quadrature of its own."""
    t = make()
    beta = jnp.asarray([0.04, -0.03, 0.02, 0.01, -0.015])
    bd, om = jnp.asarray([0.3, -0.2, 0.1, 0.05, 0.2]), jnp.asarray([0.2, -0.1, 0.3])
    T = float(eqx.filter_jit(lambda t: t.kinetic(Z3, om, beta, bd))(t))
    R = np.asarray(t.rates(t.integrals(beta), bd, om))
    L = float(t.size[0])
    n = 40
    g, gw = np.polynomial.legendre.leggauss(n)
    if t.base.name == "box":
        X, Y = np.meshgrid(0.5 * L * (g + 1), 0.5 * L * (g + 1), indexing="ij")
        W = np.outer(0.5 * L * gw, 0.5 * L * gw)
    else:
        r = 0.25 * L * (g + 1)
        th = 2 * np.pi * np.arange(2 * n) / (2 * n)
        X, Y = 0.5 * L + np.outer(r, np.cos(th)), 0.5 * L + np.outer(r, np.sin(th))
        W = np.outer(0.25 * L * gw * r, np.full(2 * n, np.pi / n))
    X, Y, W = X.ravel(), Y.ravel(), W.ravel()
    F, Fx, Fy = t.base.values(t.modes, X, Y)
    H = float(t.h) + F @ np.asarray(beta)
    s, sw = 0.5 * (g + 1), 0.5 * gw
    Z = H[:, None] * s
    k, h = np.asarray(t.k), float(t.h)
    ch, sh = np.cosh(Z[..., None] * k) / np.cosh(k * h), np.sinh(Z[..., None] * k) / np.cosh(k * h)
    u = np.stack([(Fx[:, None] * ch) @ R, (Fy[:, None] * ch) @ R, (k * F[:, None] * sh) @ R], -1)
    r = np.stack([np.broadcast_to(X[:, None], Z.shape), np.broadcast_to(Y[:, None], Z.shape), Z], -1) + np.asarray(t.origin)
    u = u + np.cross(np.asarray(om), r) + np.einsum("l,lqsc->qsc", np.asarray(om),
                                                     np.asarray(t.vortical(X[:, None], Y[:, None], Z)))
    ref = 0.5 * float(t.rho) * np.einsum("q,s,qs,qsc,qsc->", W, sw, H[:, None] * np.ones_like(Z), u, u)
    # the tank's coarser depth quadrature resolves the vortical flows' short terms to about 1e-5
    assert T == pytest.approx(ref, rel=3e-5)


def test_uniform_motion_does_not_drive_sloshing():
    t = _cylinder()
    be, bd, bdd = jnp.array([0.05, 0.01, -0.02, 0.005, 0.01]), jnp.array([0.1, -0.2, 0.05, 0.0, 0.1]), jnp.zeros(5)
    rows = eqx.filter_jit(lambda t, V: t.rows(V, Z3, be, bd, Z3, Z3, bdd, GB))
    r0, r1 = rows(t, Z3), rows(t, jnp.array([3.0, 1.0, -1.0]))
    np.testing.assert_allclose(r1[2], r0[2], rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(r1[0], r0[0], rtol=1e-10, atol=1e-9)


@pytest.mark.slow
def test_cylinder_turning_about_its_axis_keeps_its_waves_still():
    """An upright cylinder turning steadily at Omega about its axis leaves its liquid's absolute motion
    alone (a potential flow has no way to take up the turning): a wave pattern standing still in space
    turns at -Omega in the tank, so the rows linearised about rest at that rate split each m-th pair
    of modes to omega_m -+ m Omega, the axisymmetric modes unmoved. This is the second-order coupling
    of the rotation and the waves (the one that moves a rolling square tank's centre line, in the
    paper example's probe B)."""
    t = _cylinder()
    om = jnp.array([0.0, 0.0, 0.7])
    z = jnp.zeros(t.n)

    @eqx.filter_jit
    def lin(t):
        r = lambda be, bd, bdd: t.rows(Z3, om, be, bd, Z3, Z3, bdd, GB)[2]  # noqa: E731
        return (r(z, z, z), jax.jacfwd(lambda a: r(z, z, a))(z), jax.jacfwd(lambda a: r(z, a, z))(z),
                jax.jacfwd(lambda a: r(a, z, z))(z))
    r0, M, C, K = (np.asarray(a) for a in lin(t))
    assert np.abs(r0).max() < 1e-9 * np.abs(K).max()          # rest stays rest while it turns
    n = t.n
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    ev = np.linalg.eigvals(A)
    assert np.abs(ev.real).max() < 1e-9 * np.abs(ev).max()
    w = np.asarray(t.omega_linear(G))
    expect = np.sort([wn + (0.0 if m == 0 else (-m if c == 0 else m) * 0.7) for wn, (m, _, c) in zip(w, t.modes)])
    got = np.sort(np.abs(ev.imag))[::2]
    np.testing.assert_allclose(got, expect, rtol=1e-8)


@pytest.mark.parametrize("n", [6, 16])
def test_cylinder_quadrature_holds_the_modes_norms_and_orthogonality(n):
    """The disk's base quadrature (Gauss-Jacobi in r by the trapezoidal rule in theta) gives the area
    pi R^2, the modes' norms in closed form, pi_m R^2 / 2 (1 - m^2 / (k R)^2) with pi_m = 2 pi for m = 0
    and pi otherwise (J_m'(k R) = 0), and their orthogonality."""
    R = 0.6
    base = DiskBase(R)
    modes = base.lowest(n)
    x, y, w = base.quadrature(modes)
    F = base.values(modes, x, y)[0]
    k, m = base.wavenumbers(modes), np.array([md[0] for md in modes])
    norms = np.where(m == 0, 2.0 * np.pi, np.pi) * 0.5 * R * R * (1.0 - (m / (k * R)) ** 2)
    np.testing.assert_allclose(w.sum(), np.pi * R * R, rtol=1e-13)
    np.testing.assert_allclose((F * w[:, None]).T @ F, np.diag(norms), rtol=0, atol=1e-9 * norms.max())
