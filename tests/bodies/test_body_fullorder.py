"""A full-order finite-element tank (no `[tanks.reduction]`) on one of [[bodies]]
(docs/guide/bodies-and-connections.md, tanks on a body): the vessel's nodal liquid evaluated with
the body's kinematics, its block inverted whole as the bodies' deformable block. The body carrying
it beside the vessel moves, and its liquid sloshes, as the same body carrying the same tank as the
only vessel of a scene (the vessel's own liquid: an independent path through the model)."""
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli import main

from body_rows import rows_and_residual

from test_body_tanks import CARRIER, HEAD, TANK, VESSEL, VOLUME

FULL = TANK.replace("[tanks.reduction]\nmodes = {modes}\n", "")


def on_body(duration=1.0):
    return (HEAD.format(duration=duration) + VESSEL + '[[bodies]]\nname = "carrier"\nposition = [0.0, 200.0]\n'
            + CARRIER.format(table="bodies", volume=VOLUME) + FULL.format(body='body = "carrier"\n'))


def alone(duration=1.0):
    return HEAD.format(duration=duration) + "[vessel]\n" + CARRIER.format(table="vessel", volume=VOLUME) + \
        FULL.format(body="")


@pytest.mark.slow
def test_a_body_with_a_full_order_tank_moves_as_the_same_vessel_with_that_tank():
    """50 steps of a roll decay (tolerance 1e-10): the body's motion, its tank's nodal field and a
    probe on its free surface equal the lone vessel's within 1e-10 (m, rad; measured 4e-12)."""
    a, b = js.simulate(js.load_scene(on_body())), js.simulate(js.load_scene(alone()))
    assert np.ptp(b.vessel.roll_pitch_yaw[:, 0]) > 0.02                     # it rolls
    np.testing.assert_allclose(a.bodies["carrier"].roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.bodies["carrier"].position, b.vessel.position, rtol=0, atol=1e-10)
    Da, Db = a.tanks["cargo"].displacement, b.tanks["cargo"].displacement
    assert Da.shape == Db.shape and np.abs(Db).max() > 0.05                 # every node, sloshing
    np.testing.assert_allclose(Da, Db, rtol=0, atol=1e-10)
    pa, pb = a.probes["crest"].displacement, b.probes["crest"].displacement
    assert np.abs(pb[:, 2]).max() > 0.02
    np.testing.assert_allclose(pa, pb, rtol=0, atol=1e-10)


def test_a_bodys_full_order_rows_are_the_lone_vessels_at_any_state():
    """The fast twin: at a tilted, moving state with the liquid displaced and accelerating, the body's
    six rows and its liquid's rows (the rotation penalty's included) equal the lone vessel's residual
    at the same state, 1e-12 of their size."""
    ours, ref = rows_and_residual(on_body(), alone(), seed=5, sizes=(0.01, 0.02, 0.05))
    assert np.abs(ours).max() > 1e3
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-12 * np.abs(ours).max())


def test_check_describes_the_full_order_tank_on_its_body(tmp_path, capsys):
    p = tmp_path / "scene.toml"
    p.write_text(on_body())
    assert main(["check", str(p)]) == 0
    out = capsys.readouterr().out
    assert "liquid in tank 'cargo'" in out and "carried by the body 'carrier'" in out
