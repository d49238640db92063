"""`jaxslosh plot` of a result with bodies and connections: each body's roll, pitch and heave beside
the vessel's, a panel of the connections' forces (docs/guide/running.md); the vessel alone's
figure keeps its panels; a sweep file's runs with their bodies and connections."""
import dataclasses
import types

import jax
import numpy as np

import jaxslosh as js
from jaxslosh.cli import main
from jaxslosh.io.result import ConnectionHistory, Energy, Result, SolverHistory, VesselHistory
from jaxslosh.io.sweep import load_sweep, write_sweep
from jaxslosh.plot.results import plot_result, plot_sweep

SCENE = 'title = "two"\n[simulation]\nduration = 1.0\ndt = 0.1\n'


def _history(t, roll, pitch, heave):
    rpy = np.stack([roll, pitch, 0 * t], axis=1)
    q = np.stack([np.cos(roll / 2), np.sin(roll / 2), 0 * t, 0 * t], axis=1)     # pitch left out: not drawn
    return VesselHistory(np.stack([0 * t, 0 * t, heave], axis=1), q, np.zeros((t.size, 3)), rpy)


def result(bodies=True):
    t = 0.1 * np.arange(11)
    vessel = _history(t, 0.05 * np.sin(t), 0.01 * np.sin(2 * t), 0.1 * np.cos(t))
    extra = {}
    if bodies:
        extra = {"bodies": {"barge": _history(t, 0.08 * np.sin(1.5 * t), 0.02 * np.cos(t), 0.2 * np.sin(t))},
                 "connections": {"bow": ConnectionHistory(1e5 * (1 + np.sin(t)), 0.5 * (1 + np.sin(t))),
                                 "fender": ConnectionHistory(-3e4 * np.abs(np.sin(t)), -0.1 * np.abs(np.sin(t)))}}
    return Result(time=t, vessel=vessel, probes={}, energy=Energy(0 * t, 0 * t), solver=SolverHistory(0 * t, 0 * t),
                  tanks={}, status="ok", steps_done=10, scene_text=SCENE, **extra)


def _lines(ax):
    return {ln.get_label(): ln.get_ydata() for ln in ax.get_lines()}


def test_the_bodies_motions_and_the_connections_forces_are_drawn(tmp_path):
    r = result()
    fig = plot_result(r, str(tmp_path / "a.png"))
    axes = fig.get_axes()
    assert len(axes) == 3 and axes[2].get_ylabel() == "connection force (kN)"
    b = r.bodies["barge"]
    angles, heave, force = (_lines(a) for a in axes)
    np.testing.assert_allclose(angles["barge roll"], np.degrees(b.roll_pitch_yaw[:, 0]), rtol=1e-15)
    np.testing.assert_allclose(angles["barge pitch"], np.degrees(b.roll_pitch_yaw[:, 1]), rtol=1e-15)
    np.testing.assert_allclose(angles["roll"], np.degrees(r.vessel.roll_pitch_yaw[:, 0]), rtol=1e-15)
    np.testing.assert_allclose(heave["barge"], b.position[:, 2], rtol=1e-15)
    np.testing.assert_allclose(heave["vessel"], r.vessel.position[:, 2], rtol=1e-15)
    np.testing.assert_allclose(force["bow"], 1e-3 * r.connections["bow"].force, rtol=1e-15)
    np.testing.assert_allclose(force["fender"], 1e-3 * r.connections["fender"].force, rtol=1e-15)


def test_the_vessel_alones_figure_keeps_its_panels(tmp_path):
    fig = plot_result(result(bodies=False), str(tmp_path / "a.png"))
    axes = fig.get_axes()
    assert len(axes) == 2 and [ln.get_label() for ln in axes[0].get_lines()] == ["roll", "pitch"]
    assert len(axes[1].get_lines()) == 1 and axes[1].get_legend() is None


def test_jaxslosh_plot_of_a_result_file_with_bodies(tmp_path, capsys):
    path = tmp_path / "two.h5"
    js.save_result(result(), str(path))
    assert main(["plot", str(path), "-o", str(tmp_path / "two.png")]) == 0
    assert (tmp_path / "two.png").stat().st_size > 10000 and "wrote" in capsys.readouterr().out


def test_a_sweep_file_with_bodies_draws_each_runs_bodies_and_connections(tmp_path, capsys):
    """`jaxslosh plot` of a sweep file whose scene has bodies and connections: the file reads them back,
    each body has a panel of its roll and pitch (every run), its heave beside the vessel's, and each
    connection's force its panel's line per run (kN)."""
    runs = [result(), result()]
    runs[1] = dataclasses.replace(runs[1], bodies={"barge": _history(runs[1].time, 0.3 * np.sin(runs[1].time),
                                                                     0 * runs[1].time, 0 * runs[1].time)})
    batch = jax.tree_util.tree_map(lambda *x: np.stack([np.asarray(v) for v in x]), *runs)
    params = {"connections.bow.stiffness": np.array([1e5, 2e5])}
    path = tmp_path / "sweep.h5"
    write_sweep(str(path), types.SimpleNamespace(text=SCENE), params, batch, ["ok", "ok"])
    sw = load_sweep(str(path))
    assert list(sw.result.bodies) == ["barge"] and list(sw.result.connections) == ["bow", "fender"]
    fig = plot_sweep(sw.params, sw.result, sw.statuses, str(tmp_path / "s.png"), sw.scene_text)
    axes = fig.get_axes()
    assert [a.get_ylabel() for a in axes[2:]] == ["barge: roll (solid),\npitch (dashed) (deg)", "connection force (kN)"]
    rolls = [ln.get_ydata() for ln in axes[2].get_lines()][::2]
    for i, r in enumerate(runs):
        np.testing.assert_allclose(rolls[i], np.degrees(r.bodies["barge"].roll_pitch_yaw[:, 0]), rtol=1e-15)
    heave = {ln.get_label(): ln.get_ydata() for ln in axes[1].get_lines() if not ln.get_label().startswith("_")}
    np.testing.assert_allclose(heave["barge"], runs[0].bodies["barge"].position[:, 2], rtol=1e-15)
    force = {ln.get_label(): ln.get_ydata() for ln in axes[3].get_lines() if not ln.get_label().startswith("_")}
    np.testing.assert_allclose(force["fender"], 1e-3 * runs[0].connections["fender"].force, rtol=1e-15)
    assert main(["plot", str(path), "-o", str(tmp_path / "s2.png")]) == 0 and "2 runs" in capsys.readouterr().out
