"""Mooring lines on a body of [[bodies]] (docs/guide/moorings.md, docs/guide/bodies-and-connections.md):
the same hull on the same three catenary lines moves the same as the vessel and as a body, its
lines' tensions the same in the result; bad input exits 2 naming its key."""
import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.analysis.linear import linearise
from jaxslosh.assemble.system import build
from jaxslosh.mooring.term import mooring_term
from jaxslosh.physics.kinematics import rotation_matrix
from jaxslosh.scene.types import SceneError

HULL = """
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
{extra}
[{table}.hydrostatics]
waterplane_area = 200.0
displaced_volume = 390.0
gm_t = 1.5
gm_l = 15.0
[{table}.initial]
position = {position}
angular_velocity = {omega}
"""
HEAD = """
title = "moored hull"
[environment]
gravity = 9.81
water_density = 1025.0
depth = 100.0
[simulation]
duration = 1.5
dt = 0.05
scheme = "newmark"
"""
OFFSET, SPIN = [3.0, -1.0, 0.2], [0.004, -0.003, 0.01]
BODY_AT = (40.0, 2000.0)       # the body's rest position: the vessel is far away


def _lines(body: str, at=(0.0, 0.0), model: str = "") -> str:
    """Three catenary lines 120 degrees apart, their anchors 400 m from the hull at rest; fairleads 5 m below
    and 6 m out from the COG, in the hull's frame."""
    out = ""
    for i in range(3):
        a = 2 * math.pi * i / 3 + 0.3
        c, s = math.cos(a), math.sin(a)
        out += f"""
[[mooring]]
name = "l{i + 1}"
body = "{body}"
fairlead = [{6 * c!r}, {6 * s!r}, -5.0]
anchor = [{at[0] + 400 * c!r}, {at[1] + 400 * s!r}, -100.0]
length = 420.0
weight = 1200.0
ea = 5.0e8
{model}"""
    return out


def _vessel_moored() -> str:
    return HEAD + "[vessel]\n" + HULL.format(table="vessel", extra="", position=OFFSET, omega=SPIN) + _lines("vessel")


def _body_moored(model: str = "") -> str:
    return (HEAD + "[vessel]\n" + HULL.format(table="vessel", extra="", position=[0, 0, 0], omega=[0, 0, 0])
            + "[[bodies]]\nname = \"buoy\"\n"
            + HULL.format(table="bodies", extra=f"position = {list(BODY_AT)}", position=OFFSET, omega=SPIN)
            + _lines("buoy", BODY_AT, model))


@pytest.mark.slow      # two moored runs compiled (about a minute); test_a_turned_bodys_lines_act_in_its_own_frame is the fast check of the same rows
def test_a_moored_body_moves_as_the_same_moored_vessel():
    """Released from the same offset and rate, the body on its lines follows the vessel on the same
    lines to 1e-8 (the lines' forces and moments on the body's rows, in its frame), and its lines'
    tensions in the result equal the vessel's lines'; the free vessel beside it stays at rest."""
    ref = js.simulate(js.load_scene(_vessel_moored()))
    r = js.simulate(js.load_scene(_body_moored()))
    b = r.bodies["buoy"]
    X, q = np.asarray(ref.vessel.position), np.asarray(ref.vessel.quaternion)
    assert np.ptp(X[:, 0]) > 1e-3 and np.ptp(np.asarray(ref.vessel.roll_pitch_yaw)[:, 2]) > 1e-3   # it moves
    np.testing.assert_allclose(np.asarray(b.position), X, rtol=0, atol=1e-8)
    np.testing.assert_allclose(np.asarray(b.quaternion), q, rtol=0, atol=1e-8)
    np.testing.assert_allclose(np.asarray(r.vessel.position), 0.0, atol=1e-12)
    for name in ("l1", "l2", "l3"):
        for what in ("fairlead_tension", "anchor_tension"):
            want = np.asarray(getattr(ref.mooring[name], what))
            assert want.min() > 1e4
            np.testing.assert_allclose(np.asarray(getattr(r.mooring[name], what)), want, rtol=1e-8)


def test_a_line_on_a_body_that_does_not_exist_is_refused():
    """A line on a body that does not exist: refused naming the key (lumped lines on bodies are
    taken: tests/bodies/test_body_lumped.py)."""
    assert js.load_scene(_body_moored('model = "lumped"\nsegments = 4\n')).mooring[0].body == "buoy"
    with pytest.raises(SceneError, match=r"mooring\[0\]\.body.*not a body.*buoy"):
        js.load_scene(_body_moored().replace('body = "buoy"', 'body = "boy"', 1))


def _at_rest(text: str) -> str:
    return text.replace(f"position = {OFFSET}", "position = [0, 0, 0]").replace(f"angular_velocity = {SPIN}",
                                                                              "angular_velocity = [0, 0, 0]")


def test_the_still_water_rows_of_a_moored_body_are_the_moored_vessels():
    """The fast twin of the statics: at one pose away from rest, the body's six rows of the several
    frames' residual (its hydrostatics and its lines) equal the moored vessel's static residual at
    that pose to round-off; the free vessel's rows beside it vanish (it is at rest, upright)."""
    from jaxslosh.mooring.statics import frames_residual, static_residual
    scenes = js.load_scene(_at_rest(_vessel_moored())), js.load_scene(_at_rest(_body_moored()))
    x = jnp.array([3.0, -1.0, 0.2, 0.01, -0.02, 0.05])

    @jax.jit
    def rows(x):
        ref = static_residual(build(scenes[0]).system, x)
        got = frames_residual(build(scenes[1]).system, jnp.concatenate([jnp.zeros(6), x]), jnp.eye(4)[:1])
        return ref, got
    ref, got = (np.asarray(r) for r in rows(x))
    assert np.abs(ref[:3]).max() > 1e4                          # the lines and the springs pull back
    np.testing.assert_allclose(got[6:], ref, rtol=0, atol=1e-9 * np.abs(ref).max())
    np.testing.assert_allclose(got[:6], 0.0, atol=1e-9 * np.abs(ref).max())


@pytest.mark.slow      # two static analyses compiled (about a minute); the rows' twin above is the fast check
def test_a_moored_bodys_statics_are_the_moored_vessels():
    """`js.mooring` of the body on its lines beside a free vessel: the body's equilibrium and its lines'
    stiffness equal those of the same hull moored as the vessel (the free vessel, which nothing
    holds in surge, sway and yaw, stays at rest), and the lines' tensions are the same."""
    ref = js.mooring(js.load_scene(_at_rest(_vessel_moored())), offsets=[0.0])
    got = js.mooring(js.load_scene(_at_rest(_body_moored())), offsets=[0.0])
    body = got.bodies["buoy"]
    np.testing.assert_allclose(got.equilibrium, 0.0, atol=1e-12)
    np.testing.assert_allclose(body["equilibrium"], ref.equilibrium, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(body["stiffness"], ref.stiffness, rtol=1e-8, atol=1e-8 * np.abs(ref.stiffness).max())
    for a, b in zip(got.lines, ref.lines):
        assert a["fairlead_tension"] == pytest.approx(b["fairlead_tension"], rel=1e-9)
    assert set(got.as_dict()["bodies"]) == {"buoy"}


@pytest.mark.slow      # the several frames' analysis compiled (half a minute); its rows' twin above is fast
def test_the_mooring_command_prints_each_bodys_equilibrium(tmp_path, capsys):
    """`jaxslosh mooring` of the moored body beside the free vessel: a line per frame, the body's own
    stiffness table, and its JSON's "bodies" (the same program as js.mooring's: nothing compiled anew
    for a second scene of the same structure)."""
    from jaxslosh.cli import main
    p = tmp_path / "scene.toml"
    p.write_text(_at_rest(_body_moored()))
    assert main(["mooring", str(p), "--offsets", "0,5"]) == 0
    out = capsys.readouterr().out
    assert "  vessel: surge" in out and "  buoy: surge" in out and "buoy's lines' stiffness about its COG:" in out
    assert main(["mooring", str(p), "--offsets", "0,5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert len(d["bodies"]["buoy"]["equilibrium"]) == 6 and np.asarray(d["bodies"]["buoy"]["stiffness"]).shape == (6, 6)
    assert d["bodies"]["buoy"]["stiffness"][0][0] > 1e3 and d["stiffness"][0][0] == 0.0     # its lines, not the vessel's


def test_a_turned_bodys_lines_act_in_its_own_frame():
    """A body turned by a heading h, its fairleads given in its own frame (the vessel's turned by -h):
    at a pose that places the fairleads where the vessel's are, the lines' force is the vessel's and
    their moment the vessel's turned by -h into the body's axes."""
    h = 0.7
    c, s = math.cos(h), math.sin(h)
    Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    text = _body_moored().replace(f"position = {list(BODY_AT)}", f"position = {list(BODY_AT)}\nheading = {h!r}")
    for i in range(3):          # each fairlead [6 cos a, 6 sin a, -5] as the body's frame sees it
        a = 2 * math.pi * i / 3 + 0.3
        r_b = Rz.T @ np.array([6 * math.cos(a), 6 * math.sin(a), -5.0])
        text = text.replace(f"fairlead = [{6 * math.cos(a)!r}, {6 * math.sin(a)!r}, -5.0]",
                            f"fairlead = {[float(x) for x in r_b]}")
    scenes = js.load_scene(_vessel_moored()), js.load_scene(text)
    A_v = np.asarray(rotation_matrix(jnp.array([0.99, 0.05, -0.03, 0.1]) / np.linalg.norm([0.99, 0.05, -0.03, 0.1])))
    dx = np.array([2.0, -1.5, 0.3])
    X_b = np.array([BODY_AT[0], BODY_AT[1], 0.0]) + dx

    # both terms built and evaluated in one compiled program (eagerly: a hundred one-operation programs)
    @jax.jit
    def forces(dx, A_v, X_b):
        ves = mooring_term(build(scenes[0]).system)
        bod = mooring_term(build(scenes[1]).system)
        F, M = ves.force_moment(dx, A_v)
        got = bod.frame_rows(jnp.broadcast_to(X_b, (3, 3)), jnp.broadcast_to(A_v @ Rz, (3, 3, 3)))[1]
        return F + ves.carried, M, got, bod.carried

    F, M, got, carried = (np.asarray(x) for x in forces(jnp.asarray(dx), jnp.asarray(A_v), jnp.asarray(X_b)))
    ref = np.concatenate([F, A_v.T @ M])
    assert np.linalg.norm(ref[:3]) > 5e4 and np.linalg.norm(ref[3:]) > 5e4      # the lines pull and turn
    np.testing.assert_allclose(got[:3], ref[:3], rtol=1e-10, atol=1e-6)
    np.testing.assert_allclose(got[3:], Rz.T @ ref[3:], rtol=1e-10, atol=1e-5)
    assert carried == pytest.approx(0.0)     # the free vessel has no lines to carry


@pytest.mark.slow      # two linearisations (rao, modes --coupled): about 40 s on a loaded 2-core machine
def test_the_linearised_stiffness_of_a_moored_body_is_the_moored_vessels():
    """The linearisation that `rao` and `modes --coupled` use takes the lines' stiffness on a body's
    rows as on the vessel's: the body's 6 x 6 block equals the moored vessel's."""
    a = linearise(js.load_scene(_vessel_moored()))
    b = linearise(js.load_scene(_body_moored()))
    assert b.labels[6:12] == ("buoy surge", "buoy sway", "buoy heave", "buoy roll", "buoy pitch", "buoy yaw")
    np.testing.assert_allclose(b.K[6:12, 6:12], a.K[:6, :6], rtol=0, atol=1e-9 * np.abs(a.K[:6, :6]).max())
