"""The RAOs of a scene with [[bodies]] are differentiable as the vessel's (docs/guide/rao-gradients.md):
`js.rao(scene, ..., params=traced)` of the two boxes side by side on their coupled Capytaine file
(tests/data/bodies) equals the concrete RAOs, and its derivatives in a body's and the vessel's
values equal central differences."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js

from two_boxes_scene import reference, two_boxes

KEYS = ["bodies.tender.hydrostatics.gm_t", "vessel.mass", "bodies.tender.inertia"]


@pytest.fixture(scope="module")
def case():
    scene = js.load_scene(two_boxes())
    ref = reference()
    w = np.asarray(ref["omega"], dtype=float)
    w = w[(w > 0.5) & (w < 1.6)][::3]          # a few frequencies about the boxes' roll resonances
    p0 = np.array([scene.bodies[0].hydrostatics.gm_t, scene.vessel.mass, scene.bodies[0].inertia[0][0]])
    return scene, w, p0


def _params(scene, p):
    ixx = scene.bodies[0].inertia
    return {KEYS[0]: p[0], KEYS[1]: p[1], KEYS[2]: jnp.stack([p[2], ixx[1][1], ixx[2][2]])}


def _responses(scene, w, p):
    """|roll| of the tender and of the barge beside it, and |sway| of the tender, in beam seas."""
    r = js.rao(scene, w, [np.pi / 2], params=_params(scene, p))
    t, b = r.bodies["tender"][:, 0], r.vessel[:, 0]
    return jnp.concatenate([jnp.abs(t[:, 3]), jnp.abs(b[:, 3]), jnp.abs(t[:, 1])])


def test_a_bodys_rao_under_tracing_is_the_concrete_one_and_its_gradient_the_differences(case):
    scene, w, p0 = case
    f = lambda p: _responses(scene, w, p)   # noqa: E731
    traced, J = jax.jit(lambda p: (f(p), jax.jacfwd(f)(p)))(jnp.asarray(p0))
    concrete = np.asarray(f(p0))
    # the differences of the compiled RAOs (equal to the concrete ones, above): one compile, not 12
    # concrete linearisations
    values = jax.jit(f)
    assert isinstance(js.rao(scene, w, [np.pi / 2]).bodies["tender"], np.ndarray)
    np.testing.assert_allclose(np.asarray(traced), concrete, rtol=1e-10)
    J = np.asarray(J)
    for i, key in enumerate(KEYS):
        fds = []
        for rel in (1e-4, 1e-5):
            e = np.zeros(3)
            e[i] = rel * p0[i]
            fds.append((np.asarray(values(p0 + e)) - np.asarray(values(p0 - e))) / (2 * e[i]))
        scale = np.max(np.abs(fds[1]))
        assert scale * p0[i] > 1e-3 * np.max(concrete), key          # the value moves the RAOs
        assert np.max(np.abs(fds[0] - fds[1])) <= 1e-5 * scale, (key, "central differences not converged")
        assert np.max(np.abs(J[:, i] - fds[1])) <= 1e-5 * scale, (key, J[:, i], fds[1])
