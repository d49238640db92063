"""A traced fill depth with the face-normal liquid ("rt", full order): a plain box's layers scale
with the depth, so its blocks are closed functions of h / h0 (liquid/face/build.py
traced_depth_blocks). Checked: those blocks against the model built at the new depth, a run with a
traced depth against the run of the scene that says that depth, and jax.grad of a trajectory loss
against central differences; the shapes whose mesh follows the fill, and runs on modes, are refused
naming the key."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.liquid.face.build import absolute_rotation_penalty, traced_depth_blocks
from jaxslosh.liquid.face.element import _gauss, build_face_liquid, face_modes
from jaxslosh.geometry import Box
from test_gradients_liquid import SCENE

RT = '[tanks.fluid]\nelement = "rt"\n'


def _model(h):
    tm = Box(size=(2.0, 3.0, 2.0)).mesh(h, (2, 3, 2))
    return build_face_liquid(tm.nodes, tm.elements, h, 1000.0, 1500.0, 9.81)


def _kappa(m):
    fm = face_modes(m, 20)
    return (10.0 * max(w for w, k in zip(fm.omega, fm.kind) if k == "sloshing")) ** 2


def test_blocks_at_a_traced_depth_are_the_model_built_at_that_depth():
    """Gauss points, weights, fields, mass and compression equal the model built at 1.2 m from the
    one at 1.0 m, to round-off; the absolute-rotation penalty too, up to its kappa, which stays the
    scene's (it sets how stiffly the circulation is held, not the physics)."""
    m0, m1 = _model(1.0), _model(1.2)
    origin = (0.3, -0.2, 0.1)
    got = jax.jit(lambda s: traced_depth_blocks(m0, origin, s))(1.2)
    f = np.flatnonzero(m1.free)
    r = _kappa(m0) / _kappa(m1)
    want = list(_gauss(m1)) + [m1.mass[f][:, f].toarray(), m1.acoustic[f][:, f].toarray()] \
        + [r * np.asarray(v) for v in absolute_rotation_penalty(m1, origin)]
    for i, (a, b) in enumerate(zip(got, want)):
        assert np.abs(np.asarray(a) - b).max() <= 1e-13 * np.abs(b).max(), i


def _scene(fill=3.0, duration=1.0):
    text = SCENE.format(duration=duration, tolerance=1e-13, fill=fill, c=50.0)
    return js.load_scene(text.replace("[tanks.fluid]\n", RT))


def test_gradient_of_a_trajectory_loss_wrt_the_fill_depth_matches_central_differences():
    """1 s of a light hull carrying 75 t of liquid in an "rt" box (3 x 3 x 2, full order): the loss
    sums the squared roll and pitch and the free-surface elevation at a wall (probe B - A). The run
    at a traced 2.8 m equals the scene filled to 2.8 m (whose penalty's kappa is its own: within
    1e-5), and jax.grad matches central differences taken with the same program."""
    scene = _scene()

    def loss(h):
        r = js.simulate(scene, params={"tanks.tank.fill_depth": h})
        rpy = r.vessel.roll_pitch_yaw
        eta = r.probes["B"].displacement[:, 2] - r.probes["A"].displacement[:, 2]
        return jnp.sum(rpy[:, 0] ** 2) + jnp.sum(rpy[:, 1] ** 2) + 100.0 * jnp.sum(eta ** 2), rpy

    value_and_grad = jax.jit(jax.value_and_grad(loss, has_aux=True))
    (v, rpy), g = value_and_grad(jnp.asarray(2.8))
    alone = js.simulate(_scene(fill=2.8))
    want = np.asarray(alone.vessel.roll_pitch_yaw)
    assert np.abs(np.asarray(rpy) - want).max() <= 1e-5 * np.abs(want).max()
    fds = []
    for rel in (1e-4, 1e-5):
        e = rel * 2.8
        fds.append((float(value_and_grad(jnp.asarray(2.8 + e))[0][0])
                    - float(value_and_grad(jnp.asarray(2.8 - e))[0][0])) / (2 * e))
    assert abs(fds[0] - fds[1]) <= 5e-6 * abs(fds[1]), fds
    assert abs(float(g) * 2.8) > 1e-3 * float(v)              # the depth moves the loss
    assert abs(float(g) / fds[1] - 1) <= 1e-5, (float(g), fds)


def test_a_traced_depth_is_refused_where_the_mesh_follows_the_fill_or_on_modes():
    text = SCENE.format(duration=0.1, tolerance=1e-10, fill=3.0, c=1500.0).replace("[tanks.fluid]\n", RT)
    with pytest.raises(js.SceneError, match=r"tanks\[0\].fill_depth.*full order"):
        js.simulate_batch(js.load_scene(text + "[tanks.reduction]\nmodes = 4\n"),
                          {"tanks.tank.fill_depth": np.array([2.9, 3.0])})
    shaped = text.replace('mesh = [3, 3, 2]', 'mesh = [3, 4, 3]\nshape = "prismatic"\nchamfers = [[1.0, 1.0], [0.0, 0.0]]')
    with pytest.raises(js.SceneError, match=r"tanks\[0\].fill_depth.*mesh\s+follows"):
        js.simulate_batch(js.load_scene(shaped), {"tanks.tank.fill_depth": np.array([2.9, 3.0])})
