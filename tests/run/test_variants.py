"""`js.scene_with` (a scene's keys set as a file with them would load) and `Stepper.advance` (n steps
in one scan), the public ways the benchmarks vary a scene and time its step."""
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.scene.load import tomllib
from jaxslosh.scene.variant import toml_text

from helpers import vessel_scene

TANKED = "scenes/paper_ship_tank.toml"


def test_a_variant_loads_as_the_file_with_its_values():
    scene = js.load_scene(TANKED)
    v = js.scene_with(scene, {"tanks.tank.mesh": [4, 4, 3], "tanks[0].fluid.element": "rt",
                              "simulation.duration": 1.0, "vessel.initial.angular_velocity": np.array([0.2, 0.0, 0.0])})
    by_text = js.load_scene(v.text)
    assert v.tanks[0].mesh == by_text.tanks[0].mesh == (4, 4, 3)
    assert v.tanks[0].fluid.element == "rt" and v.simulation.duration == 1.0
    assert tuple(v.vessel.initial.angular_velocity) == (0.2, 0.0, 0.0)
    assert scene.tanks[0].mesh == (5, 5, 5)          # the scene itself is unchanged
    gone = js.scene_with(scene, {"vessel.initial": None})
    assert tuple(gone.vessel.initial.angular_velocity) == (0.0, 0.0, 0.0)


def test_a_bad_variant_names_its_key():
    scene = js.load_scene(TANKED)
    with pytest.raises(js.SceneError, match="tanks.tank.fill_depth"):
        js.scene_with(scene, {"tanks.tank.fill_depth": -1.0})
    with pytest.raises(js.SceneError, match="no tanks named 'nope'"):
        js.scene_with(scene, {"tanks.nope.fill_depth": 1.0})


@pytest.mark.parametrize("name", ["paper_ship_tank", "lng_carrier", "paper_ship_mast", "sloshing_experiment"])
def test_toml_text_round_trips_the_shipped_scenes(name):
    m = tomllib.loads(open(f"scenes/{name}.toml").read())
    assert tomllib.loads(toml_text(m)) == m


def test_advance_is_the_steps_one_by_one():
    scene = vessel_scene(duration=0.2, omega=(0.05, 0.02, 0.0))
    st = js.Stepper(scene)
    a = st.advance(st.init(), 7)
    b = st.init()
    for _ in range(7):
        b = st.step(b)
    np.testing.assert_allclose(np.asarray(a.s.c.q), np.asarray(b.s.c.q), rtol=0, atol=1e-14)
    assert int(a.k) == 7 and st.unknowns == 6


def test_a_mapping_sets_a_table_whose_keys_a_dotted_name_cannot_spell():
    """`{"campaign.limits": {"probe.B": 0.5}}`: the probe's limit key holds a dot (benchmarks/speed/campaign.py)."""
    scene = js.load_scene(TANKED)
    v = js.scene_with(scene, {"campaign.limits": {"roll": 0.1, "probe.B": 0.5}})
    assert tomllib.loads(v.text)["campaign"]["limits"] == {"roll": 0.1, "probe.B": 0.5}
    with pytest.raises(js.SceneError, match="campaign.limits.roll"):
        js.scene_with(scene, {"campaign.limits": {"roll": object()}})
