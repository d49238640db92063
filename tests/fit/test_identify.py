"""Parameter identification (SPEC sections 2 and 4: `jaxslosh identify`, `js.identify`)."""
import dataclasses
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.fit.identify import FitResult, identify
from jaxslosh.fit.problem import add_noise
from jaxslosh.fit.quality import data_scene_mismatch

from helpers import run_notebook, vessel_scene

ROOT = Path(__file__).resolve().parents[2]
GM = ["vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l"]

DECAY = dict(duration=10.0, omega=(0.1, 0.05, 0.0))   # 10 s of free roll and pitch decay


@pytest.fixture(scope="module")
def decay():
    scene = vessel_scene(**DECAY)
    return scene, js.simulate(scene)


def test_gradient_of_a_trajectory_loss_matches_central_differences():
    """jax.grad (reverse mode, implicit differentiation of every Newton solve) of a loss over the
    whole trajectory, with respect to GM_T, GM_L and the waterplane area (heave is excited, so the
    area matters), against central differences."""
    scene = vessel_scene(**DECAY, position=(0.0, 0.0, 0.1))   # the decay's time loop, compiled once
    keys = GM + ["vessel.hydrostatics.waterplane_area"]
    p0 = np.array([1.5, 15.0, 200.0])

    def loss(p):
        r = js.simulate(scene, params=dict(zip(keys, p)))
        rpy = r.vessel.roll_pitch_yaw
        return jnp.sum(rpy[:, 0] ** 2) + jnp.sum(rpy[:, 1] ** 2) + 100.0 * jnp.sum(r.vessel.position[:, 2] ** 2)

    g = np.asarray(jax.jit(jax.grad(loss))(jnp.asarray(p0)))
    assert np.all(np.abs(g) > 1e-4), g          # every parameter moves the loss
    # the loss compiled once for the six differences: the model built from traced parameters (called
    # eagerly, each call builds it operation by operation)
    h = 1e-5 * p0
    steps = np.concatenate([np.diag(h), -np.diag(h)])
    jloss = jax.jit(loss)
    values = [float(jloss(jnp.asarray(p0 + d))) for d in steps]
    for i in range(3):
        fd = (values[i] - values[3 + i]) / (2 * h[i])
        assert abs(g[i] - fd) <= 1e-5 * abs(fd), (keys[i], g[i], fd)


def test_identify_recovers_gm_from_noisy_roll_decay(decay, monkeypatch):
    """10 s of roll and pitch with 1e-4 rad of noise; GM_T and GM_L started 35 % off."""
    import jaxslosh.fit.problem as problem
    scene, clean = decay
    true = {GM[0]: 1.5, GM[1]: 15.0}
    measured = add_noise(clean, {"roll": 1e-4, "pitch": 1e-4}, seed=7)
    start = {GM[0]: 1.5 * 1.35, GM[1]: 15.0 * 0.65}
    traces = []     # simulate runs in Python only while a function is traced
    real = problem.simulate
    monkeypatch.setattr(problem, "simulate", lambda *a, **k: traces.append(1) or real(*a, **k))
    seen = []
    fit = identify(scene, measured, GM, x0=start, callback=lambda it, v, loss: seen.append((it, loss)))
    assert len(traces) <= 1 and fit.evaluations >= fit.iterations + 1, (len(traces), fit.evaluations)
    assert isinstance(fit, FitResult) and fit.method == "gauss-newton"
    assert fit.converged, fit.message
    for k in GM:
        err = fit.values[k] - true[k]
        assert abs(err) <= 0.01 * true[k], (k, fit.values[k])
        # the standard errors are the right size: the error is a few of them, and they are small
        assert 0 < fit.standard_errors[k] < 1e-3 * true[k], fit.standard_errors
        assert abs(err) <= 6 * fit.standard_errors[k], (k, err, fit.standard_errors[k])
    # heave is identically zero in this decay: no weight; roll and pitch by 1 / std
    assert fit.channels["heave"] == 0.0 and fit.channels["roll"] > 0 and fit.channels["pitch"] > 0
    # the loss falls from O(1) to the noise floor: mean over roll, pitch of (noise * weight)^2
    floor = np.mean([(1e-4 * fit.channels[c]) ** 2 for c in ("roll", "pitch")])
    assert fit.loss_history[0] > 1e3 * floor
    assert 0.8 * floor < fit.loss_history[-1] < 1.2 * floor, (fit.loss_history[-1], floor)
    assert np.all(np.diff(fit.loss_history) <= 0)
    assert len(fit.loss_history) == fit.iterations + 1 and len(seen) == fit.iterations
    assert fit.iterations <= 15
    # at the noise floor: a good fit, R^2 near 1, the residual the size of the noise the record shows
    assert fit.quality == "" and not fit.poor_fit and fit.status == "converged" and fit.data_scene == ""
    for c in ("roll", "pitch"):
        assert fit.r2[c] > 0.999 and 0.8 < fit.residual_to_noise[c] < 1.25, (fit.r2, fit.residual_to_noise)
    # the same problem again (another start): nothing traced or compiled, the same minimum
    again = identify(scene, measured, GM, x0={GM[0]: 1.5 * 0.7, GM[1]: 15.0 * 1.3})
    assert len(traces) <= 1 and again.compile_time == 0.0
    for k in GM:
        assert abs(again.values[k] - fit.values[k]) < 1e-3 * fit.standard_errors[k]


def test_identify_rejects_bad_input(decay):
    scene, measured = decay
    with pytest.raises(js.SceneError, match="vessel.hydrostatics.gm_x"):
        identify(scene, measured, ["vessel.hydrostatics.gm_x"])
    with pytest.raises(js.SceneError, match="simulation.dt"):
        identify(scene, measured, ["simulation.dt"])
    with pytest.raises(js.SceneError, match="vessel.hydrostatics.gm_t"):   # a positive quantity started at 0
        identify(scene, measured, GM, x0={GM[0]: 0.0})
    with pytest.raises(js.SceneError, match="method"):
        identify(scene, measured, GM, method="newton")
    with pytest.raises(js.SceneError, match="weights.yaw"):
        identify(scene, measured, GM, weights={"yaw": 1.0})


def _cli_files(tmp_path, measure=True):
    """The scene of `decay` as a file (identify then reuses the functions compiled for it) and a
    record of a ship whose GM_T is 1.6 m and GM_L 13 m (the scene file says 1.5 m and 15 m)."""
    from helpers import VESSEL
    text = VESSEL.format(duration=DECAY["duration"], dt=0.01, scheme="hht", alpha=0.01, omega=list(DECAY["omega"]),
                         position=[0.0, 0.0, 0.0])
    scene_path = tmp_path / "ship.toml"
    scene_path.write_text(text)
    data = tmp_path / "measured.h5"
    if measure:
        r = js.simulate(js.load_scene(text), params={GM[0]: 1.6, GM[1]: 13.0})
        js.save_result(add_noise(r, {"roll": 1e-4, "pitch": 1e-4}, seed=3), data)
    return scene_path, data


def test_cli_identify_writes_json(tmp_path, capsys):
    from jaxslosh.cli import main
    scene_path, data = _cli_files(tmp_path)
    out = tmp_path / "fit.json"
    code = main(["identify", str(scene_path), "--data", str(data), "--fit", ",".join(GM), "-o", str(out)])
    printed = capsys.readouterr().out
    assert code == 0, printed
    fit = json.loads(out.read_text())
    assert {"values", "standard_errors", "loss_history", "iterations", "converged", "method"} <= set(fit)
    assert fit["method"] == "gauss-newton" and fit["converged"] is True
    assert fit["quality"] == "good" and fit["data_scene"] is None and min(fit["r2"].values()) > 0.999, fit
    for k, true in zip(GM, (1.6, 13.0)):
        assert abs(fit["values"][k] - true) < 1e-3 * true, fit
        assert fit["standard_errors"][k] > 0
    assert fit["iterations"] == len(fit["loss_history"]) - 1
    assert GM[0] in printed and GM[1] in printed


@pytest.mark.parametrize("argv_tail, named", [
    (["--fit", "vessel.hydrostatics.gm_q"], "vessel.hydrostatics.gm_q"),
    (["--fit", "vessel.hydrostatics.gm_t,tanks.tank.fill_depth"], "tanks.tank.fill_depth"),
    (["--fit", "simulation.dt"], "simulation.dt"),
])
def test_cli_identify_bad_key(tmp_path, capsys, decay, argv_tail, named):
    from jaxslosh.cli import main
    scene_path, data = _cli_files(tmp_path, measure=False)
    js.save_result(decay[1], data)
    out = tmp_path / "fit.json"
    code = main(["identify", str(scene_path), "--data", str(data), "-o", str(out)] + argv_tail)
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and named in err, err
    assert not out.exists()


def test_cli_identify_bad_data(tmp_path, capsys):
    from jaxslosh.cli import main
    scene_path, data = _cli_files(tmp_path, measure=False)
    not_result = tmp_path / "other.h5"
    import h5py
    with h5py.File(not_result, "w") as f:
        f["x"] = np.zeros(3)
    for path in (tmp_path / "missing.h5", not_result, scene_path):
        code = main(["identify", str(scene_path), "--data", str(path), "--fit", GM[0]])
        err = capsys.readouterr().err
        assert code == 2 and len(err.strip().splitlines()) == 1 and "--data" in err and str(path) in err, err


def _other_scene_record(path, **changes):
    """A record (noise 1e-4 rad) made with the `_cli_files` scene text changed: {old: new} lines."""
    from helpers import VESSEL
    text = VESSEL.format(duration=DECAY["duration"], dt=0.01, scheme="hht", alpha=0.01, omega=list(DECAY["omega"]),
                         position=[0.0, 0.0, 0.0])
    for old, new in changes.items():
        assert old in text
        text = text.replace(old, new)
    js.save_result(add_noise(js.simulate(js.load_scene(text)), {"roll": 1e-4, "pitch": 1e-4}, seed=5), path)
    return path


def test_cli_identify_refuses_data_from_another_scene(tmp_path, capsys):
    """Issue 21: the record's file carries the scene that made it; one that differs in a value that
    is not fitted (vessel.mass 4.4e5 against 4.0e5; and the initial roll rate reversed) is refused
    with exit 2 and one line naming the keys and both values, before anything is compiled. With
    --data-scene ignore it is fitted, and the fit, GM_T unable to turn the roll around, says it
    is poor instead of a bare "converged" (R^2 about -0.2 on roll; the residual 650 times the
    record's noise, pitch's 1.0 times)."""
    from jaxslosh.cli import main
    scene_path, _ = _cli_files(tmp_path, measure=False)
    data = _other_scene_record(tmp_path / "other.h5", **{"mass = 4.0e5": "mass = 4.4e5",
                                                         "angular_velocity = [0.1,": "angular_velocity = [-0.1,"})
    out = tmp_path / "fit.json"
    argv = ["identify", str(scene_path), "--data", str(data), "--fit", ",".join(GM), "-o", str(out)]
    code = main(argv)
    captured = capsys.readouterr()
    err = captured.err
    assert code == 2 and not out.exists() and captured.out == "", captured
    assert len(err.strip().splitlines()) == 1, err
    assert "vessel.mass = 440000.0 in the data's scene, 400000.0 here" in err, err
    assert "vessel.initial.angular_velocity" in err and "--data-scene ignore" in err, err
    assert "gm_t =" not in err and "duration" not in err         # fitted and harmless keys are not named

    code = main(argv + ["--data-scene", "ignore"])
    captured = capsys.readouterr()
    assert code == 0, captured
    assert "vessel.mass" in captured.err                          # said, not refused
    summary = [line for line in captured.out.splitlines() if line.startswith("gauss-newton:")]
    assert summary and "poor fit: R^2" in summary[0] and "on roll" in summary[0], captured.out
    fit = json.loads(out.read_text())
    assert fit["quality"].startswith("poor fit: R^2") and "on roll" in fit["quality"] and "pitch" not in fit["quality"]
    assert fit["r2"]["roll"] < 0.5 and fit["r2"]["pitch"] > 0.999, fit["r2"]
    assert fit["residual_to_noise"]["roll"] > 50 and fit["residual_to_noise"]["pitch"] < 1.5, fit
    assert "vessel.mass" in fit["data_scene"]


def test_identify_warns_on_data_from_another_scene(tmp_path, decay):
    """The Python API warns (and fits) where the command refuses; data_scene="error" raises,
    "ignore" says nothing. A record that differs only in fitted keys, or carries no scene, passes."""
    import warnings
    scene, _ = decay
    data = _other_scene_record(tmp_path / "heavier.h5", **{"mass = 4.0e5": "mass = 4.4e5"})
    with pytest.warns(UserWarning, match=r"vessel\.mass = 440000\.0 in the data's scene, 400000\.0 here"):
        fit = identify(scene, data, GM, max_iter=0)
    assert "vessel.mass" in fit.data_scene
    with pytest.raises(js.SceneError, match="vessel.mass"):
        identify(scene, data, GM, data_scene="error")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert identify(scene, data, GM, max_iter=0, data_scene="ignore").data_scene != ""
        external = dataclasses.replace(js.load_result(data), scene_text="")     # data from elsewhere
        assert identify(scene, external, GM, max_iter=0).data_scene == ""
    # the comparison alone: fitted keys and the duration do not count, anything else does
    text = scene.text.replace("gm_t = 1.5", "gm_t = 1.6").replace("duration = 10.0", "duration = 12.0")
    other = dataclasses.replace(js.load_result(data), scene_text=text)
    assert data_scene_mismatch(scene, other, GM) == ""
    assert data_scene_mismatch(scene, other, GM[1:]).endswith(
        "vessel.hydrostatics.gm_t = 1.6 in the data's scene, 1.5 here (fitted: vessel.hydrostatics.gm_l)")
    broken = dataclasses.replace(other, scene_text=text + '[[probes]]\nname = "deck"\ntank = "none"\npoint = [0, 0, 0]\n')
    assert "does not load" in data_scene_mismatch(scene, broken, GM)


def _execute_notebook(env):
    outputs = run_notebook("identify_metacentric_heights.ipynb", env, timeout=1200)
    assert sum("image/png" in o.get("data", {}) for o in outputs) >= 2     # the loss curve and the fit
    text = "".join(o.get("text", "") for o in outputs)
    assert "converged=True" in text


def test_notebook_executes():
    """The notebook's small run, on the ship without its tank (the paper scene's liquid makes the
    first compilation of the fit take minutes; benchmarks/ runs that case)."""
    _execute_notebook({"JAXSLOSH_NOTEBOOK_SMALL": "1", "JAXSLOSH_NOTEBOOK_SCENE": "scenes/vessel_only.toml"})
