"""The lines' term inside the rest of the program: gradients of a moored run with respect to a
line's values (finite differences), and the coupled modes' yaw frequency from the lines'
stiffness (the linearisation differentiates the same term)."""
import jax
import numpy as np
import pytest

import jaxslosh as js
from test_statics import SMALL, _lines


def _scene():
    return js.load_scene(SMALL.replace("duration = 60.0", "duration = 2.0") + _lines())


@pytest.mark.slow
@pytest.mark.parametrize("key", ["mooring.l0.length", "mooring.l1.ea"])
def test_gradient_of_a_moored_run_in_a_line_value(key):
    scene = _scene()
    base = {"mooring.l0.length": 420.0, "mooring.l1.ea": 3.0e8}[key]

    def final_surge(value):
        return js.simulate(scene, params={key: value}).vessel.position[-1, 0]

    g = float(jax.grad(final_surge)(base))
    h = 1e-4 * base
    fd = (float(final_surge(base + h)) - float(final_surge(base - h))) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-4, abs=1e-12)
    assert abs(g) > 0


def test_gradient_of_the_lines_force_in_line_values():
    """The fast check of the slow one above: the term built with traced line values, its force and
    moment at a displaced pose differentiated against finite differences."""
    import jax.numpy as jnp
    from jaxslosh.mooring.term import build_mooring
    scene = _scene()
    keys = ["mooring.l0.length", "mooring.l1.ea", "mooring.l2.weight", "mooring.l0.seabed_friction"]
    base = np.array([420.0, 3.0e8, 600.0, 0.3])
    A = jnp.asarray(np.eye(3))

    @jax.jit
    def loads(values):
        term = build_mooring(scene, True, params=dict(zip(keys, values)))
        F, M = term.force_moment(jnp.array([1.5, -0.7, 0.2]), A)
        return jnp.concatenate([F + term.carried, M])

    J = np.asarray(jax.jacfwd(loads)(jnp.asarray(base)))
    for i in range(len(keys)):
        h = np.zeros(len(keys))
        h[i] = 1e-5 * base[i]
        fd = (np.asarray(loads(jnp.asarray(base + h))) - np.asarray(loads(jnp.asarray(base - h)))) / (2 * h[i])
        np.testing.assert_allclose(J[:, i], fd, rtol=1e-5, atol=1e-6 * np.max(np.abs(fd)), err_msg=keys[i])


@pytest.mark.slow
def test_coupled_yaw_mode_from_the_lines_stiffness():
    """Yaw is held by the lines alone and, with the fairleads at the COG's height and symmetric
    lines, couples to nothing: omega = sqrt(K66 / I_zz) with K66 from js.mooring."""
    from jaxslosh.analysis.coupled import coupled_modes
    scene = _scene()
    K66 = js.mooring(scene, offsets=[0.0]).stiffness[5, 5]
    modes = coupled_modes(scene, n=6)
    yaw = modes.omega[list(modes.dominant).index("yaw")]
    assert yaw == pytest.approx(np.sqrt(K66 / 1.7e7), rel=1e-6)


@pytest.mark.slow
def test_batch_over_a_line_length_records_each_runs_tensions():
    from jaxslosh.mooring.catenary import catenary
    from jaxslosh.physics.kinematics import rotation_matrix
    scene = js.load_scene(SMALL.replace("duration = 60.0", "duration = 0.5").replace("dt = 0.2", "dt = 0.25")
                          + _lines())
    lengths = np.array([415.0, 425.0])
    res, statuses = js.simulate_batch(scene, {"mooring[0].length": lengths})
    assert statuses == ["ok", "ok"]
    for i, L in enumerate(lengths):
        X = np.asarray(res.vessel.position)[i, -1]
        p = X + np.asarray(rotation_matrix(res.vessel.quaternion[i, -1])) @ np.array([5.0, 0.0, 0.0])
        c = catenary((np.hypot(400.0 - p[0], p[1]), p[2] + 100.0), L, 600.0, 3.0e8)
        assert float(res.mooring["l0"].fairlead_tension[i, -1]) == pytest.approx(
            float(np.hypot(c.fairlead_horizontal, c.fairlead_vertical)), rel=1e-8)


def test_bad_traced_line_value_names_the_key():
    with pytest.raises(js.SceneError, match=r"^mooring\.l0\.length: must be positive"):
        js.simulate(_scene(), params={"mooring.l0.length": -1.0})
