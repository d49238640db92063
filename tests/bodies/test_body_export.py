"""`jaxslosh export --paraview` of a scene with bodies: each body its own XDMF time series, read
back with meshio, its points where the result's /bodies/<name>/position and quaternion put them
(docs/guide/paraview.md)."""
import h5py
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli import main
from jaxslosh.physics.kinematics import rotation_matrix

meshio = pytest.importorskip("meshio")
from meshio.xdmf import TimeSeriesReader  # noqa: E402

SCENE = """
[simulation]
duration = 1.0
dt = 0.05
[vessel]
name = "ship"
mass = 4.1e5
inertia = [5.13e6, 1.474e7, 1.63e7]
cog_height = 1.5
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 400.0
gm_t = 1.67
gm_l = 14.2
[[bodies]]
name = "barge"
position = [3.0, 40.0]
heading = 0.4
cog_height = -0.5
mass = 2.05e5
inertia = [1.5e6, 6.0e6, 7.0e6]
[bodies.hydrostatics]
waterplane_area = 144.0
displaced_volume = 200.0
gm_t = 2.5
gm_l = 20.0
[bodies.initial]
position = [0.0, 0.0, 0.2]
velocity = [0.3, 0.0, 0.0]
angular_velocity = [0.1, 0.05, 0.02]
"""


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    path = tmp_path_factory.mktemp("body_export") / "two.h5"
    js.save_result(js.simulate(js.load_scene(SCENE)), str(path))
    return path


def test_a_body_is_its_own_mesh_moving_with_its_position_and_attitude(result, tmp_path, capsys):
    out = tmp_path / "two.xdmf"
    assert main(["export", str(result), "--paraview", str(out)]) == 0
    assert str(tmp_path / "two_body_barge.xdmf") in capsys.readouterr().out
    r = js.load_result(str(result))
    b = r.bodies["barge"]
    pos, q = np.asarray(b.position), np.asarray(b.quaternion)
    assert np.ptp(pos[:, 0]) > 0.1 and np.ptp(np.asarray(b.roll_pitch_yaw)[:, 0]) > 0.01      # it moves
    rest = np.array([3.0, 40.0, -0.5 - 1.5])         # its COG at rest, from the vessel's COG at rest
    size = 0.5 * np.sqrt(144.0)
    reader = TimeSeriesReader(str(tmp_path / "two_body_barge.xdmf"))
    _, cells = reader.read_points_cells()
    assert reader.num_steps == len(r.time) and cells[0].type == "line" and cells[0].data.shape == (3, 2)
    with h5py.File(tmp_path / "two_paraview.h5", "r") as f:
        for k in (0, 10, len(r.time) - 1):
            geo = f[f"body_barge/geometry/{k}"][()]
            R = np.asarray(rotation_matrix(q[k]))
            np.testing.assert_allclose(geo[0], rest + pos[k], rtol=0, atol=1e-12)
            np.testing.assert_allclose(geo[1:], rest + pos[k] + size * R.T, rtol=0, atol=1e-12)
    # at rest its x axis is along its heading
    np.testing.assert_allclose(np.asarray(rotation_matrix(q[0]))[:, 0], [np.cos(0.4), np.sin(0.4), 0.0], atol=1e-12)
    # the vessel alone keeps its own file, as before
    _, c = TimeSeriesReader(str(tmp_path / "two.xdmf")).read_points_cells()
    assert c[0].type == "line" and c[0].data.shape == (3, 2)


def test_a_bodys_box_hull_is_its_wetted_box_at_its_own_height(tmp_path, capsys):
    """A body with a box hull (its COG height kg - draft, no `cog_height`) is drawn as its wetted box,
    keel to waterline, where its rest pose and the result's motion put it: at rest its waterline
    corners lie on the still water (z = 0 above the vessel's COG at rest, 1.5 m below it)."""
    L, B, T, kg = 12.0, 8.0, 2.0, 2.5
    hull = f"[bodies.hull]\nlength = {L}\nbeam = {B}\ndraft = {T}\nkg = {kg}\n[bodies.hydrostatics]\n"
    text = SCENE.replace("cog_height = -0.5\n", "").replace("[bodies.hydrostatics]\n", hull)
    text = text.replace("waterplane_area = 144.0\ndisplaced_volume = 200.0\ngm_t = 2.5\ngm_l = 20.0\n", "")
    text = text.replace("mass = 2.05e5", f"mass = {1025.0 * L * B * T}")
    scene = js.load_scene(text)
    assert scene.bodies[0].hull is not None and scene.bodies[0].cog_height == pytest.approx(kg - T)
    path = tmp_path / "hull.h5"
    js.save_result(js.simulate(scene), str(path))
    out = tmp_path / "hull.xdmf"
    assert main(["export", str(path), "--paraview", str(out)]) == 0
    r = js.load_result(str(path))
    b = r.bodies["barge"]
    pos, q = np.asarray(b.position), np.asarray(b.quaternion)
    rest = np.array([3.0, 40.0, (kg - T) - 1.5])
    _, cells = TimeSeriesReader(str(tmp_path / "hull_body_barge.xdmf")).read_points_cells()
    assert cells[0].type == "hexahedron" and cells[0].data.shape == (1, 8)
    corners = np.array([[x, y, z] for z in (-kg, T - kg) for y in (-B / 2, B / 2) for x in (-L / 2, L / 2)])
    with h5py.File(tmp_path / "hull_paraview.h5", "r") as f:
        for k in (0, 10, len(r.time) - 1):
            geo = f[f"body_barge/geometry/{k}"][()]
            want = rest + pos[k] + corners @ np.asarray(rotation_matrix(q[k])).T
            np.testing.assert_allclose(np.sort(geo, axis=0), np.sort(want, axis=0), rtol=0, atol=1e-12)
        top = f["body_barge/geometry/0"][()][:, 2].max()
    assert pos[0, 2] == pytest.approx(0.2) and top == pytest.approx(-1.5 + 0.2, abs=1e-12)   # its waterline, lifted 0.2 m
