"""The wave excitation's cosine and sine (physics/seakeeping.cos_sin) against NumPy's, and its
derivative against the closed form."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxslosh.physics.seakeeping import cos_sin


@pytest.mark.parametrize("span", [1.0, 100.0, 3.0e4, 1.5e6])
def test_cos_sin_within_two_ulps_of_numpy(span):
    # |x| up to 3e4 rad: 2 rad/s for a 3-hour record; 1.5e6: the range where n pi/2 stays exact
    x = np.random.default_rng(7).uniform(-span, span, 20000)
    x = np.concatenate([x, np.arange(-8, 9) * np.pi / 4])       # the quadrants' edges
    c, s = cos_sin(jnp.asarray(x))
    assert np.max(np.abs(np.asarray(c) - np.cos(x))) <= 2.3e-16
    assert np.max(np.abs(np.asarray(s) - np.sin(x))) <= 2.3e-16


def test_cos_sin_derivatives():
    x = jnp.linspace(-20.0, 20.0, 41)
    dc = jax.vmap(jax.grad(lambda t: cos_sin(t)[0]))(x)
    ds = jax.vmap(jax.grad(lambda t: cos_sin(t)[1]))(x)
    assert np.allclose(dc, -np.sin(x), rtol=0, atol=1e-15)
    assert np.allclose(ds, np.cos(x), rtol=0, atol=1e-15)
