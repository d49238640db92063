"""`jaxslosh plot` of a result with bodies and connections: each body's roll, pitch and heave beside
the vessel's, a panel of the connections' forces (docs/guide/running.md); the vessel alone's
figure keeps its panels."""
import numpy as np

import jaxslosh as js
from jaxslosh.cli import main
from jaxslosh.io.result import ConnectionHistory, Energy, Result, SolverHistory, VesselHistory
from jaxslosh.plot.results import plot_result

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
