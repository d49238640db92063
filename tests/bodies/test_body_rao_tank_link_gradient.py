"""The RAOs of a scene with [[bodies]] are differentiable in a body's tank and in a connection
(docs/guide/rao-gradients.md): the two boxes of tests/data/bodies, a tank of water on the tender and
a spring between them; the derivatives of `js.rao` in the tank's fill depth
(`tanks.<name>.fill_depth`) and the spring's stiffness (`connections.<name>.stiffness`) equal
central differences (the keys of test_body_rao_gradient.py are the bodies' own)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js

from two_boxes_scene import reference, two_boxes

KEYS = ["tanks.hold.fill_depth", "connections.link.stiffness"]

# a 4 x 3 m tank, 1 m of water, on the tender (12 x 6 m, 148 t: 12 t of water), its first transverse
# sloshing mode (about 2.7 rad/s) above the band; a spring holding the tender's sway to the barge
EXTRA = """
[[tanks]]
name = "hold"
body = "tender"
origin = [-2.0, -1.5, 0.5]
size = [4.0, 3.0, 2.0]
fill_depth = 1.0
mesh = [4, 3, 2]

[[connections]]
name = "link"
kind = "spring"
bodies = ["barge", "tender"]
points = [[0.0, 4.0, 1.0], [0.0, -3.0, 1.0]]
length = 7.0
stiffness = 2.0e5
damping = 0.0
"""


@pytest.fixture(scope="module")
def case():
    scene = js.load_scene(two_boxes() + EXTRA)
    w = np.asarray(reference()["omega"], dtype=float)
    w = w[(w > 0.5) & (w < 1.6)][::3]
    return scene, w, np.array([1.0, 2.0e5])


def _responses(scene, w, p):
    """|roll| and |sway| of the tender, |roll| of the barge beside it, in beam seas."""
    r = js.rao(scene, w, [np.pi / 2], params={KEYS[0]: p[0], KEYS[1]: p[1]})
    t, b = r.bodies["tender"][:, 0], r.vessel[:, 0]
    return jnp.concatenate([jnp.abs(t[:, 3]), jnp.abs(b[:, 3]), jnp.abs(t[:, 1])])


@pytest.mark.slow      # about 2 minutes on a loaded machine: three compiles of the RAOs with a liquid
def test_the_rao_gradient_in_a_body_tanks_fill_and_a_connections_stiffness(case):
    scene, w, p0 = case
    f = lambda p: _responses(scene, w, p)   # noqa: E731
    traced, J = jax.jit(lambda p: (f(p), jax.jacfwd(f)(p)))(jnp.asarray(p0))
    concrete = np.asarray(f(p0))
    np.testing.assert_allclose(np.asarray(traced), concrete, rtol=1e-10)
    values = jax.jit(f)
    J = np.asarray(J)
    for i, key in enumerate(KEYS):
        fds = []
        for rel in (1e-5, 3e-6):
            e = np.zeros(2)
            e[i] = rel * p0[i]
            fds.append((np.asarray(values(p0 + e)) - np.asarray(values(p0 - e))) / (2 * e[i]))
        scale = np.max(np.abs(fds[1]))
        assert scale * p0[i] > 1e-3 * np.max(concrete), key          # the value moves the RAOs
        assert np.max(np.abs(fds[0] - fds[1])) <= 1e-5 * scale, (key, "central differences not converged")
        assert np.max(np.abs(J[:, i] - fds[1])) <= 1e-5 * scale, (key, J[:, i], fds[1])
