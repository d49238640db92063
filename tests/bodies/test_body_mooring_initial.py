"""A body's traced initial state with mooring lines on that body (docs/guide/bodies-and-connections.md,
a body's values in params): the lines start from the traced pose (their state settled there), so
that a concrete `bodies.<name>.initial.position` runs as the scene file that says it and the
gradient of a run in it equals central differences. (A lumped line on a body starts in its static
shape at the body's initial pose of the scene file, as the vessel's do: tests/bodies/test_body_lumped.py.)"""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js

from test_body_mooring import BODY_AT, HEAD, HULL, OFFSET, SPIN, _lines

KEY = "bodies.buoy.initial.position"


def _text(position, duration=0.3) -> str:
    return (HEAD.replace("duration = 1.5", f"duration = {duration}") + "[vessel]\n"
            + HULL.format(table="vessel", extra="", position=[0, 0, 0], omega=[0, 0, 0])
            + "[[bodies]]\nname = \"buoy\"\n"
            + HULL.format(table="bodies", extra=f"position = {list(BODY_AT)}", position=list(position), omega=SPIN)
            + _lines("buoy", BODY_AT))


@pytest.fixture(scope="module")
def scene():
    return js.load_scene(_text(OFFSET))


def _loss(scene):
    def loss(p):
        r = js.simulate(scene, params={KEY: p})
        b = r.bodies["buoy"]
        return jnp.sum(b.position ** 2) + jnp.sum(r.mooring["l1"].fairlead_tension) * 1e-6
    return jax.jit(loss)


def test_a_concrete_initial_position_runs_as_the_file_that_says_it(scene):
    """params {bodies.buoy.initial.position: p} (6 steps) equals the scene file with that initial
    position: the body's motion to 1e-10 m and its lines' tensions to 1e-10 relative."""
    p = [1.0, 2.0, -0.1]
    got = js.simulate(scene, params={KEY: p})
    want = js.simulate(js.load_scene(_text(p)))
    np.testing.assert_allclose(np.asarray(got.bodies["buoy"].position), np.asarray(want.bodies["buoy"].position),
                               rtol=0, atol=1e-10)
    for name in ("l1", "l2", "l3"):
        t = np.asarray(want.mooring[name].fairlead_tension)
        assert t.min() > 1e4
        np.testing.assert_allclose(np.asarray(got.mooring[name].fairlead_tension), t, rtol=1e-10)
    np.testing.assert_allclose(np.asarray(got.bodies["buoy"].position)[0], p, rtol=0, atol=1e-12)   # it starts there


@pytest.mark.slow      # about 35 s of CPU (its compile); the test above is the fast check of the same start
def test_the_gradient_in_a_moored_bodys_initial_position_matches_central_differences(scene):
    """6 steps: the gradient of the body's squared offsets and a line's tension in its initial
    position's three components within 1e-6 of central differences (relative steps 1e-4, 1e-5,
    which agree first)."""
    loss = _loss(scene)
    p0 = np.asarray(OFFSET, dtype=float)
    g = np.asarray(jax.grad(loss)(jnp.asarray(p0)))
    for i in range(3):
        fds = []
        for h in (1e-4, 1e-5):
            e = np.zeros(3)
            e[i] = h
            fds.append((float(loss(jnp.asarray(p0 + e))) - float(loss(jnp.asarray(p0 - e)))) / (2 * h))
        assert abs(fds[1]) > 0 and abs(fds[0] - fds[1]) <= 1e-6 * abs(fds[1]), (i, fds)
        assert abs(g[i] - fds[1]) <= 1e-6 * abs(fds[1]), (i, g[i], fds[1])
