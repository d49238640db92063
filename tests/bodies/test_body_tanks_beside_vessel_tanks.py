"""A body's tank beside finite-element tanks on the vessel, in one scene (docs/guide/bodies-and-
connections.md, tanks on a body): the vessel's liquid and the body's each keep their own unknowns,
so that with nothing between them (200 m apart, no waves, no connection) the carrier and its tank
move as the carrier alone with its tank, and the vessel and its tank as the vessel alone with its
tank (independent paths: each as the only vessel of its scene); probes in both tanks follow them."""
import numpy as np
import pytest

import jaxslosh as js

from test_body_tanks import CARRIER, HEAD, TANK, VESSEL, VOLUME

FULL = TANK.replace("[tanks.reduction]\nmodes = {modes}\n", "")
# the vessel's own full-order tank and a probe on its free surface at a side wall
HOLD = """
[[tanks]]
name = "hold"
origin = [-3.0, -3.0, -1.0]
size = [6.0, 6.0, 2.5]
fill_depth = 1.2
mesh = [2, 3, 2]
[[probes]]
name = "rim"
tank = "hold"
point = [6.0, 3.0, 1.2]
"""
# the vessel floats with its liquid (its mass, 4e5 kg, and 6 x 6 x 1.2 m of water on 390 m^3)
VESSEL_HOLD = VESSEL.replace("displaced_volume = 390.0", f"displaced_volume = {(4.0e5 + 43.2e3) / 1025.0!r}")


def _scenes(tank: str, duration: float):
    head = HEAD.format(duration=duration)
    pair = (head + VESSEL_HOLD + '[[bodies]]\nname = "carrier"\nposition = [0.0, 200.0]\n'
            + CARRIER.format(table="bodies", volume=VOLUME) + tank.format(body='body = "carrier"\n', modes=6) + HOLD)
    carrier = head + "[vessel]\n" + CARRIER.format(table="vessel", volume=VOLUME) + tank.format(body="", modes=6)
    vessel = head + VESSEL_HOLD + HOLD
    return [js.load_scene(t) for t in (pair, carrier, vessel)]


# the reduced tank's case: about 20 s of CPU on a loaded 2-core machine (its bases), the full-order one's 10 s
@pytest.mark.parametrize("tank", [pytest.param(TANK, marks=pytest.mark.slow), FULL], ids=["reduced", "full-order"])
def test_a_body_tank_beside_the_vessels_tank_is_each_alone(tank):
    """20 steps of both rolling: the carrier's motion, its tank's field and probe within 1e-10 of the
    lone carrier's (m, rad), the vessel's and its tank's within 1e-10 of the lone vessel's."""
    pair, carrier, vessel = _scenes(tank, 0.4)
    assert pair.warnings == ()
    a, b, v = js.simulate(pair), js.simulate(carrier), js.simulate(vessel)
    body = a.bodies["carrier"]
    assert np.ptp(b.vessel.roll_pitch_yaw[:, 0]) > 0.01 and np.ptp(v.vessel.roll_pitch_yaw[:, 0]) > 1e-3
    np.testing.assert_allclose(body.roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(body.position, b.vessel.position, rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.vessel.roll_pitch_yaw, v.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.vessel.position, v.vessel.position, rtol=0, atol=1e-10)
    for name, alone in (("cargo", b), ("hold", v)):
        Da, Db = a.tanks[name].displacement, alone.tanks[name].displacement
        assert Da.shape == Db.shape and np.abs(Db).max() > 1e-5, name        # it sloshes
        np.testing.assert_allclose(Da, Db, rtol=0, atol=1e-10)
    for name, alone in (("crest", b), ("rim", v)):
        pa, pb = a.probes[name].displacement, alone.probes[name].displacement
        assert np.abs(pb[:, 2]).max() > 1e-5, name
        np.testing.assert_allclose(pa, pb, rtol=0, atol=1e-10)
