"""Figures of a result: the free surface at a few instants and its animation (`jaxslosh plot --animate`).

The result here is written by hand (a first sloshing mode standing in the small tank of a gently
rolling ship), so the figures are tested in seconds without compiling a run; the notebook test
animates a real run of the paper example."""
import numpy as np
import pytest
from PIL import Image, ImageSequence

from jaxslosh.cli import main
from jaxslosh.fem.mesh import box_elements as _box_elements
from jaxslosh.plot.surface import animate_free_surface, plot_free_surface
from jaxslosh.io.result import Energy, Result, SolverHistory, TankField, VesselHistory, save_result

from helpers import VESSEL

SIZE, DEPTH, MESH = (4.0, 3.0, 3.0), 2.0, (4, 3, 2)
TANK = f"""
[[tanks]]
name = "tank"
origin = [-2.0, -1.5, -1.0]
size = [{SIZE[0]}, {SIZE[1]}, {SIZE[2]}]
fill_depth = {DEPTH}
mesh = [{MESH[0]}, {MESH[1]}, {MESH[2]}]
"""


def hand_result(n=13, dt=0.05, sloshing=0.05, roll=0.05, tanks=True):
    """n frames: the surface rises at one wall and falls at the other (amplitude `sloshing`, m, the
    tank's first mode at 2.4 rad/s) while the ship rolls (amplitude `roll`, rad, at 1.1 rad/s)."""
    t = dt * np.arange(n)
    nx, ny, nz = MESH
    X, Y, Z = np.meshgrid(np.linspace(0, SIZE[0], nx + 1), np.linspace(0, SIZE[1], ny + 1),
                          np.linspace(0, DEPTH, nz + 1), indexing="ij")
    nodes = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    D = np.zeros((n, len(nodes), 3))
    D[:, :, 2] = sloshing * np.sin(2.4 * t)[:, None] * (np.cos(np.pi * nodes[:, 0] / SIZE[0])
                                                        * nodes[:, 2] / DEPTH)[None, :]
    phi = roll * np.sin(1.1 * t)
    q = np.stack([np.cos(phi / 2), np.sin(phi / 2), 0 * t, 0 * t], axis=1)
    zeros3 = np.zeros((n, 3))
    rpy = np.stack([phi, 0 * t, 0 * t], axis=1)
    omega = np.stack([roll * 1.1 * np.cos(1.1 * t), 0 * t, 0 * t], axis=1)
    scene = VESSEL.format(duration=dt * (n - 1), dt=dt, scheme="hht", alpha=0.01, omega=[0.0, 0.0, 0.0],
                          position=[0.0, 0.0, 0.0]) + TANK
    field = {"tank": TankField(nodes, _box_elements(nx, ny, nz), D)} if tanks else {}
    return Result(time=t, vessel=VesselHistory(zeros3, q, omega, rpy), probes={}, energy=Energy(0 * t, 0 * t),
                  solver=SolverHistory(0 * t, 0 * t), tanks=field, status="ok", steps_done=n - 1, scene_text=scene)


def _frames(path):
    with Image.open(path) as im:
        return im.n_frames, [np.asarray(f.convert("RGB"), dtype=float) for f in ImageSequence.Iterator(im)]


def _body(frames):
    """The frames below the titles (the time is written there)."""
    return [f[f.shape[0] // 6:] for f in frames]


def test_animation_writes_one_gif_frame_per_shown_instant_and_the_surface_moves(tmp_path):
    result = hand_result(roll=0.0)                       # the ship held still: only the surface moves
    gif = tmp_path / "surface.gif"
    assert animate_free_surface(result, str(gif), scale=20.0, every=3) == 5      # frames 0, 3, 6, 9, 12
    n, frames = _frames(gif)
    assert n == 5
    body = _body(frames)
    for a, b in zip(body[:-1], body[1:]):
        assert np.abs(a - b).mean() > 0.5                # every frame differs from the one before (measured 1 to 4)
    # a still surface on a still ship: below the titles, the frames differ by a few stray pixels only
    # (the depth order of a flat surface's triangles, the palette; measured 0.02 to 0.05)
    still = tmp_path / "still.gif"
    assert animate_free_surface(hand_result(sloshing=0.0, roll=0.0), str(still), every=3) == 5
    n, frames = _frames(still)
    assert n == 5 and all(np.abs(b - _body(frames)[0]).mean() < 0.3 for b in _body(frames))
    # the default stride keeps at most max_frames
    assert animate_free_surface(result, str(tmp_path / "few.gif"), max_frames=4) == 4   # frames 0, 4, 8, 12
    assert _frames(tmp_path / "few.gif")[0] == 4
    with pytest.raises(ValueError, match="every"):
        animate_free_surface(result, str(tmp_path / "bad.gif"), every=0)


def test_plot_surface_and_animate_from_the_command_line(tmp_path, capsys):
    h5 = tmp_path / "r.h5"
    save_result(hand_result(), str(h5))
    png, surf, gif = tmp_path / "r.png", tmp_path / "s.png", tmp_path / "a.gif"
    assert main(["plot", str(h5), "-o", str(png), "--surface", str(surf), "--animate", str(gif), "--scale", "20",
                 "--every", "4", "--fps", "5"]) == 0
    out = capsys.readouterr().out
    assert f"wrote {gif} (4 frames)" in out
    assert png.stat().st_size > 1000 and surf.stat().st_size > 1000
    n, _ = _frames(gif)
    assert n == 4
    with Image.open(gif) as im:
        assert im.info.get("duration") == 200            # 5 frames per second
    # bad input: exit 2, one line naming the flag
    for args, flag in ([["--animate", str(tmp_path / "a.mp4")], "--animate"],
                       [["--animate", str(gif), "--every", "0"], "--every"],
                       [["--animate", str(gif), "--fps", "-1"], "--fps"],
                       [["--animate", str(tmp_path / "missing" / "a.gif")], "--animate"]):
        assert main(["plot", str(h5), "-o", str(png)] + args) == 2
        err = capsys.readouterr().err
        assert flag in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_surface_figures_need_liquid_fields(tmp_path, capsys):
    dry = hand_result(tanks=False)
    with pytest.raises(ValueError, match="no liquid fields"):
        animate_free_surface(dry, str(tmp_path / "a.gif"))
    with pytest.raises(ValueError, match="no liquid fields"):
        plot_free_surface(dry, str(tmp_path / "s.png"))
    h5 = tmp_path / "dry.h5"
    save_result(dry, str(h5))
    assert main(["plot", str(h5), "--animate", str(tmp_path / "a.gif")]) == 2
    assert "--animate" in capsys.readouterr().err and not (tmp_path / "a.gif").exists()


def test_surface_axes_are_labelled_in_metres(tmp_path):
    fig = plot_free_surface(hand_result(), str(tmp_path / "s.png"))
    assert len(fig.axes) == 4
    for ax in fig.axes:
        assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("X (m)", "Y (m)", "Z (m)")


def test_animation_reports_the_frames_written(tmp_path):
    calls = []
    n = animate_free_surface(hand_result(), str(tmp_path / "a.gif"), every=4,
                             progress=lambda done, total: calls.append((done, total)))
    assert n == 4
    # one call as each frame is drawn (frames written before it), then the last: all of them
    assert calls == [(0, 4), (1, 4), (2, 4), (3, 4), (4, 4)]
