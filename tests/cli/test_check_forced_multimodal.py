"""`check` of a prescribed motion and of a multimodal tank (issue 43, item 8): a vessel whose motion
[vessel.forced] prescribes does not "fall freely"; a multimodal tank is described by its modes (the
count the assembled liquid has: a cylinder's completed to whole cos/sin pairs), not by a mesh it does
not use, and the unknowns `check` counts are the assembled system's."""
import os

import numpy as np

import jaxslosh as js
from jaxslosh.assemble.effects import count_unknowns
from jaxslosh.assemble.system import build
from jaxslosh.cli.main import main

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXPERIMENT = os.path.join(ROOT, "scenes", "sloshing_experiment.toml")


def _check(capsys, path):
    assert main(["check", path]) == 0
    return capsys.readouterr().out


def test_a_forced_vessel_does_not_fall_and_a_multimodal_tank_has_modes(capsys):
    out = _check(capsys, EXPERIMENT)
    assert "falls freely" not in out and "free body" not in out, out
    assert "gravity: the vessel's weight moves nothing: its motion is prescribed ([vessel.forced])" in out, out
    assert "no hydrostatics (its motion prescribed by [vessel.forced])" in out, out
    assert "hexahedra" not in out and "mesh 2 x 2 x 1" not in out, out
    assert "8 free-surface modes cos(i pi x / L), i = 1..8" in out, out
    scene = js.load_scene(EXPERIMENT)
    assert count_unknowns(scene) == 6 + build(scene).system.nf == 14
    assert "unknowns per step: 14" in out


def test_a_cylinder_counts_its_modes_as_the_liquid_holds_them(tmp_path, capsys):
    t = open(EXPERIMENT).read().replace("size = [1.73, 0.2, 1.15]", "size = [1.0, 1.0, 1.15]").replace(
        'model = "multimodal"', 'model = "multimodal"\nshape = "cylinder"\naxis = "z"').replace("modes = 8", "modes = 3")
    path = tmp_path / "cylinder.toml"
    path.write_text(t)
    out = _check(capsys, str(path))
    scene = js.load_scene(str(path))
    n = build(scene).system.nf
    assert n == 4                                # (1, 1) cos and sin, (2, 1) cos and sin: 3 asked
    assert count_unknowns(scene) == 6 + n and f"unknowns per step: {6 + n}" in out
    assert "4 free-surface modes of its disk base" in out and "3 asked" in out, out
    assert "multimodal (three-dimensional), 4 free-surface modes" in out, out
    assert "hexahedra" not in out, out


def test_a_free_vessel_without_hydrostatics_still_falls(tmp_path, capsys):
    t = open(EXPERIMENT).read()
    t = t[:t.index("[vessel.forced]")] + t[t.index("[[tanks]]"):]
    path = tmp_path / "free.toml"
    path.write_text(t)
    out = _check(capsys, str(path))
    assert "gravity: no hydrostatics table: the vessel falls freely" in out and "(free body)" in out, out


def test_a_damped_multimodal_tank_lists_its_own_linear_modes(tmp_path, capsys):
    """`check`'s damping line of a multimodal tank is the damping its model runs: its N linear modes,
    omega_i^2 = g k_i tanh(k_i h), k_i = i pi / L (not the sloshing modes of a mesh it has no use for)."""
    t = open(EXPERIMENT).read().replace("modes = 8", "modes = 3\n[tanks.damping]\nratio = 0.02\n")
    path = tmp_path / "damped.toml"
    path.write_text(t)
    out = _check(capsys, str(path))
    line = next(x for x in out.splitlines() if x.startswith("damping of tank 'tank'"))
    k = np.arange(1, 4) * np.pi / 1.73
    omega = np.sqrt(9.81 * k * np.tanh(k * 0.6))
    shown = [float(w.split(" rad/s")[0]) for w in line.split("per sloshing mode: ")[1].split(", ")]
    np.testing.assert_allclose(shown, omega, rtol=1e-3)
    assert "modal damping of the multimodal tank's linear modes, ratio 0.02" in out
