"""A hawser or fender that sits at its length at rest is inside its contact's smoothing band
(physics/bodies.py BAND): `rao` says so, naming each, and the stiffness it sees there is what the
warning says (3/8 of its own at its length: the smoothed law's derivative, against its closed form)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.analysis.rao import contact_warnings
from jaxslosh.physics.bodies import BAND, Link


def test_rao_names_the_connections_that_sit_in_their_band_at_rest():
    flng = contact_warnings(js.load_scene("scenes/flng_side_by_side.toml"))
    assert len(flng) == 1 and flng[0].startswith("12 connection(s)")
    for name in ("bow_line", "stern_line", "fender_1", "fender_4"):
        assert f"'{name}'" in flng[0]
    assert contact_warnings(js.load_scene("scenes/paper_ship_tank.toml")) == []


@pytest.mark.parametrize("kind", ["hawser", "fender"])
def test_the_stiffness_at_its_length_is_three_eighths_and_its_own_beyond_the_band(kind):
    k = 2.0e6
    link = Link(ends=(-1, -2), kind=kind, pa=jnp.zeros(3), pb=jnp.zeros(3), length=jnp.asarray(1.0),
                xs=jnp.array([0.0, 1.0]), fs=jnp.array([0.0, k]), damping=jnp.asarray(0.0))
    stiffness = jax.grad(lambda e: link.law(e)[1])
    assert float(stiffness(0.0)) == pytest.approx(3.0 / 8.0 * k, rel=1e-12)
    working = BAND if kind == "hawser" else -BAND          # taut rope, pressed fender
    assert float(stiffness(working)) == pytest.approx(k, rel=1e-12)
    assert float(stiffness(-working)) == pytest.approx(0.0, abs=1e-9 * k)
    assert np.isfinite(float(stiffness(0.25 * BAND)))
