"""Traced values of a lumped line (`mooring.<line>.length | weight | ea` through params, a sweep's
batch; docs/guide/moorings-lumped.md): the run equals the scene file with those values, gradients
match central differences, the keys a lumped line cannot trace are refused naming the key."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.mooring.lumped_term import build_lumped_lines
from jaxslosh.run.batch import simulate_batch
from jaxslosh.scene.keys import traceable, traceable_keys
from jaxslosh.scene.types import SceneError
from test_statics import SMALL

LINE = """
[[mooring]]
name = "l0"
fairlead = [5.0, 0.0, 0.0]
anchor = [400.0, 0.0, -100.0]
length = {length}
weight = {weight}
ea = {ea}
model = "lumped"
segments = 4
mass = 70.0
"""
BASE = dict(length=420.0, weight=600.0, ea=3.0e8)


def _scene(**values):
    text = SMALL.replace("duration = 60.0", "duration = 0.5").replace("dt = 0.2", "dt = 0.25")
    return js.load_scene(text + LINE.format(**(BASE | values)))


def test_traced_values_equal_the_scene_file_with_them():
    # values whose line keeps the scene's sub-step count (the sub-step is the scene values')
    new = dict(length=421.0, weight=610.0, ea=3.05e8)
    a = js.simulate(_scene(), params={f"mooring.l0.{k}": v for k, v in new.items()})
    b = js.simulate(_scene(**new))
    c = js.simulate(_scene())
    for r in (a, b):
        assert r.status == "ok"
    np.testing.assert_allclose(np.asarray(a.vessel.position), np.asarray(b.vessel.position), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(np.asarray(a.mooring["l0"].fairlead_tension),
                               np.asarray(b.mooring["l0"].fairlead_tension), rtol=1e-10)
    # and the values change the run (they were ignored before)
    assert not np.allclose(np.asarray(a.mooring["l0"].fairlead_tension), np.asarray(c.mooring["l0"].fairlead_tension))


@pytest.mark.parametrize("key,h", [("length", 4.2e-3), ("weight", 0.06), ("ea", 3e3)])
def test_rest_pull_gradient_matches_central_differences(key, h):
    """The line's pull at the start (its static shape solved with traced values, differentiated by
    the implicit function theorem) against central differences of the concrete solve."""
    scene = _scene()

    def pull(x):
        (t,) = build_lumped_lines(scene, True, params={f"mooring.l0.{key}": x})
        return t.carried[2]

    g = float(jax.grad(pull)(jnp.asarray(BASE[key])))
    fd = (float(pull(BASE[key] + h)) - float(pull(BASE[key] - h))) / (2 * h)
    assert abs(g) > 0
    assert g == pytest.approx(fd, rel=1e-6)   # measured: within 4e-7 (the seabed band is 1 mm)


def test_lumped_lines_refuse_seabed_friction_naming_the_key():
    scene = _scene()
    assert "mooring.l0.length" in traceable_keys(scene)
    assert "mooring.l0.seabed_friction" not in traceable_keys(scene)
    # a concrete value is checked as the scene file with it (the loader's refusal), a traced one by the keys
    with pytest.raises(SceneError, match=r"^mooring.l0.seabed_friction: .*lumped line's seabed has no friction"):
        js.simulate(scene, params={"mooring.l0.seabed_friction": 0.3})
    with pytest.raises(SceneError, match=r"^mooring.l0.seabed_friction: cannot be traced on a lumped line"):
        traceable(scene, ["mooring.l0.seabed_friction"])


@pytest.mark.slow
def test_batch_over_a_lumped_line_value_is_each_runs():
    scene = _scene()
    res, statuses = simulate_batch(scene, {"mooring.l0.length": np.array([415.0, 425.0])})
    assert statuses == ["ok", "ok"]
    for i, v in enumerate((415.0, 425.0)):
        one = js.simulate(scene, params={"mooring.l0.length": v})
        np.testing.assert_allclose(np.asarray(res.mooring["l0"].fairlead_tension)[i],
                                   np.asarray(one.mooring["l0"].fairlead_tension), rtol=1e-9)


@pytest.mark.slow
def test_gradient_of_a_run_in_a_lumped_line_value():
    scene = _scene()

    def surge(x):
        return js.simulate(scene, params={"mooring.l0.length": x}).vessel.position[-1, 0]

    g = float(jax.grad(surge)(420.0))
    fd = (float(surge(420.05)) - float(surge(419.95))) / 0.1
    assert abs(g) > 0
    assert g == pytest.approx(fd, rel=1e-4)
