"""The Python API around simulate: stepping by hand, run status as codes, raising inside jax.jit,
and no recompilation of a scene already compiled (single runs and batches)."""
import equinox as eqx
import h5py
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.run import loop

from helpers import vessel_scene


def _failing(duration=0.2):
    """A scene whose first step cannot converge: one Newton iteration allowed, a tolerance below round-off."""
    text = vessel_scene(duration=duration, omega=(0.05, 0.02, 0.0)).text
    return js.load_scene(text.replace("[simulation]", "[simulation]\nmax_iterations = 1\ntolerance = 1e-16"))


def test_stepping_by_hand_gives_the_states_of_simulate():
    scene = vessel_scene(duration=0.3, omega=(0.05, 0.02, 0.0))
    ref = js.simulate(scene)
    stepper = js.Stepper(scene)
    state = stepper.init()
    for k in range(1, 31):
        state = stepper.step(state)
        if k % 10 == 0:
            np.testing.assert_allclose(np.asarray(stepper.roll_pitch_yaw(state)),
                                       np.asarray(ref.vessel.roll_pitch_yaw[k]), rtol=0, atol=1e-13)
    assert stepper.status(state) == "ok" and int(state.code) == js.Status.OK
    frame = stepper.observe(state)
    assert abs(float(frame.t) - 0.3) < 1e-12
    np.testing.assert_allclose(np.asarray(frame.X0), np.asarray(ref.vessel.position[-1]), atol=1e-13)


def test_a_failure_is_a_code_with_its_text_in_the_result_and_the_file(tmp_path):
    scene = _failing()
    r = js.simulate(scene, throw=False)
    assert r.status_code == js.Status.NEWTON and r.status != "ok"
    assert "step 1" in r.status and "Newton did not converge" in r.status
    stepper = js.Stepper(scene)
    state = stepper.step(stepper.init())
    assert int(state.code) == js.Status.NEWTON and stepper.status(state) == r.status
    with pytest.raises(js.NumericalFailure, match="Newton did not converge"):
        js.simulate(scene)          # throw=True by default
    path = str(tmp_path / "r.h5")
    js.save_result(r, path)
    with h5py.File(path, "r") as f:
        assert f.attrs["status"] == r.status and int(f.attrs["status_code"]) == js.Status.NEWTON
    back = js.load_result(path)
    assert back.status == r.status and back.status_code == js.Status.NEWTON


def test_a_batch_gives_each_failed_run_the_status_of_its_single_run():
    scene = _failing()
    gm = [1.2, 1.7]
    _, statuses = js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": np.asarray(gm)})
    singles = [js.simulate(scene, params={"vessel.hydrostatics.gm_t": g}, throw=False).status for g in gm]
    assert statuses == singles and all("step 1" in s and "Newton did not converge" in s for s in statuses)


def test_throw_raises_inside_jax_jit_and_a_good_run_passes():
    scene = _failing()
    run = jax.jit(lambda gm: js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm}, throw=True).time[-1])
    with pytest.raises(Exception, match="Newton did not converge"):
        jax.block_until_ready(run(1.5))
    good = vessel_scene(duration=0.1, omega=(0.05, 0.02, 0.0))
    ok = jax.jit(lambda gm: js.simulate(good, params={"vessel.hydrostatics.gm_t": gm}, throw=True).time[-1])
    assert abs(float(ok(1.5)) - 0.1) < 1e-12


def test_a_scene_compiles_once_for_runs_and_batches():
    scene = vessel_scene(duration=0.1, omega=(0.03, 0.01, 0.0))
    js.simulate(scene)
    n_init, n_loop = eqx.debug.get_num_traces(loop.traced_init), eqx.debug.get_num_traces(loop.traced_advance)
    for gm in (1.2, 1.7):        # other values of a traced parameter: the same program
        js.simulate(js.load_scene(scene.text.replace("gm_t = 1.5", f"gm_t = {gm}")))
    js.simulate(scene)
    assert eqx.debug.get_num_traces(loop.traced_init) == n_init
    assert eqx.debug.get_num_traces(loop.traced_advance) == n_loop
    gm = np.array([1.2, 1.5, 1.8, 2.1])
    js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm})
    n_batch = eqx.debug.get_num_traces(loop.traced_advance)
    r, _ = js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm + 0.1})
    assert eqx.debug.get_num_traces(loop.traced_advance) == n_batch
    assert np.asarray(r.time).shape == (4, 11)
    assert jnp.all(jnp.isfinite(r.vessel.roll_pitch_yaw))


def test_api_messages_name_what_the_caller_can_give(tmp_path):
    """Issue 31, item 16: an unknown probe names the scene's probes; js.campaign's errors name its
    keyword arguments (limits=, seeds=), not the command line's flags (which `jaxslosh campaign` keeps);
    a damping ratio list longer than a sparse mesh's sloshing modes says how many were searched."""
    from test_campaign import SCATTER, scene_text
    from helpers import VESSEL
    tank = ('\n[[tanks]]\nname = "t"\norigin = [-1.0, -1.0, -1.0]\nsize = [2.0, 2.0, 2.0]\nfill_depth = 1.0\n'
            'mesh = [2, 2, 2]\n[[probes]]\nname = "A"\ntank = "t"\npoint = [2.0, 1.0, 0.0]\n'
            '[[probes]]\nname = "B"\ntank = "t"\npoint = [2.0, 1.0, 1.0]\n')
    scene = js.load_scene(VESSEL.format(duration=0.1, dt=0.05, scheme="hht", alpha=0.01, omega=[0.0, 0.0, 0.0],
                                        position=[0.0, 0.0, 0.0]) + tank)
    stepper = js.Stepper(scene)
    state = stepper.init()
    assert np.asarray(stepper.probe(state, "B")).shape == (3,)
    with pytest.raises(ValueError, match=r"no probe named 'nope'; the scene's probes: A, B"):
        stepper.probe(state, "nope")
    from jaxslosh.campaign.run import CampaignError
    template = js.load_scene(scene_text())
    for kw, msg in (({"limits": {"yaw": 0.1}}, r"^limits\['yaw'\]: not a channel"),
                    ({"limits": {"roll": -1.0}}, r"^limits\['roll'\]: must be a positive number"),
                    ({"seeds": 0}, r"^seeds: must be at least 1")):
        with pytest.raises(CampaignError, match=msg) as e:
            js.campaign(template, SCATTER, **kw)
        assert "--" not in str(e.value) and e.value.cli.startswith("--")
    from jaxslosh.run.simulate import prepare
    text = open(js.__file__.replace("jaxslosh/__init__.py", "scenes/paper_ship_tank.toml")).read()
    text = text.replace("save_every = 1", 'save_every = 1\nlinear_solver = "sparse"').replace(
        'walls = "rigid"\n', 'walls = "rigid"\n[tanks.damping]\nratio = [' + ", ".join(["0.01"] * 60) + ']\n')
    with pytest.raises(js.SceneError, match=r"gives 60 damping ratios, but the 48 lowest modes searched on this "
                                            r"mesh hold \d+ sloshing modes"):
        prepare(js.load_scene(text))


def test_a_failed_run_under_jit_says_so_raising_by_default_or_as_its_outcome():
    """Under jax.jit the outcome is a leaf: the same failed run that eager code reports as a
    NumericalFailure raises by default, and with throw=False returns its code and step (not "ok"
    and every step done)."""
    scene = _failing(duration=0.5)
    eager = js.simulate(scene, throw=False)
    assert eager.status_code == js.Status.NEWTON
    f = jax.jit(lambda gm: js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm}).vessel.roll_pitch_yaw)
    with pytest.raises(Exception, match="Newton did not converge"):
        jax.block_until_ready(f(1.5))
    g = jax.jit(lambda gm: js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm}, throw=False))
    r = g(1.5)
    assert bool(r.outcome == js.RunResult.newton) and not bool(r.ok)
    assert r.status_code == js.Status.NEWTON and r.status == eager.status      # the step, time and residual
    assert int(r.failure.step) == 1 and r.steps_done == 0
    # a gradient through the failed run is not a silent number: it raises too
    loss = jax.jit(jax.grad(lambda gm: js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm}
                                                   ).vessel.roll_pitch_yaw[:, 0].sum()))
    with pytest.raises(Exception, match="Newton did not converge"):
        jax.block_until_ready(loss(1.5))


def test_a_good_run_under_jit_is_ok_with_every_step():
    good = vessel_scene(duration=0.1, omega=(0.05, 0.02, 0.0))
    r = jax.jit(lambda gm: js.simulate(good, params={"vessel.hydrostatics.gm_t": gm}))(1.5)
    assert bool(r.ok) and r.status == "ok" and r.steps_done == 10 and int(r.failure.step) == -1


@pytest.mark.slow       # about 30 s: the fast tests above hold the same facts on a scene failing at step 1
def test_the_violent_roll_under_jit_raises_and_reports_its_step():
    """The paper ship set rolling hard (0.6 rad, [0.5, 0.3, 0.2] rad/s): its step 1114 fails eagerly;
    under jax.jit it raises by default and, with throw=False, names the same step."""
    import os
    path = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "paper_ship_tank.toml")
    text = open(path).read().replace("angular_velocity = [0.1, 0.05, 0.0]",
                                     "angular_velocity = [0.5, 0.3, 0.2]\nroll_pitch_yaw = [0.6, 0.0, 0.0]")
    scene = js.load_scene(text.replace("duration = 20.0", "duration = 12.0"))
    with pytest.raises(js.NumericalFailure, match="step 1114"):
        js.simulate(scene)
    run = lambda gm, throw: js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm}, throw=throw)  # noqa: E731
    r = jax.jit(lambda gm: run(gm, False))(1.67)
    assert r.status_code == js.Status.NEWTON and "step 1114" in r.status and r.steps_done == 1113
    with pytest.raises(Exception, match="Newton did not converge"):
        jax.block_until_ready(jax.jit(lambda gm: run(gm, True).time)(1.67))
