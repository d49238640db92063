"""The residual is the virtual work of one Lagrangian: forces are gradients of the potential energy,
the mass matrix is the Hessian of the kinetic energy (STYLE.md: write energies once)."""
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxslosh.assemble.system import build
from jaxslosh.physics.kinematics import quat_exp, quat_from_rpy, quat_multiply
from jaxslosh.physics.terms import Config

from test_coupled import ship_with_tank


@pytest.fixture(scope="module")
def system():
    return build(ship_with_tank(mesh=(2, 2, 2), rpy=(0.05, 0.0, 0.0))).system


def _state(system, seed):
    rng = np.random.default_rng(seed)
    c = Config(jnp.asarray(rng.normal(size=3) * 0.1), quat_from_rpy(jnp.asarray(rng.normal(size=3) * 0.2)),
               jnp.asarray(rng.normal(size=system.nf) * 1e-3))
    v = jnp.asarray(rng.normal(size=system.n) * 0.1)
    return c, v


# Each side one program, the system and the state its inputs (run eagerly, their operations
# compiled one by one: ~9 s of the file's CPU); the seeds and the tests of a system share it.

@eqx.filter_jit
def _rows_and_potential_gradient(system, c):
    """The residual at rest in the state c, and the gradient of the potential energy there."""
    z = jnp.zeros(system.n)

    def V(x):
        return system.potential_energy(Config(c.X0 + x[:3], quat_multiply(c.q, quat_exp(x[3:6])), c.d + x[6:]))

    return system.residual(c, z[:3], z[3:6], z[6:], z), jax.grad(V)(z)


@eqx.filter_jit
def _mass_matrices(system, c, v):
    """The residual's Jacobian in the accelerations, and the Hessian of the kinetic energy."""
    Mr = jax.jacfwd(lambda a: system.residual(c, v[:3], v[3:6], v[6:], a))(jnp.zeros(system.n))
    return Mr, jax.hessian(lambda w: system.kinetic_energy(c, w))(v)


@pytest.mark.parametrize("seed", [0, 1])
def test_static_residual_is_the_gradient_of_the_potential(system, seed):
    c, _ = _state(system, seed)
    r, g = _rows_and_potential_gradient(system, c)
    np.testing.assert_allclose(r, g, rtol=1e-9, atol=1e-9 * float(jnp.max(jnp.abs(g))))


@pytest.mark.parametrize("seed", [0, 1])
def test_mass_matrix_is_the_hessian_of_the_kinetic_energy(system, seed):
    c, v = _state(system, seed)
    Mr, Mt = _mass_matrices(system, c, v)
    np.testing.assert_allclose(Mr, Mt, rtol=1e-10, atol=1e-10 * float(jnp.max(jnp.abs(Mt))))


@pytest.fixture(scope="module")
def falling():
    """Nothing holds this vessel up (no hydrostatics): the Weight term carries the whole weight, and
    the liquid's first moment adds its moment."""
    scene = ship_with_tank(mesh=(2, 2, 2), rpy=(0.05, 0.0, 0.0))
    text = scene.text
    start = text.index("[vessel.hydrostatics]")
    end = text.index("[vessel.initial]")
    import jaxslosh as js
    return build(js.load_scene(text[:start] + text[end:])).system


@pytest.mark.parametrize("seed", [0, 1])
def test_weight_rows_of_a_free_vessel_are_the_gradient_of_the_potential(falling, seed):
    assert "Weight" in {type(t).__name__ for t in falling.terms}
    c, _ = _state(falling, seed)
    r, g = _rows_and_potential_gradient(falling, c)
    np.testing.assert_allclose(r, g, rtol=1e-9, atol=1e-9 * float(jnp.max(jnp.abs(g))))
