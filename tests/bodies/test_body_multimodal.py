"""A multimodal tank on one of [[bodies]] (docs/guide/bodies-and-connections.md, tanks on a body):
the vessel's multimodal liquid evaluated with the body's kinematics, its coordinates in the exact
block of the Newton matrix as the vessel's are. The body carrying it beside the vessel moves, and
its free surface sloshes, as the same body carrying the same tank as the only vessel of a scene (the
vessel's own liquid: an independent path through the model)."""
import numpy as np
import pytest

import jaxslosh as js

from body_rows import rows_and_residual
from test_body_checks import _check

from test_body_tanks import CARRIER, HEAD, VESSEL

TANK = """
[[tanks]]
name = "cargo"
{body}origin = [-4.0, -2.0, 1.0]
size = [8.0, 4.0, 3.0]
fill_depth = 1.5
model = "multimodal"
modes = 4
[[probes]]
name = "crest"
tank = "cargo"
point = [8.0, 2.0, 1.5]
"""

VOLUME = (3.0e5 + 8.0 * 4.0 * 1.5 * 1000.0) / 1025.0     # the carrier and its liquid float at rest
# pitching: the waves run along the tank's length (the multimodal flow)
PITCHING = CARRIER.replace("angular_velocity = [0.05, 0.0, 0.0]", "angular_velocity = [0.0, 0.05, 0.0]")


def on_body(duration=1.0):
    return (HEAD.format(duration=duration) + VESSEL + '[[bodies]]\nname = "carrier"\nposition = [0.0, 200.0]\n'
            + PITCHING.format(table="bodies", volume=VOLUME) + TANK.format(body='body = "carrier"\n'))


def alone(duration=1.0):
    return HEAD.format(duration=duration) + "[vessel]\n" + PITCHING.format(table="vessel", volume=VOLUME) + \
        TANK.format(body="")


@pytest.fixture(scope="module")
def runs():
    return (js.simulate(js.load_scene(on_body())), js.simulate(js.load_scene(alone())),
            js.simulate(js.load_scene(HEAD.format(duration=1.0) + VESSEL)))


@pytest.mark.slow
def test_a_body_with_a_multimodal_tank_moves_as_the_same_vessel_with_that_tank(runs):
    """50 steps of a pitch decay: the body's motion, its tank's free surface and a probe on it at
    the end wall equal the lone vessel's within 1e-10 (m, rad); the vessel beside it is the vessel
    alone."""
    a, b, v = runs
    body = a.bodies["carrier"]
    assert np.ptp(b.vessel.roll_pitch_yaw[:, 1]) > 0.02                     # it pitches
    np.testing.assert_allclose(body.roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(body.position, b.vessel.position, rtol=0, atol=1e-10)
    Da, Db = a.tanks["cargo"].displacement, b.tanks["cargo"].displacement
    assert np.abs(Db).max() > 0.05                                          # it sloshes
    np.testing.assert_allclose(Da, Db, rtol=0, atol=1e-10)
    pa, pb = a.probes["crest"].displacement, b.probes["crest"].displacement
    assert np.abs(pb[:, 2]).max() > 0.02
    np.testing.assert_allclose(pa, pb, rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.vessel.roll_pitch_yaw, v.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)


def test_check_describes_the_multimodal_tank_on_its_body(tmp_path, capsys):
    status, out = _check(tmp_path, capsys, on_body())
    assert status == 0, out.err
    assert "liquid in tank 'cargo': multimodal (two-dimensional along x), 4 free-surface modes" in out.out
    assert "carried by the body 'carrier'" in out.out
    assert "unknowns per step: 16" in out.out          # 6 + 6 rigid, 4 modal


FEM = """
[[tanks]]
name = "ballast"
{body}origin = [-2.0, -1.0, -1.0]
size = [4.0, 2.0, 1.0]
fill_depth = 0.5
mesh = [2, 2, 1]
{reduction}"""


@pytest.mark.parametrize("extra,key,words", [
    (FEM.format(body="", reduction=""), "tanks[0].model", "beside finite-element tanks"),
    (FEM.format(body='body = "carrier"\n', reduction="[tanks.reduction]\nmodes = 2\n"), "tanks[1].model",
     "on the body 'carrier'"),
], ids=["finite-element tanks on the vessel", "two models on one body"])
def test_what_a_multimodal_tank_on_a_body_cannot_be_beside_exits_2(tmp_path, capsys, extra, key, words):
    status, out = _check(tmp_path, capsys, on_body() + extra)
    assert status == 2 and key in out.err and words in out.err, out.err


def test_a_bodys_multimodal_rows_are_the_lone_vessels_at_any_state():
    """The fast twin of the run's equivalence: at a state away from rest (tilted, moving, the surface
    displaced and accelerating), the body's six rows and its tank's modal rows equal the lone
    vessel's residual at the same state to round-off, 1e-12 of their size."""
    ours, ref = rows_and_residual(on_body(), alone(), seed=3)
    assert np.abs(ours).max() > 1e3
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-12 * np.abs(ours).max())
