"""The multimodal liquid (liquid/multimodal/term.py): its coefficients against quadrature of the exact
modes by SciPy, its small-amplitude limits against linear theory, its nonlinear free oscillations
against the third-order standing wave of Tadjbakhsh & Keller (1960) and the critical depth
h / L = 0.3368 (Faltinsen et al. 2000), and its force against the spring-mass model."""
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate

from jaxslosh.liquid.multimodal.term import modal_tank

G = 9.81
Z3 = jnp.zeros(3)
GB = jnp.array([0.0, 0.0, -G])


def _tank(hL, n=5, L=1.0, origin=(0.0, 0.0, 0.0)):
    return modal_tank(L, 0.1, hL * L, 1000.0, origin, n)


@eqx.filter_jit
def _linear(t):
    """Modal mass and stiffness of the rows at rest, by JAX."""
    z = jnp.zeros(t.n)
    r = lambda be, bdd: t.rows(Z3, Z3, be, z, Z3, Z3, bdd, GB)[2]  # noqa: E731
    return jax.jacfwd(lambda a: r(z, a))(z), jax.jacfwd(lambda be: r(be, z))(z)


@pytest.mark.parametrize("hL", [0.5, 0.2])
def test_small_amplitude_frequencies_are_linear_theory(hL):
    t = _tank(hL)
    M, K = _linear(t)
    w = np.sort(np.sqrt(np.linalg.eigvals(np.linalg.solve(M, K)).real))
    k = np.arange(1, 6) * np.pi
    np.testing.assert_allclose(w, np.sqrt(G * k * np.tanh(k * hL)), rtol=5e-3)
    np.testing.assert_allclose(w, np.sqrt(G * k * np.tanh(k * hL)), rtol=1e-9)


def test_integrals_against_scipy_quadrature_of_the_exact_modes():
    """A_n, dA_n/dbeta, A_nk, the flux integrals and the moments at a large surface deflection."""
    t = _tank(0.4, n=3)
    beta = jnp.array([0.08, -0.03, 0.02])
    # the integrals and their derivative in one program (eager: each operation compiles on its own)
    I, Jn = eqx.filter_jit(lambda t, b: (t.integrals(b), jax.jacfwd(lambda be: t.integrals(be).An)(b)))(t, beta)
    h, k = 0.4, np.arange(1, 4) * np.pi
    zeta = lambda x: float(np.cos(k * x) @ np.asarray(beta))  # noqa: E731
    phi = lambda n, x, u: np.cos(k[n] * x) * np.cosh(k[n] * u) / np.cosh(k[n] * h)  # noqa: E731
    px = lambda n, x, u: -k[n] * np.sin(k[n] * x) * np.cosh(k[n] * u) / np.cosh(k[n] * h)  # noqa: E731
    pz = lambda n, x, u: k[n] * np.cos(k[n] * x) * np.sinh(k[n] * u) / np.cosh(k[n] * h)  # noqa: E731

    def q(f):
        return integrate.dblquad(lambda u, x: f(x, u), 0.0, 1.0, 0.0, lambda x: h + zeta(x), epsabs=1e-12,
                                 epsrel=1e-11)[0]
    for n in range(3):
        assert float(I.An[n]) == pytest.approx(q(lambda x, u: phi(n, x, u)), rel=1e-9, abs=1e-12)
        assert float(I.grad[n, 0]) == pytest.approx(q(lambda x, u: px(n, x, u)), rel=1e-9, abs=1e-12)
        assert float(I.Zux[n]) == pytest.approx(q(lambda x, u: u * px(n, x, u)), rel=1e-9, abs=1e-12)
        assert float(I.Xuz[n]) == pytest.approx(q(lambda x, u: x * pz(n, x, u)), rel=1e-9, abs=1e-12)
        for m in range(3):
            ref = q(lambda x, u: px(n, x, u) * px(m, x, u) + pz(n, x, u) * pz(m, x, u))
            assert float(I.Ank[n, m]) == pytest.approx(ref, rel=1e-9, abs=1e-12)
    np.testing.assert_allclose(I.Jn, Jn, rtol=1e-12, atol=1e-14)
    assert float(I.mxz) == pytest.approx(q(lambda x, u: x * u), rel=1e-10)
    assert float(I.area) == pytest.approx(h, rel=1e-13)        # the cosines conserve the volume


def test_uniform_motion_does_not_drive_sloshing():
    """Galilean invariance: a tank moving at constant velocity sloshes as one at rest."""
    t = _tank(0.4, n=4)
    be, bd, bdd = jnp.array([0.05, 0.01, -0.02, 0.005]), jnp.array([0.1, -0.2, 0.05, 0.0]), jnp.zeros(4)
    V = jnp.array([3.0, 0.0, -1.0])
    rows = eqx.filter_jit(lambda t, v: t.rows(v, Z3, be, bd, Z3, Z3, bdd, GB))   # one program for both
    r0, r1 = rows(t, Z3), rows(t, V)
    np.testing.assert_allclose(r1[2], r0[2], rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(r1[0], r0[0], rtol=1e-10, atol=1e-9)


@eqx.filter_jit
def _surge_derivatives(t):
    """The rows' derivatives at rest (modal mass, stiffness, coupling to surge acceleration) and the
    horizontal force's (per unit surge acceleration, per unit modal acceleration), in one program
    (eager, each primitive of the five derivatives compiles on its own)."""
    z = jnp.zeros(t.n)

    def rows(be, bdd, a):
        f, _, rb = t.rows(Z3, Z3, be, z, jnp.array([a, 0.0, 0.0]), Z3, bdd, GB)
        return f[0], rb
    M = jax.jacfwd(lambda x: rows(z, x, 0.0)[1])(z)
    K = jax.jacfwd(lambda x: rows(x, z, 0.0)[1])(z)
    c = jax.jacfwd(lambda a: rows(z, z, a)[1])(0.0)
    fa = jax.grad(lambda a: rows(z, z, a)[0])(0.0)
    fb = jax.grad(lambda x: rows(z, x, 0.0)[0])(z)
    return M, K, c, fa, fb


def test_surge_force_is_the_spring_mass_models():
    """Linear transfer function of the horizontal force per unit surge acceleration:
    m + sum_n m_n w^2 / (w_n^2 - w^2), m_n = 8 m tanh(k_n h) / (n^3 pi^3 h / L) for odd n."""
    hL, L, n = 0.5, 1.0, 5
    t = _tank(hL, n=n, L=L, origin=(-0.3, -0.05, -0.2))
    M, K, c, fa, fb = _surge_derivatives(t)
    mass = 1000.0 * 0.1 * L * hL * L
    k = np.arange(1, n + 1) * np.pi / L
    wn = np.sqrt(G * k * np.tanh(k * hL * L))
    mn = np.where(np.arange(1, n + 1) % 2 == 1, 8 * mass * np.tanh(k * hL * L) / (np.arange(1, n + 1) ** 3 * np.pi ** 3 * hL), 0.0)
    for w in (0.5 * wn[0], 0.9 * wn[0], 1.3 * wn[0]):
        beta = np.linalg.solve(np.asarray(K) - w ** 2 * np.asarray(M), -np.asarray(c))    # per unit acceleration
        F = float(fa) + float(np.asarray(fb) @ (-w ** 2 * beta))
        assert F == pytest.approx(mass + np.sum(mn * w ** 2 / (wn ** 2 - w ** 2)), rel=1e-9)


#: RK4's stages: (the step's fraction to the stage's state, the stage's weight times 6)
RK4_STAGES = jnp.array([[0.0, 1.0], [0.5, 2.0], [0.5, 2.0], [1.0, 1.0]])


@eqx.filter_jit
def _free_period(t, eps, periods: int = 8, per: int = 120):
    """Free oscillation from beta_1 = eps L at rest (RK4): the mean period of beta_1's down-crossings."""
    n = t.n
    z = jnp.zeros(n)

    def acc(y):
        be, bd = y[:n], y[n:]
        r = lambda a: t.rows(Z3, Z3, be, bd, Z3, Z3, a, GB)[2]  # noqa: E731
        return jnp.concatenate([bd, -jnp.linalg.solve(jax.jacfwd(r)(z), r(z))])
    T = 2 * jnp.pi / t.omega_linear(G)[0]
    dt = T / per

    def step(y, _):
        # RK4's four stages as a loop: the program holds the rows (and their Jacobian) once, not four
        # times (a quarter of the compile)
        def stage(carry, c):
            total, k = carry
            k = acc(y + c[0] * dt * k)
            return (total + c[1] * k, k), None
        (total, _), _ = jax.lax.scan(stage, (jnp.zeros_like(y), jnp.zeros_like(y)), RK4_STAGES)
        y = y + dt / 6 * total
        return y, y[0]
    _, b1 = jax.lax.scan(step, jnp.concatenate([z.at[0].set(eps * t.L), z]), None, length=periods * per)
    return jnp.concatenate([jnp.array([eps * t.L]), b1]), dt, T


def _period_shift(hL, eps):
    t = _tank(hL, n=5)
    b1, dt, T = _free_period(t, eps)
    b1, dt, T = np.asarray(b1), float(dt), float(T)
    i = np.flatnonzero((b1[:-1] > 0) & (b1[1:] <= 0))
    tc = (i + b1[i] / (b1[i] - b1[i + 1])) * dt
    return T / ((tc[-1] - tc[0]) / (len(tc) - 1)) - 1.0


def _tadjbakhsh_keller(hL, eps):
    """omega / omega_1 - 1 of the third-order standing wave of amplitude a = eps L, k = pi / L."""
    T = np.tanh(np.pi * hL)
    return (np.pi * eps) ** 2 * (9 / T ** 4 - 12 / T ** 2 - 3 - 2 * T ** 2) / 64


@pytest.mark.parametrize("hL", [0.5, 0.2])
def test_frequency_amplitude_dependence_changes_sign_at_critical_depth(hL):
    """Soft above h / L = 0.3368, hard below, as the third-order theory's backbone."""
    shift = _period_shift(hL, 0.02)
    ref = _tadjbakhsh_keller(hL, 0.02)
    assert (shift < 0) if hL > 0.3368 else (shift > 0)
    assert shift == pytest.approx(ref, rel=0.1)


def test_rotation_keeps_the_liquid_irrotational():
    """The pitch rate's vortical flow w: no flux through the walls, curl -2 and no divergence, and a
    closed square tank's effective pitch inertia is the Stokes-Joukowski 0.157 of the frozen one."""
    t = modal_tank(1.0, 0.4, 0.5, 1000.0, (-0.5, -0.2, -0.3), 3, D=0.8)
    # one program for the flow at the walls and its Jacobian (eager, each operation compiles on its own)
    flow = eqx.filter_jit(lambda t, x, u, p: (t.vortical(x, u), jax.jacfwd(lambda p: jnp.array(t.vortical(p[0], p[1])))(p)))
    u, p = jnp.linspace(0.0, 0.8, 9), jnp.array([0.3, 0.4])
    (wx, _), Jw = flow(t, jnp.zeros(9), u, p)
    np.testing.assert_allclose(wx, 0.0, atol=1e-12)
    (wx, _), _ = flow(t, jnp.ones(9), u, p)
    np.testing.assert_allclose(wx, 0.0, atol=1e-12)
    (_, wz), _ = flow(t, jnp.linspace(0.05, 0.95, 9), jnp.zeros(9), p)
    np.testing.assert_allclose(wz, 0.0, atol=2e-3)             # the series' truncation, worst near corners
    assert float(Jw[0, 1] - Jw[1, 0]) == pytest.approx(-2.0, rel=1e-9)
    assert float(Jw[0, 0] + Jw[1, 1]) == pytest.approx(0.0, abs=1e-9)
    full = modal_tank(1.0, 1.0, 1.0 - 1e-9, 1000.0, (-0.5, -0.5, -0.5), 3, D=1.0)
    M = eqx.filter_jit(lambda t: t.mass_matrix(jnp.zeros(3)))(full)
    assert float(M[4, 4]) / (1000.0 / 6.0) == pytest.approx(0.157, rel=5e-3)


def test_closed_form_integrals_are_the_quadrature_over_the_liquid():
    """`integrals` (closed forms through the depth, the vortical flow's by its flux through the free
    surface) against Gauss quadrature over the whole deflected liquid, pitch terms included."""
    t = modal_tank(1.0, 0.4, 0.5, 1000.0, (-0.5, -0.2, -0.3), 5, D=0.8)
    beta = jnp.array([0.09, -0.03, 0.02, 0.01, -0.005])

    @eqx.filter_jit        # both sides and their derivatives, one program (eager: each operation its own)
    def both(t, beta):
        return (t.integrals(beta), t.integrals_quadrature(beta), jax.jacfwd(lambda be: t.integrals(be).W)(beta),
                jax.jacfwd(lambda be: t.integrals_quadrature(be).W)(beta))
    a, b, Ja, Jb = both(t, beta)
    for name in a._fields:
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-9, atol=1e-11, err_msg=name)
    np.testing.assert_allclose(Ja, Jb, rtol=1e-8, atol=1e-10)
