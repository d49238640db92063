"""`jaxslosh export RESULT.h5 --paraview OUT.xdmf` (issue 20): XDMF time series read back with
meshio; the liquid's exported geometry against the model's own probe positions, the hull, the
structures, the probes; bad input."""
import dataclasses
from pathlib import Path

import h5py
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli import main
from jaxslosh.io.paraview import export_paraview
from jaxslosh.physics.kinematics import rotation_matrix

meshio = pytest.importorskip("meshio")
from meshio.xdmf import TimeSeriesReader  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """The paper example for 1.5 s, with a probe on a free-surface node (4, 2, 3)."""
    text = (ROOT / "scenes" / "paper_ship_tank.toml").read_text().replace("duration = 20.0", "duration = 1.5") + \
        '\n[[probes]]\nname = "N"\ntank = "tank"\npoint = [4.0, 2.0, 3.0]\n'
    path = tmp_path_factory.mktemp("export") / "paper.h5"
    js.save_result(js.simulate(js.load_scene(text)), str(path))
    return path


def test_export_reads_back_with_meshio(result, tmp_path, capsys):
    out = tmp_path / "pv" / "paper.xdmf"
    out.parent.mkdir()
    assert main(["export", str(result), "--paraview", str(out)]) == 0
    assert "done: 151 frames" in capsys.readouterr().out
    r = js.load_result(str(result))
    tank = r.tanks["tank"]
    with TimeSeriesReader(str(out)) as reader:
        points, cells = reader.read_points_cells()
        assert reader.num_steps == 151
        assert cells[0].type == "hexahedron" and cells[0].data.shape == (125, 8)
        np.testing.assert_array_equal(cells[0].data, np.asarray(tank.elements))
        for k in (0, 75, 150):
            t, pd, _ = reader.read_data(k)
            assert t == pytest.approx(float(r.time[k]))
            np.testing.assert_allclose(pd["displacement"], np.asarray(tank.displacement)[k], rtol=0, atol=1e-15)
            np.testing.assert_allclose(pd["elevation"], np.asarray(tank.displacement)[k, :, 2], rtol=0, atol=1e-15)
    # frame k's geometry is the model's own: the probe on node (4, 2, 3) sits where the run put it
    nodes = np.asarray(tank.nodes)
    i = int(np.argmin(np.linalg.norm(nodes - [4.0, 2.0, 3.0], axis=1)))
    with h5py.File(tmp_path / "pv" / "paper_paraview.h5", "r") as f:
        for k in (0, 150):
            geo = f[f"liquid/geometry/{k}"][()]
            np.testing.assert_allclose(geo[i], np.asarray(r.probes["N"].position)[k], rtol=0, atol=1e-12)
            A = np.asarray(rotation_matrix(np.asarray(r.vessel.quaternion)[k]))
            body = nodes + [-2.5, -2.5, -1.0] + np.asarray(tank.displacement)[k]
            np.testing.assert_allclose(geo, np.asarray(r.vessel.position)[k] + body @ A.T, rtol=0, atol=1e-12)
    # the free surface: the 25 top faces; the vessel's frame; the probes
    surf = TimeSeriesReader(str(tmp_path / "pv" / "paper_surface.xdmf"))
    _, c = surf.read_points_cells()
    assert c[0].type == "quad" and c[0].data.shape == (25, 4)
    assert np.all(np.isclose(nodes[c[0].data, 2], 3.0))
    _, c = TimeSeriesReader(str(tmp_path / "pv" / "paper_vessel.xdmf")).read_points_cells()
    assert c[0].type == "line" and c[0].data.shape == (3, 2)
    probes = TimeSeriesReader(str(tmp_path / "pv" / "paper_probes.xdmf"))
    p, c = probes.read_points_cells()
    assert c[0].type == "vertex" and p.shape == (3, 3)
    _, pd, _ = probes.read_data(150)
    np.testing.assert_allclose(pd["displacement"][1], np.asarray(r.probes["B"].displacement)[150], atol=1e-15)


def test_export_hull_and_structures(result, tmp_path):
    """The hull as its wetted box carried by the vessel, structures as their blocks."""
    r = js.load_result(str(result))
    text = r.scene_text.replace("[vessel.hydrostatics]", "[vessel.hull]\nlength = 16.0\nbeam = 10.0\ndraft = 2.5\n"
                                                          "kg = 2.9\n\n[vessel.hydrostatics]") + \
        ('\n[[structures]]\nname = "mast"\norigin = [-0.15, -0.15, 1.0]\nsize = [0.3, 0.3, 5.0]\nmesh = [1, 1, 4]\n'
         'attach = "z-"\n[structures.material]\nyoung = 2.1e11\npoisson = 0.3\ndensity = 7850.0\n')
    files = export_paraview(dataclasses.replace(r, scene_text=text), str(tmp_path / "s.xdmf"), every=50)
    assert len(files) == 6
    vessel = TimeSeriesReader(str(tmp_path / "s_vessel.xdmf"))
    p, c = vessel.read_points_cells()
    assert vessel.num_steps == 4 and c[0].type == "hexahedron"
    assert np.allclose(p.min(axis=0), [-8.0, -5.0, -2.9]) and np.allclose(p.max(axis=0), [8.0, 5.0, -0.4])
    p, c = TimeSeriesReader(str(tmp_path / "s_structures.xdmf")).read_points_cells()
    assert c[0].data.shape == (4, 8) and np.isclose(p[:, 2].max(), 6.0)


def test_export_bad_input(result, tmp_path, capsys):
    bad = tmp_path / "bad.h5"
    bad.write_bytes(b"nonsense")
    for args in (["export", str(bad), "--paraview", str(tmp_path / "o.xdmf")],
                 ["export", str(result), "--paraview", str(tmp_path / "o.vtk")],
                 ["export", str(result), "--paraview", str(tmp_path / "missing" / "o.xdmf")],
                 ["export", str(result), "--paraview", str(tmp_path / "o.xdmf"), "--every", "0"]):
        assert main(args) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1, err
