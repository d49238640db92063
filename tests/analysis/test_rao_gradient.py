"""The RAOs are differentiable: `js.rao(scene, ..., params=traced)` under jax.grad gives the
derivative of the response with respect to traceable scene keys (the linearisation's matrices
stay JAX values), equal to central finite differences of the concrete RAOs, and its value equals
the concrete one. (The anti-roll tank's fill depth and damping ratio: notebooks/anti_roll_tank.ipynb,
run by tests/docs/test_notebooks.py.)"""
import jax
import jax.numpy as jnp
import numpy as np

import jaxslosh as js

from test_frequency import box_tables_scene

W = np.array([0.6, 0.8, 1.0])


def test_roll_rao_gradient_with_respect_to_gm_t_equals_finite_differences():
    scene = box_tables_scene()
    head = [np.pi / 2]
    gm0 = scene.vessel.hydrostatics.gm_t

    def roll(gm):
        r = js.rao(scene, W, head, params={"vessel.hydrostatics.gm_t": gm})
        return jnp.abs(r.vessel[:, 0, 3])

    traced = np.asarray(jax.jit(roll)(gm0))
    concrete = np.abs(js.rao(scene, W, head).vessel[:, 0, 3])
    np.testing.assert_allclose(traced, concrete, rtol=1e-10)

    grad = np.asarray(jax.jit(jax.jacfwd(roll))(gm0))
    e = 1e-4 * gm0
    fd = (np.abs(js.rao(scene, W, head, params={"vessel.hydrostatics.gm_t": gm0 + e}).vessel[:, 0, 3])
          - np.abs(js.rao(scene, W, head, params={"vessel.hydrostatics.gm_t": gm0 - e}).vessel[:, 0, 3])) / (2 * e)
    assert np.all(np.abs(fd) > 1e-3), fd          # the roll responds to GM_T at each frequency
    np.testing.assert_allclose(grad, fd, rtol=1e-5)
