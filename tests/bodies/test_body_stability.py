"""`jaxslosh stability` of a scene with bodies: each body's GZ curve from its linear hydrostatics
against the closed form GM sin(phi) (GM_T about roll, GM_L about pitch), beside the vessel's hull
curve, which the bodies leave as it is; a vessel without a hull beside bodies gets its linear
curve (docs/guide/stability.md#bodies)."""
import json
from pathlib import Path

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.analysis.bodystability import linear_levers
from jaxslosh.cli import main

ROOT = Path(__file__).resolve().parents[2]
BOX = """
[environment]
water_density = 1025.0
[simulation]
duration = 1.0
dt = 0.01
[vessel]
mass = 410000.0
inertia = [4.9e6, 1.45e7, 1.6e7]
[vessel.hull]
length = 16.0
beam = 10.0
draft = 2.5
kg = 2.9
depth = 5.0
"""
BODY = """
[[bodies]]
name = "tug"
position = [0.0, 40.0]
mass = 1.025e5
inertia = [1.0e6, 4.0e6, 4.5e6]
[bodies.hydrostatics]
waterplane_area = 60.0
displaced_volume = 100.0
gm_t = 0.8
gm_l = 12.0
"""
PHI = np.radians(np.linspace(0.0, 170.0, 18))


def test_a_bodys_gz_is_gm_sin_phi_about_both_axes():
    s = js.load_scene(str(ROOT / "scenes" / "side_by_side.toml"))
    for axis, gm_vessel, gm_barge in (("roll", 1.67, 2.5), ("pitch", 14.2, 20.0)):
        st = js.stability(s, PHI, axis=axis)
        barge = st.bodies["barge"]
        np.testing.assert_allclose(barge.gz, gm_barge * np.sin(PHI), rtol=0, atol=1e-12 * gm_barge)
        assert barge.gm0 == pytest.approx(gm_barge, rel=1e-7) and barge.vanishing_angle is None
        # the ship has no hull: its linear curve, as the barge's
        assert st.model == "linear" and st.criteria == ()
        np.testing.assert_allclose(st.gz, gm_vessel * np.sin(PHI), rtol=0, atol=1e-12 * gm_vessel)
    # past 180 degrees the lever turns: the vanishing angle is 180 degrees
    beyond = js.stability(s, np.radians([90.0, 179.0, 181.0]))
    assert np.degrees(beyond.bodies["barge"].vanishing_angle) == pytest.approx(180.0, abs=1e-9)


def test_the_paper_moment_form_is_its_terms_lever():
    """eq. (36)'s moment literally: its slope upright is GM all the same."""
    s = js.load_scene(str(ROOT / "scenes" / "side_by_side.toml"))
    h = s.bodies[0].hydrostatics.__class__(**{**s.bodies[0].hydrostatics.__dict__, "moment": "paper"})
    gz = linear_levers(h, 1025.0, 9.81, np.array([-1e-4, 1e-4]), "roll")
    assert (gz[1] - gz[0]) / 2e-4 == pytest.approx(2.5, rel=1e-6)


def test_the_vessels_hull_curve_is_unchanged_by_a_body(tmp_path, capsys):
    alone = tmp_path / "alone.toml"
    alone.write_text(BOX)
    both = tmp_path / "both.toml"
    both.write_text(BOX + BODY)
    fig = tmp_path / "gz.png"
    assert main(["stability", str(alone), "--angles", "0:60:7", "--json"]) == 0
    one = json.loads(capsys.readouterr().out)
    assert "bodies" not in one and "model" not in one              # the vessel alone: its object as ever
    assert main(["stability", str(both), "--angles", "0:60:7", "--json", "-o", str(fig)]) == 0
    two = json.loads(capsys.readouterr().out)
    assert two["model"] == "hull" and list(two["bodies"]) == ["tug"]
    for k in ("gz", "gz_frozen", "gm0", "criteria"):
        assert two[k] == one[k]
    tug = two["bodies"]["tug"]
    np.testing.assert_allclose(tug["gz"], 0.8 * np.sin(np.radians(np.linspace(0, 60, 7))), rtol=0, atol=1e-12)
    assert (tug["gm_t"], tug["gm_l"], tug["model"]) == (0.8, 12.0, "linear") and fig.stat().st_size > 10000
    assert main(["stability", str(both), "--angles", "0:60:7"]) == 0
    text = capsys.readouterr().out
    assert "body tug: GZ about the roll axis (m) of its linear hydrostatics, GM_T 0.80000 m, GM_L 12.00000 m:" in text
    assert "   30.000    0.40000" in text and "IS Code 2008 Part A 2.2 (liquids level):" in text


def test_a_vessel_without_a_hull_alone_still_exits_2(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(BOX.split("[vessel.hull]")[0] + "[vessel.hydrostatics]\nwaterplane_area = 160.0\n"
                 "displaced_volume = 400.0\ngm_t = 1.67\ngm_l = 14.2\n")
    assert main(["stability", str(p)]) == 2
    assert "vessel.hull" in capsys.readouterr().err


def test_a_vessel_without_a_hull_but_with_a_tank_beside_bodies_levels_its_liquid(tmp_path, capsys):
    """A vessel on linear springs carrying a box tank, beside a body: its frozen curve is GM sin(phi),
    its level curve the wall-sided tank's free-surface effect taken off, FSC sin(phi) (1 + tan^2(phi) / 2)
    with FSC = rho_l (l b^3 / 12) / (rho V), within 1e-9 m while the surface stays between floor and roof;
    GM0 level is GM - FSC. The command prints both columns and judges no criteria."""
    tank = ('[[tanks]]\nname = "t"\norigin = [-2.0, -3.0, -1.0]\nsize = [4.0, 6.0, 3.0]\nfill_depth = 1.0\n'
            'mesh = [2, 3, 2]\n')
    text = (BOX.split("[vessel.hull]")[0].replace("410000.0", "386000.0") + "[vessel.hydrostatics]\n"
            "waterplane_area = 160.0\ndisplaced_volume = 400.0\ngm_t = 1.67\ngm_l = 14.2\n" + BODY + tank)
    phi = np.radians([0.0, 5.0, 10.0, 15.0])
    s = js.stability(js.load_scene(text), phi)
    fsc = 1000.0 * (4.0 * 6.0 ** 3 / 12.0) / (1025.0 * 400.0)
    assert s.model == "linear" and s.criteria == ()
    np.testing.assert_allclose(s.gz_frozen, 1.67 * np.sin(phi), rtol=0, atol=1e-12)
    np.testing.assert_allclose(s.gz, np.sin(phi) * (1.67 - fsc * (1 + np.tan(phi) ** 2 / 2)), rtol=0, atol=1e-9)
    assert s.gm0 == pytest.approx(1.67 - fsc, abs=1e-8) and s.gm0_frozen == pytest.approx(1.67, abs=1e-8)
    p = tmp_path / "s.toml"
    p.write_text(text)
    assert main(["stability", str(p), "--angles", "0:15:4"]) == 0
    out = capsys.readouterr().out
    assert "GZ level  GZ frozen" in out and "not judged on linear hydrostatics" in out and "body tug:" in out


def test_a_body_with_a_tank_levels_its_liquid_as_the_vessel_does(tmp_path, capsys):
    """The same box tank on a body of linear hydrostatics: its entry has both curves, the level one
    with the tank's free-surface effect (the closed form above, of the body's own V)."""
    tank = ('[[tanks]]\nname = "t"\nbody = "tug"\norigin = [-2.0, -3.0, -1.0]\nsize = [4.0, 6.0, 3.0]\n'
            'fill_depth = 1.0\nmesh = [2, 3, 2]\n')
    text = BOX + BODY.replace("mass = 1.025e5", "mass = 78500.0") + tank
    phi = np.radians([0.0, 5.0, 10.0, 15.0])
    b = js.stability(js.load_scene(text), phi, criteria=False).bodies["tug"]
    fsc = 1000.0 * (4.0 * 6.0 ** 3 / 12.0) / (1025.0 * 100.0)
    assert b["model"] == "linear"
    np.testing.assert_allclose(b.gz_frozen, 0.8 * np.sin(phi), rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.gz, np.sin(phi) * (0.8 - fsc * (1 + np.tan(phi) ** 2 / 2)), rtol=0, atol=1e-9)
    p = tmp_path / "s.toml"
    p.write_text(text)
    assert main(["stability", str(p), "--angles", "0:15:4"]) == 0
    out = capsys.readouterr().out.split("body tug (its linear hydrostatics")[1]
    assert "GZ level  GZ frozen" in out and f"(free-surface correction {fsc:.5f} m)" in out
