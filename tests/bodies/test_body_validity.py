"""The validity watch on the tanks [[bodies]] carry (docs/guide/bodies-and-connections.md, tanks on
a body): a body's tank whose free surface passes its roof is said, naming the tank and its body, as
the vessel's tanks are; below the roof nothing is said."""
import h5py
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.cli import main
from jaxslosh.physics.bodies import bodies_term
from jaxslosh.run.validity import Watch

from test_body_multimodal import on_body as multimodal_on_body
from test_body_tanks import scene_on_body as reduced_on_body

LOW_ROOF = ("size = [8.0, 4.0, 3.0]", "size = [8.0, 4.0, 1.55]")     # 5 cm of freeboard over 1.5 m of liquid


def _warnings(scene, body_d):
    """The watch's warnings for two frames (t = 0, 1 s) of the bodies' tanks' unknowns `body_d` (2, m),
    the vessel still."""
    built = build(scene)
    w = Watch(scene)
    w.watch_bodies(built)
    w.update(np.array([0.0, 1.0]), np.zeros((2, 0, 2)), np.zeros(2), np.zeros((2, 0)), None, body_d)
    return w.warnings()


def test_a_multimodal_tank_on_a_body_past_its_roof_is_said():
    """The first mode's amplitude beta_1 raises the surface at the wall x = 0 by beta_1 (cos 0): 0.1 m
    passes the 5 cm freeboard; 0.04 m does not."""
    scene = js.load_scene(multimodal_on_body().replace(*LOW_ROOF))
    said = _warnings(scene, np.array([[0.0, 0, 0, 0], [0.1, 0, 0, 0]]))
    assert said == ["tank 'cargo' on the body 'carrier': the free surface rose 0.1 m at t = 1 s, above the roof "
                    "(0.05 m of freeboard): the multimodal liquid is outside its validity"]
    assert _warnings(scene, np.array([[0.0, 0, 0, 0], [0.04, 0, 0, 0]])) == []


def test_a_reduced_tank_on_a_body_past_its_roof_is_said():
    """A reduced tank: its lowest sloshing mode scaled so that its highest free-surface node rises
    0.08 m (its modes' vertical displacement there), above the 5 cm freeboard."""
    scene = js.load_scene(reduced_on_body().text.replace(*LOW_ROOF))
    built = build(scene)
    tank = bodies_term(built.system).bodies[0].tank
    blk = built.body_tanks[0].tanks[0]
    top = blk.node_offset + np.flatnonzero(np.isclose(blk.nodes[:, 2], blk.nodes[:, 2].max()))
    heave = np.asarray(tank.surface_heave(np.eye(tank.nf)[0], top))
    d = np.zeros((2, tank.nf))
    d[1, 0] = 0.08 / np.abs(heave).max() * np.sign(heave[np.argmax(np.abs(heave))])
    said = _warnings(scene, d)
    assert len(said) == 1 and said[0].startswith("tank 'cargo' on the body 'carrier': the free surface rose 0.08 m "
                                                 "at t = 1 s, above the roof (0.05 m of freeboard): the linear liquid")
    assert _warnings(scene, 0.5 * d) == []


@pytest.mark.slow
def test_a_run_says_a_body_tank_past_its_roof(tmp_path, capsys):
    """`jaxslosh run`: a pitching carrier's multimodal tank with 5 cm of freeboard (its surface rises
    8 cm within the first second): the warning on stderr and in the result file."""
    p = tmp_path / "low.toml"
    p.write_text(multimodal_on_body().replace(*LOW_ROOF))
    out = tmp_path / "low.h5"
    assert main(["run", str(p), "-o", str(out)]) == 0
    assert "tank 'cargo' on the body 'carrier': the free surface rose" in capsys.readouterr().err
    with h5py.File(out) as f:
        assert any("on the body 'carrier'" in str(w) for w in f.attrs["warnings"])
