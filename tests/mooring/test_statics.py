"""`js.mooring` on OC3-Hywind against the OC3 report's stiffness, the lines' term in a run (a surge
free decay against the command's own stiffness, the result datasets), and bad mooring input."""
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.cli.main import main
from jaxslosh.mooring.catenary import catenary
from jaxslosh.mooring.statics import stiffness
from jaxslosh.mooring.term import mooring_term
from jaxslosh.scene.types import SceneError

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
OC3 = os.path.join(ROOT, "scenes", "oc3_hywind.toml")


@pytest.fixture(scope="module")
def oc3():
    scene = js.load_scene(OC3)
    return scene, js.mooring(scene, offsets=[0.0, 5.0])


def test_oc3_lines_at_rest_equal_map(oc3):
    _, r = oc3
    for line in r.lines:
        np.testing.assert_allclose([line["horizontal"], line["vertical"], line["seabed_length"]],
                                   [736939.0, 535728.0, 134.785], rtol=1e-5)
    # the rest position is the equilibrium (symmetric lines, their vertical pull carried by buoyancy)
    np.testing.assert_allclose(r.equilibrium, 0.0, atol=1e-4)


def test_oc3_stiffness_equals_the_report(oc3):
    """The OC3 report's mooring stiffness (Jonkman 2010, table 5-1): K11 = K22 = 41,180 N/m, K33 =
    11,940 N/m, K66 = 1.156e7 N m/rad about the COG's vertical; its K44 = K55 = 3.111e8 N m/rad and
    K15 = -2.821e6 N are about the platform's reference point at the still-water level, 78 m above
    the COG: the same lines' matrix about that point agrees; about the COG (what the command
    gives) roll and pitch differ, since moving the reference point moves moments by lever arms."""
    scene, r = oc3
    K = np.asarray(r.stiffness)
    np.testing.assert_allclose([K[0, 0], K[1, 1], K[2, 2], K[5, 5]], [41180.0, 41180.0, 11940.0, 1.156e7], rtol=0.01)
    # the term built and its stiffness in one compiled program (eagerly, hundreds of one-operation programs)
    about = jax.jit(lambda point: stiffness(mooring_term(build(scene).system), jnp.zeros(3), jnp.eye(3), point=point))
    Ks = np.asarray(about(jnp.array([0.0, 0.0, -scene.vessel.cog_height])))
    np.testing.assert_allclose([Ks[3, 3], Ks[4, 4], Ks[0, 4], Ks[5, 5]], [3.111e8, 3.111e8, -2.821e6, 1.156e7],
                               rtol=0.01)
    # the command's matrix is this one moved to the COG: K44 about the COG is far smaller
    assert abs(K[3, 3]) < 0.05 * Ks[3, 3]


def test_oc3_single_line_stiffness_from_catenary(oc3):
    """K11 of three lines 120 deg apart = 3/2 (dH/dXF + H/XF): the catenary's 2x2 stiffness and the
    lines' geometric (transverse) stiffness; K33 = 3 dV/dZF."""
    _, r = oc3
    c = catenary((853.87 - 5.2, 250.0), 902.2, 698.094, 384.243e6)
    K11 = 1.5 * (float(c.stiffness[0, 0]) + float(c.fairlead_horizontal) / (853.87 - 5.2))
    assert r.stiffness[0, 0] == pytest.approx(K11, rel=1e-6)     # the scene rounds the anchors to 0.1 mm
    assert r.stiffness[2, 2] == pytest.approx(3 * float(c.stiffness[1, 1]), rel=1e-6)


def test_offset_curve_restores(oc3):
    _, r = oc3
    assert r.restoring[0] == pytest.approx(0.0, abs=1e-3)
    assert r.restoring[1] > 0.99 * 5.0 * r.stiffness[0, 0]     # stiffening with the offset
    assert r.max_tension[1] > r.max_tension[0]


SMALL = """
title = "moored barge"
[environment]
gravity = 9.81
water_density = 1025.0
depth = 100.0
[simulation]
duration = 60.0
dt = 0.2
scheme = "newmark"
[vessel]
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 390.0
gm_t = 1.5
gm_l = 15.0
[vessel.initial]
position = [0.5, 0.0, 0.0]
"""


def _lines(z=0.0, n=3, extra=""):
    out = ""
    for i in range(n):
        a = 2 * np.pi * i / n
        out += (f'\n[[mooring]]\nname = "l{i}"\nfairlead = [{5 * np.cos(a):.9f}, {5 * np.sin(a):.9f}, {z}]\n'
                f"anchor = [{400 * np.cos(a):.9f}, {400 * np.sin(a):.9f}, -100.0]\nlength = 420.0\nweight = 600.0\n"
                f"ea = 3.0e8\n{extra}")
    return out


@pytest.mark.slow
def test_moored_surge_free_decay_period():
    """A surge free decay (no added mass, no damping: m + 0) oscillates with 2 pi sqrt(m / K11), K11
    from the command's own stiffness (measured: 25.235 s against 25.216 s)."""
    # from -0.5 m: upward zero crossings at a quarter and at one and a quarter periods (25 s)
    scene = js.load_scene(SMALL.replace("duration = 60.0", "duration = 35.0").replace("dt = 0.2", "dt = 0.25")
                          .replace("position = [0.5, 0.0, 0.0]", "position = [-0.5, 0.0, 0.0]") + _lines())
    K11 = js.mooring(scene, offsets=[0.0]).stiffness[0, 0]
    result = js.simulate(scene)
    t, x = np.asarray(result.time), np.asarray(result.vessel.position)[:, 0]
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))          # upward zero crossings, interpolated
    tc = t[up] - x[up] * (t[up + 1] - t[up]) / (x[up + 1] - x[up])
    assert len(tc) >= 2
    assert np.mean(np.diff(tc)) == pytest.approx(2 * np.pi * np.sqrt(4.0e5 / K11), rel=0.01)


def test_moored_run_records_line_tensions(tmp_path):
    """A short moored run: each line's tensions in the Result and the file, equal to the catenary's
    at the recorded pose; the vessel moves back towards the lines' equilibrium."""
    scene = js.load_scene(SMALL.replace("duration = 60.0", "duration = 1.0").replace("dt = 0.2", "dt = 0.25")
                          + _lines())
    result = js.simulate(scene)
    t = np.asarray(result.time)
    tf = np.asarray(result.mooring["l0"].fairlead_tension)
    assert tf.shape == t.shape == (5,)
    assert np.asarray(result.vessel.position)[-1, 0] < 0.5         # pulled back from 0.5 m
    # the catenary at the pose of the last frame (line l0 along +X)
    from jaxslosh.physics.kinematics import rotation_matrix
    X = np.asarray(result.vessel.position)[-1]
    p = X + np.asarray(rotation_matrix(result.vessel.quaternion[-1])) @ np.array([5.0, 0.0, 0.0])
    c = catenary((np.hypot(400.0 - p[0], p[1]), p[2] + 100.0), 420.0, 600.0, 3.0e8)
    assert tf[-1] == pytest.approx(float(np.hypot(c.fairlead_horizontal, c.fairlead_vertical)), rel=1e-8)
    ta = np.asarray(result.mooring["l0"].anchor_tension)
    assert ta[-1] == pytest.approx(float(c.anchor_horizontal), rel=1e-8)     # the anchor on the seabed: H only
    path = str(tmp_path / "moored.h5")
    js.save_result(result, path)
    back = js.load_result(path)
    np.testing.assert_array_equal(np.asarray(back.mooring["l2"].anchor_tension),
                                  np.asarray(result.mooring["l2"].anchor_tension))


@pytest.mark.parametrize("text, key", [
    (SMALL.replace("depth = 100.0\n", "") + _lines(), "environment.depth"),
    (SMALL + _lines().replace("-100.0]", "-100.5]", 1), "mooring[0].anchor"),
    (SMALL + _lines(extra='body = "barge"\n'), "mooring[0].body"),
    (SMALL + _lines().replace("length = 420.0", "length = 0.0", 1), "mooring[0].length"),
    (SMALL + _lines().replace("weight = 600.0", "weight = 0.0", 1), "mooring[0].weight"),
    (SMALL + _lines(extra='model = "lumped"\nsegments = 1\n'), "mooring[0].segments"),
    (SMALL + _lines(extra='model = "lumped"\ncd = [1.0]\n'), "mooring[0].cd"),
    (SMALL + _lines(extra='model = "lumped"\nseabed_friction = 0.5\n'), "mooring[0].seabed_friction"),
    (SMALL + _lines(extra='segments = 20\n'), "mooring[0].segments"),
    (SMALL + _lines().replace('name = "l1"', 'name = "l0"'), "mooring[1].name"),
])
def test_bad_mooring_input_names_the_key(text, key):
    with pytest.raises(SceneError) as e:
        js.load_scene(text)
    assert e.value.key == key
    assert str(e.value).startswith(key + ":")


def test_bad_mooring_input_exits_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(SMALL + _lines(extra='body = "barge"\n'))
    assert main(["check", str(path)]) == 2
    assert "mooring[0].body" in capsys.readouterr().err
    path.write_text(SMALL)
    assert main(["mooring", str(path)]) == 2


def test_vessel_name_and_taut_line_warning():
    scene = js.load_scene(SMALL.replace("[vessel]\n", '[vessel]\nname = "barge"\n')
                          + _lines(extra='body = "barge"\n').replace("length = 420.0", "length = 390.0", 1))
    assert scene.mooring[0].body == "barge"
    assert any("mooring[0].length" in w and "stretched" in w for w in scene.warnings)
    assert not any("mooring[1]" in w for w in scene.warnings)


@pytest.mark.slow      # the command in process (about a minute on 2 cores); the OC3 tests check js.mooring, which it prints
def test_mooring_command_json_and_figure(tmp_path, capsys):
    import json
    path = tmp_path / "moored.toml"
    path.write_text(SMALL + _lines(z=-1.0))
    fig = tmp_path / "lines.png"
    assert main(["mooring", str(path), "--offsets", "0,2,4", "--direction", "90", "--json", "-o", str(fig)]) == 0
    d = json.loads(capsys.readouterr().out)
    assert {"equilibrium", "lines", "stiffness", "offsets", "restoring", "max_tension"} <= set(d)
    assert [x["name"] for x in d["lines"]] == ["l0", "l1", "l2"]
    assert np.shape(d["stiffness"]) == (6, 6) and d["offsets"] == [0.0, 2.0, 4.0]
    assert d["restoring"][2] > d["restoring"][1] > 0          # along +Y the lines pull back
    assert d["stiffness"][1][1] == pytest.approx(d["stiffness"][0][0], rel=1e-6)    # three lines: isotropic
    assert fig.stat().st_size > 0
    assert main(["mooring", str(path), "--offsets", "0,x"]) == 2
    assert "--offsets" in capsys.readouterr().err
