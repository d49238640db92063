"""Figures of a result: the free surface at a few instants and its animation (`jaxslosh plot --animate`).

The result here is written by hand (a first sloshing mode standing in the small tank of a gently
rolling ship), so the figures are tested in seconds without compiling a run; the notebook test
animates a real run of the paper example."""
import dataclasses

import numpy as np
import pytest
from PIL import Image, ImageSequence

from jaxslosh.cli import main
from jaxslosh.fem.mesh import box_elements as _box_elements
from jaxslosh.plot.surface import animate_free_surface, plot_free_surface
from jaxslosh.io.result import Energy, Result, SolverHistory, TankField, VesselHistory, load_result, save_result

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
    assert len(fig.axes) == 5                            # four instants and the elevation's colour bar
    for ax in fig.axes[:4]:
        assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("X (m)", "Y (m)", "Z (m)")
    assert fig.axes[4].get_ylabel() == "free-surface elevation (m)"


def _faces(ax):
    """The surface's triangles drawn on a 3D axes and their colours."""
    (coll,) = [c for c in ax.collections if c.get_array() is not None]
    return coll


def test_a_flat_surface_is_one_colour_and_the_colour_scale_is_symmetric_with_a_floor(tmp_path):
    """Issue 31, item 12: round-off on the surface at rest (1e-13 m here) is not a checkerboard; the
    colour bar spans the record's largest elevation either side of rest, with a floor for a still
    surface, and says its unit."""
    r = hand_result()                                    # the surface flat at t = 0, 0.05 m later
    D = np.array(r.tanks["tank"].displacement)
    D[0, :, 2] += 1e-13 * np.random.default_rng(0).standard_normal(D.shape[1])
    r = dataclasses.replace(r, tanks={"tank": TankField(r.tanks["tank"].nodes, r.tanks["tank"].elements, D)})
    fig = plot_free_surface(r, str(tmp_path / "s.png"))
    first = _faces(fig.axes[0])
    assert np.unique(np.round(first.get_facecolor(), 6), axis=0).shape[0] == 1      # one colour at rest
    assert len(np.unique(np.round(_faces(fig.axes[1]).get_facecolor(), 6), axis=0)) > 1   # sloshing: several
    high = np.abs(D[:, :, 2]).max()
    assert first.norm.vmin == -first.norm.vmax and abs(first.norm.vmax - high) <= 1e-12
    still = plot_free_surface(hand_result(sloshing=0.0), str(tmp_path / "still.png"))
    assert _faces(still.axes[0]).norm.vmax == pytest.approx(1e-4 * max(SIZE))       # the floor


def test_animation_reports_the_frames_written(tmp_path):
    calls = []
    n = animate_free_surface(hand_result(), str(tmp_path / "a.gif"), every=4,
                             progress=lambda done, total: calls.append((done, total)))
    assert n == 4
    # one call as each frame is drawn (frames written before it), then the last: all of them
    assert calls == [(0, 4), (1, 4), (2, 4), (3, 4), (4, 4)]


def _shaped_result(tank_toml, nodes, elements, n=5, dt=0.1):
    """A hand result of a tank of any shape: its liquid mesh `nodes`, `elements`, the free surface
    (nodes on the highest plane) rising at one end while the ship rolls."""
    t = dt * np.arange(n)
    D = np.zeros((n, len(nodes), 3))
    top = np.isclose(nodes[:, 2], nodes[:, 2].max())
    x = (nodes[:, 0] - nodes[:, 0].min()) / np.ptp(nodes[:, 0])
    D[:, top, 2] = 0.02 * np.sin(2.0 * t)[:, None] * np.cos(np.pi * x[top])[None, :]
    phi = 0.05 * np.sin(t)
    q = np.stack([np.cos(phi / 2), np.sin(phi / 2), 0 * t, 0 * t], axis=1)
    z3 = np.zeros((n, 3))
    scene = VESSEL.format(duration=dt * (n - 1), dt=dt, scheme="hht", alpha=0.01, omega=[0.0, 0.0, 0.0],
                          position=[0.0, 0.0, 0.0]) + tank_toml
    return Result(time=t, vessel=VesselHistory(z3, q, z3, np.stack([phi, 0 * t, 0 * t], axis=1)), probes={},
                  energy=Energy(0 * t, 0 * t), solver=SolverHistory(0 * t, 0 * t),
                  tanks={"tank": TankField(nodes, elements, D)}, status="ok", steps_done=n - 1, scene_text=scene)


def test_every_tank_shape_plots_its_surface_and_animation(tmp_path, capsys):
    """Issue 31, item 5: `plot --surface` and `--animate` of a result of every shape (box, prismatic,
    horizontal and vertical cylinders, and a mesh tank, which gives no fill_depth: KeyError before);
    the drawn surface is the mesh's highest plane, its triangles cover the surface's nodes."""
    meshio = pytest.importorskip("meshio")
    from jaxslosh.fem.mesh import box_mesh
    from jaxslosh.geometry import SHAPES
    path = tmp_path / "liquid.msh"
    nodes, elements = box_mesh((3.0, 2.0, 1.5), (3, 2, 2))
    meshio.write(str(path), meshio.Mesh(nodes, [("hexahedron", elements)]), file_format="gmsh22")
    head = 'name = "tank"\norigin = [-1.5, -1.0, -1.0]\n'
    cases = {
        "mesh": (f'[[tanks]]\n{head}size = [3.0, 2.0, 2.0]\nshape = "mesh"\nfile = "{path}"\n', nodes, elements),
    }
    for shape, extra, size, mesh in (
            ("box", "", (3.0, 2.0, 2.0), (3, 2, 2)),
            ("prismatic", "chamfers = [[0.5, 0.5], [0.0, 0.0]]\n", (3.0, 2.0, 2.0), (3, 4, 2)),
            ("cylinder", 'axis = "x"\n', (3.0, 2.0, 2.0), (3, 4, 4)),
            ("cylinder-z", 'axis = "z"\n', (2.0, 2.0, 2.0), (4, 4, 2))):
        kind = shape.split("-")[0]
        own = {"axis": "z" if shape.endswith("-z") else "x", "chamfers": ((0.5, 0.5), (0.0, 0.0))}
        geo = SHAPES[kind](size=size, **{k: x for k, x in own.items() if k in SHAPES[kind].keys})
        tm = geo.mesh(1.2, mesh)
        text = (f'[[tanks]]\n{head}size = [{size[0]}, {size[1]}, {size[2]}]\nshape = "{kind}"\n{extra}'
                f'fill_depth = 1.2\nmesh = [{mesh[0]}, {mesh[1]}, {mesh[2]}]\n')
        cases[shape] = (text, tm.nodes, tm.elements)
    for shape, (text, nd, el) in cases.items():
        h5, surf, gif = tmp_path / f"{shape}.h5", tmp_path / f"{shape}_s.png", tmp_path / f"{shape}.gif"
        # two saved frames: an animation of two (3-D frames are what this test's time goes to)
        save_result(_shaped_result(text, np.asarray(nd, float), np.asarray(el), n=2), str(h5))
        assert main(["plot", str(h5), "-o", str(tmp_path / f"{shape}.png"), "--surface", str(surf),
                     "--animate", str(gif)]) == 0, (shape, capsys.readouterr().err)
        assert surf.stat().st_size > 1000 and _frames(gif)[0] == 2, shape
        # the surface drawn at one instant (the command's figure draws four of them)
        fig = plot_free_surface(load_result(str(h5)), str(tmp_path / f"{shape}_one.png"), times=[0.1])
        faces = _faces(fig.axes[0])
        top = np.isclose(np.asarray(nd)[:, 2], np.asarray(nd)[:, 2].max())
        # two triangles per surface face, every surface node drawn
        assert len(faces.get_array()) == 2 * (top[np.asarray(el)][:, 4:].all(axis=1)).sum(), shape
