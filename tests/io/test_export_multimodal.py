"""A multimodal tank's free surface in the result, `export --paraview` and `plot --surface` (issue
43, item 9): a multimodal run keeps its tanks' free surface (one layer of hexahedra over the base,
the top displaced by the elevation the modal coordinates give), ParaView's files hold it, the plot
draws it; a result without fields says why truly. The surface against a probe on it (the probe's
own path through the modes) and, for an upright cylinder, against the Bessel modes' closed form."""
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy import special

import jaxslosh as js
from jaxslosh.liquid.multimodal.build import surface_fields, surface_meshes
from jaxslosh.liquid.multimodal.build3d import tank_3d
from jaxslosh.cli import main

meshio = pytest.importorskip("meshio")
from meshio.xdmf import TimeSeriesReader  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """Faltinsen's tank surged for 0.2 s on 2 modes, a probe on the free surface at the wall x = 0."""
    text = (ROOT / "scenes" / "sloshing_experiment.toml").read_text()
    text = text.replace("duration = 10.0", "duration = 0.2").replace("modes = 8 ", "modes = 2 ")
    text = text.replace("amplitude = 0.032", "amplitude = 0.1")
    text += '\n[[probes]]\nname = "x0"\ntank = "tank"\npoint = [0.0, 0.0, 0.6]\n'
    path = tmp_path_factory.mktemp("multimodal") / "tank.h5"
    r = js.simulate(js.load_scene(text))
    assert r.status == "ok"
    js.save_result(r, str(path))
    return path


@pytest.mark.slow
def test_the_result_keeps_the_free_surface(result):
    r = js.load_result(str(result))
    tank = r.tanks["tank"]
    nodes, D = np.asarray(tank.nodes), np.asarray(tank.displacement)
    assert nodes.shape[0] == D.shape[1] and np.allclose(np.unique(nodes[:, 2]), [0.0, 0.6])
    top, bottom = np.isclose(nodes[:, 2], 0.6), np.isclose(nodes[:, 2], 0.0)
    assert np.all(D[:, bottom] == 0.0) and np.all(D[..., :2] == 0.0)
    i = int(np.flatnonzero(top & (np.linalg.norm(nodes[:, :2], axis=1) < 1e-12))[0])      # the corner x = y = 0
    probe = np.asarray(r.probes["x0"].displacement)[:, 2]                 # inertial: the tank only surges
    assert np.abs(probe).max() > 1e-3
    np.testing.assert_allclose(D[:, i, 2], probe, rtol=0, atol=1e-12 * np.abs(probe).max() + 1e-15)
    # the modes keep the volume: the elevation's mean over the surface (trapezoid along x) is zero
    row = top & np.isclose(nodes[:, 1], 0.0)
    x = nodes[row, 0]
    order = np.argsort(x)
    eta = D[:, row, 2][:, order]
    assert np.abs(np.trapezoid(eta, x[order], axis=1)).max() < 1e-12 * np.abs(eta).max()


@pytest.mark.slow
def test_export_and_plot_draw_the_multimodal_surface(result, tmp_path, capsys):
    out = tmp_path / "tank.xdmf"
    assert main(["export", str(result), "--paraview", str(out)]) == 0
    captured = capsys.readouterr()
    assert "no liquid fields" not in captured.err and str(tmp_path / "tank_surface.xdmf") in captured.out
    r = js.load_result(str(result))
    D = np.asarray(r.tanks["tank"].displacement)
    with TimeSeriesReader(str(tmp_path / "tank_surface.xdmf")) as reader:
        _, cells = reader.read_points_cells()
        assert cells[0].type == "quad" and cells[0].data.shape[0] == 24          # the top faces
        t, pd, _ = reader.read_data(reader.num_steps - 1)
        np.testing.assert_allclose(pd["elevation"], D[-1, :, 2], rtol=0, atol=1e-15)
        assert np.abs(pd["elevation"]).max() > 1e-3
    png = tmp_path / "surface.png"
    assert main(["plot", str(result), "--surface", str(png)]) == 0
    assert png.stat().st_size > 0


def test_a_result_without_fields_says_why(tmp_path, capsys):
    """A multimodal scene's result without fields (run with --no-fields, or by an older jaxslosh):
    the plot and the export say so, not only "--no-fields"."""
    text = (ROOT / "scenes" / "sloshing_experiment.toml").read_text()
    vessel = js.simulate(js.load_scene(text[:text.index("[[tanks]]")].replace("duration = 10.0", "duration = 0.05")))
    bare = tmp_path / "bare.h5"
    js.save_result(dataclasses.replace(vessel, scene_text=text), str(bare))
    assert main(["plot", str(bare), "--surface", str(tmp_path / "s.png")]) == 2
    err = capsys.readouterr().err
    assert "holds no liquid fields: it was run with --no-fields" in err and "multimodal run made before" in err, err
    assert main(["export", str(bare), "--paraview", str(tmp_path / "b.xdmf")]) == 0
    assert "multimodal run made before" in capsys.readouterr().err


#: j'_{m,s} (Abramowitz & Stegun table 9.5) of the lowest cylinder modes, in order: (1,1), (2,1), (0,1)
JP = {(1, 1): 1.841183781, (2, 1): 3.054236928, (0, 1): 3.831705970}


def test_a_cylinder_surface_is_its_bessel_modes():
    R, h = 1.5, 1.2
    scene = js.load_scene(f"""
[simulation]
duration = 0.1
dt = 0.01
[vessel]
mass = 1.0e3
inertia = [1.0e3, 1.0e3, 1.0e3]
[vessel.forced]
dof = "surge"
amplitude = 0.01
frequency = 1.0
[[tanks]]
name = "c"
origin = [0.0, 0.0, 0.0]
size = [{2 * R}, {2 * R}, 2.0]
fill_depth = {h}
model = "multimodal"
shape = "cylinder"
axis = "z"
modes = 5
""")
    t = scene.tanks[0]
    mt = tank_3d(t, t.fill_depth, t.fluid.density)
    assert mt.modes == ((1, 1, 0), (1, 1, 1), (2, 1, 0), (2, 1, 1), (0, 1, 0))
    (mesh,) = surface_meshes(scene)
    F = surface_fields(scene, [mt], [mt.n])
    beta = np.array([0.03, -0.02, 0.01, 0.015, -0.025])
    x, y, z = mesh.nodes.T
    r, th = np.hypot(x - R, y - R), np.arctan2(y - R, x - R)
    want = sum(b * special.jv(m, JP[(m, s)] * r / R) / special.jv(m, JP[(m, s)])
               * (np.sin(m * th) if c else np.cos(m * th)) for b, (m, s, c) in zip(beta, mt.modes))
    np.testing.assert_allclose(F @ beta, want * z / h, rtol=0, atol=1e-8)
    assert np.isclose(np.hypot(x - R, y - R).max(), R) and np.isclose(z.max(), h)


def test_the_multimodal_liquid_gives_the_surface_meshes_fields():
    """The fields the run saves (MultimodalLiquid.nodal_fields of the frames' modal coordinates) on
    the mesh the build hands the writer (Built.tanks): cos(i pi x / L) on top, zero at the bottom."""
    from jaxslosh.liquid.multimodal.liquid import MultimodalLiquid
    from jaxslosh.liquid.multimodal.term import modal_tank
    scene = js.load_scene((ROOT / "scenes" / "sloshing_experiment.toml").read_text().replace("modes = 8 ", "modes = 3 "))
    t = scene.tanks[0]
    (mesh,) = surface_meshes(scene)
    mt = modal_tank(t.size[0], t.size[1], t.fill_depth, 1000.0, t.origin, 3, D=t.size[2])
    F = surface_fields(scene, [mt], [3])
    liquid = MultimodalLiquid(tanks=(mt,), sizes=(3,), samples=None, gravity=9.81, fields=F)
    beta = np.array([[0.02, -0.01, 0.005], [0.0, 0.01, 0.0]])
    D = np.asarray(liquid.nodal_fields(beta))
    x, _, z = mesh.nodes.T
    want = np.cos(np.outer(x, np.arange(1, 4) * np.pi / t.size[0])) @ beta.T * (z / t.fill_depth)[:, None]
    assert D.shape == (2, len(x), 3) and liquid.n_nodes == len(x)
    np.testing.assert_allclose(D[..., 2], want.T, rtol=0, atol=1e-15)
    assert np.all(D[..., :2] == 0.0) and mesh.elements.shape == (24, 8)
