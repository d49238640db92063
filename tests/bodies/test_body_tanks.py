"""Tanks on [[bodies]] (docs/guide/bodies-and-connections.md): a body's tank is the vessel's model
evaluated with the body's own kinematics. A body with a tank beside the vessel moves, and its
liquid sloshes, as the same body carrying the same tank as the only vessel of a scene (an
independent path: the vessel's own liquid block); the vessel beside it does not feel it."""
import numpy as np
import pytest

import jaxslosh as js

HEAD = """
title = "body tanks"
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
[vessel.initial]
angular_velocity = [0.02, 0.0, 0.0]
"""

# the carrier: heavier than its liquid, rolling from a roll rate (a roll decay with sloshing)
CARRIER = """
mass = 3.0e5
inertia = [2.0e6, 8.0e6, 9.0e6]
[{table}.hydrostatics]
waterplane_area = 160.0
displaced_volume = {volume}
gm_t = 1.2
gm_l = 12.0
[{table}.initial]
angular_velocity = [0.05, 0.0, 0.0]
"""

TANK = """
[[tanks]]
name = "cargo"
{body}origin = [-4.0, -2.0, 1.0]
size = [8.0, 4.0, 3.0]
fill_depth = 1.5
mesh = [2, 4, 3]
[tanks.reduction]
modes = {modes}
[[probes]]
name = "crest"
tank = "cargo"
point = [4.0, 4.0, 1.5]
"""

VOLUME = (3.0e5 + 8.0 * 4.0 * 1.5 * 1000.0) / 1025.0     # the carrier and its liquid float at rest


def scene_on_body(duration=6.0, modes=6):
    """The vessel and the carrier beside it (200 m away, nothing between them), the tank on the carrier."""
    text = (HEAD.format(duration=duration) + VESSEL + '[[bodies]]\nname = "carrier"\nposition = [0.0, 200.0]\n'
            + CARRIER.format(table="bodies", volume=VOLUME) + TANK.format(body='body = "carrier"\n', modes=modes))
    return js.load_scene(text)


def scene_alone(duration=6.0, modes=6):
    """The carrier as the only vessel, with the same tank."""
    text = HEAD.format(duration=duration) + "[vessel]\n" + CARRIER.format(table="vessel", volume=VOLUME) + \
        TANK.format(body="", modes=modes)
    return js.load_scene(text)


def scene_vessel_only(duration=6.0):
    return js.load_scene(HEAD.format(duration=duration) + VESSEL)


def test_a_body_with_a_tank_moves_as_the_same_vessel_with_the_same_tank():
    """Over 300 steps of a roll decay: the body's motion and its tank's free surface equal the lone
    vessel's and its tank's within 1e-8 (m, rad), and the vessel beside it equals the vessel alone."""
    a = js.simulate(scene_on_body())
    b = js.simulate(scene_alone())
    v = js.simulate(scene_vessel_only())
    body = a.bodies["carrier"]
    assert np.ptp(b.vessel.roll_pitch_yaw[:, 0]) > 0.02           # it rolls
    np.testing.assert_allclose(body.roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-8)
    np.testing.assert_allclose(body.position, b.vessel.position, rtol=0, atol=1e-8)
    Da, Db = a.tanks["cargo"].displacement, b.tanks["cargo"].displacement
    assert np.abs(Db).max() > 1e-3                                  # it sloshes
    np.testing.assert_allclose(Da, Db, rtol=0, atol=1e-8)
    # a probe on the free surface at a side wall follows the body's liquid
    pa, pb = a.probes["crest"].displacement, b.probes["crest"].displacement
    assert np.abs(pb[:, 2]).max() > 0.02
    np.testing.assert_allclose(pa, pb, rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.vessel.roll_pitch_yaw, v.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.vessel.position, v.vessel.position, rtol=0, atol=1e-10)
