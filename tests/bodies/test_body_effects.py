"""The `[effects]` switches on a [[bodies]] body by the vessel's rules (docs/guide/running.md#effects,
docs/guide/bodies-and-connections.md): with `buoyancy = false` a body on linear hydrostatics has no
restoring, as the vessel (its weight balanced: it drifts and turns freely, closed forms), and with
`gravity_turning = false` its tank's liquid sees gravity frozen at its initial attitude, as the
vessel's: the same body and tank as a body far from the vessel and as the only vessel move alike."""
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli import main

HEAD = """
title = "body effects"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
dt = 0.02
scheme = "newmark"
tolerance = 1e-10
"""

VESSEL = """
[vessel]
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 390.0
gm_t = 1.5
gm_l = 15.0
"""

# a carrier heavier than its liquid, released with a heave velocity and a roll rate
CARRIER = """
mass = 3.0e5
inertia = [2.0e6, 8.0e6, 9.0e6]
[{table}.hydrostatics]
waterplane_area = 160.0
displaced_volume = {volume}
gm_t = 1.2
gm_l = 12.0
[{table}.initial]
velocity = [0.0, 0.0, {heave_rate}]
angular_velocity = [{roll_rate}, 0.0, 0.0]
"""

TANK = """
[[tanks]]
name = "cargo"
{body}origin = [-4.0, -2.0, 1.0]
size = [8.0, 4.0, 3.0]
fill_depth = 1.5
mesh = [2, 4, 3]
[tanks.reduction]
modes = 4
"""


def scenes(effects: str, tank: bool, duration=2.0, heave_rate=0.0, roll_rate=0.05):
    """(the vessel and the carrier 200 m from it, the carrier as the only vessel), `effects` the
    [effects] table's lines, the tank on the carrier where `tank`."""
    volume = (3.0e5 + (8.0 * 4.0 * 1.5 * 1000.0 if tank else 0.0)) / 1025.0
    carrier = lambda table: CARRIER.format(table=table, volume=volume, heave_rate=heave_rate,  # noqa: E731
                                           roll_rate=roll_rate)
    tail = "\n[effects]\n" + effects + "\n"
    on_body = (HEAD.format(duration=duration) + VESSEL + '[[bodies]]\nname = "carrier"\nposition = [0.0, 200.0]\n'
               + carrier("bodies") + (TANK.format(body='body = "carrier"\n') if tank else "") + tail)
    alone = HEAD.format(duration=duration) + "[vessel]\n" + carrier("vessel") + (TANK.format(body="") if tank else "") + tail
    return js.load_scene(on_body), js.load_scene(alone)


def test_without_buoyancy_a_body_drifts_and_turns_freely_as_the_vessel():
    """`buoyancy = false`: the body on linear hydrostatics keeps no springs (its weight balanced, as
    the vessel's): released with a heave rate and a roll rate about a principal axis it heaves at
    that rate and rolls at that rate (closed forms, 1e-10), and equals the same carrier as the
    vessel (1e-10); with buoyancy it oscillates instead."""
    on_body, alone = scenes("buoyancy = false", tank=False, heave_rate=0.1, roll_rate=0.05)
    a, b = js.simulate(on_body), js.simulate(alone)
    t = np.asarray(a.time)
    body = a.bodies["carrier"]
    np.testing.assert_allclose(body.position[:, 2], 0.1 * t, rtol=0, atol=1e-10)
    np.testing.assert_allclose(body.roll_pitch_yaw[:, 0], 0.05 * t, rtol=0, atol=1e-10)
    np.testing.assert_allclose(body.position, b.vessel.position, rtol=0, atol=1e-10)
    np.testing.assert_allclose(body.roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    held = js.simulate(scenes("buoyancy = true", tank=False, heave_rate=0.1, roll_rate=0.05)[0]).bodies["carrier"]
    assert abs(held.position[-1, 2] - 0.1 * t[-1]) > 0.05          # the springs pull it back


def test_check_says_a_body_has_no_hydrostatics_with_buoyancy_off(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(scenes("buoyancy = false", tank=False)[0].text)
    assert main(["check", str(p)]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if "'carrier'" in x)
    assert "no hydrostatics ([effects] buoyancy off)" in line and "linear hydrostatics" not in line


@pytest.mark.parametrize("turning", [False, True])
def test_a_bodys_gravity_turns_as_the_vessels(turning):
    """`gravity_turning` on a body's tank as on the vessel's: the carrier with its tank rolling as
    a body and as the only vessel, over 100 steps, equal within 1e-10 (rad, m) with the switch off
    and on; and switched off, gravity frozen at the start changes the roll (it is not the turning
    one's)."""
    on_body, alone = scenes(f"gravity_turning = {str(turning).lower()}", tank=True)
    a, b = js.simulate(on_body), js.simulate(alone)
    body = a.bodies["carrier"]
    assert np.ptp(body.roll_pitch_yaw[:, 0]) > 0.02                # it rolls
    np.testing.assert_allclose(body.roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(body.position, b.vessel.position, rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.tanks["cargo"].displacement, b.tanks["cargo"].displacement, rtol=0, atol=1e-10)
    if not turning:
        other = js.simulate(scenes("gravity_turning = true", tank=True)[1])
        assert np.abs(np.asarray(other.vessel.roll_pitch_yaw[:, 0]) - np.asarray(body.roll_pitch_yaw[:, 0])).max() > 1e-4


@pytest.mark.parametrize("name", ["paper_ship_tank.toml", "parametric_roll.toml"])
@pytest.mark.parametrize("buoyancy", [True, False])
def test_the_lines_rule_of_a_balanced_weight_is_the_restorings(name, buoyancy):
    """The moorings carry a floating body's lines' pull at rest where its weight is balanced there
    (physics/bodies.py weight_balanced); that must be the restoring's own choice (assemble/hull.py
    restoring: no weight term), on linear springs and on a hull's pressure, buoyancy on and off."""
    from jaxslosh.assemble.hull import restoring
    from jaxslosh.physics.bodies import weight_balanced
    scene = js.scene_with(js.load_scene(f"scenes/{name}"), {"effects.buoyancy": buoyancy})
    held = restoring(scene, scene.vessel, {}, 9.81, "vessel")
    assert weight_balanced(scene, scene.vessel) == (not held.weighs)
    assert weight_balanced(scene, scene.vessel) == (not (scene.vessel.hydrostatics.nonlinear and buoyancy))
