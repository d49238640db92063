"""The RAOs of a scene with [[bodies]] are differentiable in a body's tank (docs/guide/rao-gradients.md):
the two boxes of tests/data/bodies, a tank of water on the tender and a spring between them; the
derivative of `js.rao` in the tank's fill depth (`tanks.<name>.fill_depth`, traced through the
liquid's matrices) equals central differences (the keys of test_body_rao_gradient.py are the
bodies' own), and so does its derivative in a connection's stiffness (`connections.<name>.stiffness`),
which needs the spring's force differentiated right at its unstretched length (the rest state)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.physics.bodies import Link

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
def test_the_rao_gradient_in_a_body_tanks_fill_depth(case):
    scene, w, p0 = case
    f = lambda p: _responses(scene, w, p)   # noqa: E731
    traced, J = jax.jit(lambda p: (f(p), jax.jacfwd(f)(p)))(jnp.asarray(p0))
    concrete = np.asarray(f(p0))
    np.testing.assert_allclose(np.asarray(traced), concrete, rtol=1e-10)
    values = jax.jit(f)
    J = np.asarray(J)[:, 0]
    # steps of 1e-3 and 5e-4 of the depth: the RAOs' round-off (about 1e-10 of them: the liquid's
    # compression is stiff) makes smaller steps' differences noisier than these' truncation
    fds = []
    for rel in (1e-3, 5e-4):
        e = np.array([rel * p0[0], 0.0])
        fds.append((np.asarray(values(p0 + e)) - np.asarray(values(p0 - e))) / (2 * e[0]))
    scale = np.max(np.abs(fds[1]))
    assert scale * p0[0] > 1e-3 * np.max(concrete)          # the fill depth moves the RAOs
    assert np.max(np.abs(fds[0] - fds[1])) <= 1e-5 * scale, "central differences not converged"
    assert np.max(np.abs(J - fds[1])) <= 1e-5 * scale, (J, fds[1])


def test_a_springs_force_has_its_stiffness_at_its_length():
    """A spring at its unstretched length (the RAOs' rest state): dF/de is its stiffness, on both sides
    (through sign(e) F(|e|) the derivative at e = 0 was 0, and js.rao left the spring out)."""
    k = 2.0e5
    link = Link(ends=(-1, 0), kind="spring", xs=jnp.array([0.0, 1.0]), fs=jnp.array([0.0, k]))
    dF = jax.grad(lambda e: link.law(e)[1])
    for e in (0.0, 0.3, -0.3):
        np.testing.assert_allclose(float(dF(jnp.asarray(e))), k, rtol=1e-14)
    np.testing.assert_allclose(float(link.law(jnp.asarray(-0.3))[1]), -0.3 * k, rtol=1e-14)
    np.testing.assert_allclose(float(link.law(jnp.asarray(-0.3))[0]), 0.5 * k * 0.09, rtol=1e-14)


@pytest.mark.slow
def test_a_connections_stiffness_moves_the_rao_and_its_gradient_is_the_differences(case):
    scene, _, _ = case
    w = np.array([0.6, 1.0, 1.4])
    sway = lambda k: jnp.abs(js.rao(scene, w, [np.pi / 2], params={KEYS[1]: k}).bodies["tender"][:, 0, 1])  # noqa: E731
    values = jax.jit(sway)
    k0 = 2.0e5
    J = np.asarray(jax.jit(jax.jacfwd(sway))(k0))
    assert np.max(np.abs(np.asarray(values(100 * k0)) - np.asarray(values(k0)))) > 1e-3 * np.max(np.asarray(values(k0)))
    fds = [(np.asarray(values(k0 * (1 + rel))) - np.asarray(values(k0 * (1 - rel)))) / (2 * rel * k0)
           for rel in (1e-3, 5e-4)]
    scale = np.max(np.abs(fds[1]))
    assert np.max(np.abs(fds[0] - fds[1])) <= 1e-5 * scale, "central differences not converged"
    assert np.max(np.abs(J - fds[1])) <= 1e-5 * scale, (J, fds[1])
