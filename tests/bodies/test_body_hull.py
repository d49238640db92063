"""A hull on one of [[bodies]] (docs/guide/bodies-and-connections.md, a body's hull): `[bodies.hull]`
takes `[vessel.hull]`'s keys and kinds, and `model = "nonlinear"` its large-angle hydrostatics (the
vessel's pressure term on the body's wetted hull, the waves' pressure at the body's own place, and
its weight). A body with a box hull beside the vessel moves as the same box as the only vessel of a
scene (an independent path: the vessel's own terms), in waves whose phase is shifted by the
body's place; at rest its hull bears its weight (rho g L B T) and its small-heel lever is the box's
GM = KB + BM - KG."""
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.physics.bodies import bodies_term
from jaxslosh.physics.hull import HullPressure
from jaxslosh.physics.kinematics import quat_from_rpy

from body_rows import rows_and_residual
from test_body_checks import _check

HEAD = """
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
dt = 0.05
scheme = "newmark"
tolerance = 1e-8
"""

# the vessel: a box with its linear hydrostatics and Froude-Krylov forces (the waves need a force on it)
VESSEL = """
[vessel]
mass = 410000.0
inertia = [5.0e6, 1.5e7, 1.7e7]
[vessel.hull]
length = 20.0
beam = 10.0
draft = 2.0
kg = 3.0
"""

L, B, T, KG = 20.0, 8.0, 2.0, 3.0
RHO, G = 1025.0, 9.81
BOX = f"""mass = {RHO * L * B * T}
inertia = [2.0e6, 1.2e7, 1.3e7]
[{{t}}.hull]
length = {L}
beam = {B}
draft = {T}
kg = {KG}
depth = 5.0
[{{t}}.hydrostatics]
model = "nonlinear"
[{{t}}.initial]
angular_velocity = [0.1, 0.02, 0.0]
velocity = [0.0, 0.0, 0.3]
"""

OMEGA, X0 = 2.0 * np.pi / 5.0, 30.0
K = OMEGA ** 2 / G          # deep water
WAVES = """[waves]
type = "regular"
amplitude = 0.5
period = 5.0
heading = 0.0
ramp = {ramp}
phase = {phase!r}
"""


def on_body(duration=1.0, ramp=0.5):
    """The vessel and the barge 200 m to port and X0 ahead of it, the waves running along X."""
    return (HEAD.format(duration=duration) + VESSEL + f'[[bodies]]\nname = "barge"\nposition = [{X0}, 200.0]\n'
            + BOX.format(t="bodies") + WAVES.format(ramp=ramp, phase=0.3))


def alone(duration=1.0, ramp=0.5):
    """The barge as the only vessel, the waves' phase the one at the barge's place (eta ~ cos(w t + phase - k x))."""
    return HEAD.format(duration=duration) + "[vessel]\n" + BOX.format(t="vessel") + \
        WAVES.format(ramp=ramp, phase=0.3 - K * X0)


def test_a_bodys_box_hull_moves_as_the_same_box_as_the_vessel():
    """20 steps in regular waves from a roll, pitch and heave kick: the body's roll, pitch, yaw and
    position equal the lone vessel's within 1e-10 (rad, m)."""
    a = js.simulate(js.load_scene(on_body()))
    b = js.simulate(js.load_scene(alone()))
    body, ves = a.bodies["barge"], b.vessel
    assert np.ptp(ves.roll_pitch_yaw[:, 0]) > 0.05 and np.ptp(ves.position[:, 2]) > 0.05    # it rolls and heaves
    assert np.ptp(ves.position[:, 0]) > 0.02                                                # the waves push it
    np.testing.assert_allclose(body.roll_pitch_yaw, ves.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(body.position, ves.position, rtol=0, atol=1e-10)


def test_a_bodys_hull_rows_are_the_lone_vessels_at_any_state():
    """The fast twin: at a tilted, moving, accelerating state in the waves (no ramp), the body's six
    rows equal the lone vessel's residual to round-off."""
    ours, ref = rows_and_residual(on_body(ramp=0.0), alone(ramp=0.0), seed=5)
    assert np.abs(ours).max() > 1e4
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-12 * np.abs(ours).max())


@pytest.fixture(scope="module")
def barge():
    """The barge's floating frame in still water."""
    text = HEAD.format(duration=1.0) + VESSEL + f'[[bodies]]\nname = "barge"\nposition = [{X0}, 200.0]\n' + \
        BOX.format(t="bodies")
    return bodies_term(build(js.load_scene(text)).system).bodies[0]


def _rows(floating, roll=0.0):
    k = floating.kin(floating.rest, quat_from_rpy(jnp.array([roll, 0.0, 0.0])), jnp.zeros(6), jnp.zeros(6), G, 0.0)
    hull = next(t for t in floating.terms if isinstance(t, HullPressure))
    return np.asarray(hull.rows(k).rigid), np.asarray(floating.rows(k)[0])


def test_a_bodys_box_hull_at_its_draft_bears_its_weight(barge):
    """At rest the hull's pressure lifts rho g L B T (N) and the body's rows (pressure and weight) vanish."""
    hull, total = _rows(barge)
    weight = RHO * G * L * B * T
    assert -hull[2] == pytest.approx(weight, rel=1e-12)
    np.testing.assert_allclose(total, 0.0, atol=1e-9 * weight)


def test_a_bodys_box_hull_rights_with_the_boxs_gm(barge):
    """A heel of 1e-3 rad: the righting lever over sin(phi) is GM = KB + BM - KG with BM = B^2 / (12 T)
    (the box's closed form) within 1e-5 relative (the heel's own share is BM tan^2(phi) / 2)."""
    phi = 1e-3
    hull, _ = _rows(barge, phi)
    gz = hull[3] / (RHO * G * L * B * T)         # rows are minus the moment: a righting moment's row is positive
    gm = T / 2 + B ** 2 / (12 * T) - KG
    assert gz / np.sin(phi) == pytest.approx(gm, rel=1e-5)


BAD = [
    ("draft = 2.0\n", "", "bodies[0].hull.draft", "a required key is missing"),
    ("kg = 3.0\n", "kg = -1.0\n", "bodies[0].hull.kg", "above the keel"),
    ("depth = 5.0\n", "depth = 1.0\n", "bodies[0].hull.depth", "above the waterline"),
    ("depth = 5.0\n", "", "bodies[0].hull.depth", "keel-to-deck depth"),
    ("depth = 5.0\n", "depth = 5.0\ncolour = 1\n", "bodies[0].hull.colour", ""),
    ("length = 20.0\n", 'type = "mesh"\nfile = "x.stl"\nlength = 20.0\n', "bodies[0].hull.length",
     'not of type = "mesh"'),
    ('model = "nonlinear"\n', 'model = "linear"\n', "bodies[0].hull.type", "", ),
]


@pytest.mark.parametrize("old,new,key,words", BAD)
def test_bad_hull_keys_on_a_body_exit_2_naming_them(tmp_path, capsys, old, new, key, words):
    text = on_body().replace("[bodies.hull]", "[bodies.hull]\n__HULL__")
    head, tail = text.split("__HULL__")
    if key.endswith("type"):
        tail = tail.replace("length = 20.0\nbeam = 8.0\ndraft = 2.0\nkg = 3.0\ndepth = 5.0\n",
                            'type = "mesh"\nfile = "x.stl"\n')
    status, out = _check(tmp_path, capsys, head + tail.replace(old, new, 1))
    assert status == 2 and key in out.err and words in out.err, out.err


def test_nonlinear_hydrostatics_without_a_hull_exit_2(tmp_path, capsys):
    text = on_body()
    start, end = text.index("[bodies.hull]"), text.index("[bodies.hydrostatics]")
    status, out = _check(tmp_path, capsys, text[:start] + text[end:])
    assert status == 2 and "bodies[0].hydrostatics.model" in out.err and "[bodies.hull]" in out.err, out.err


def test_connection_points_outside_a_bodys_hull_exit_2(tmp_path, capsys):
    """The body's box bounds its connection points (the keel 3 m below its COG)."""
    link = ('[[connections]]\nkind = "spring"\nbodies = ["vessel", "barge"]\n'
            'points = [[0.0, 5.0, 0.0], [0.0, -4.0, {z}]]\nlength = 180.0\nstiffness = 1.0e3\n')
    status, out = _check(tmp_path, capsys, on_body() + link.format(z=-2.9))
    assert status == 0, out.err
    status, out = _check(tmp_path, capsys, on_body() + link.format(z=-3.5))
    assert status == 2 and "connections[0].points" in out.err and "'barge''s hull" in out.err \
        and "below the keel at -3 m" in out.err, out.err


@pytest.mark.parametrize("y,status", [(9.5, 0), (8.5, 2)])
def test_hulls_side_by_side_overlap_by_their_plans(tmp_path, capsys, y, status):
    """Two box hulls without `footprint` are compared by their plans (beams 10 and 8 m: 9 m between
    their COGs at least), not by circles of their waterplane areas (15.1 m): 9.5 m apart they float,
    8.5 m apart they overlap by 0.5 m, named at the body's position."""
    text = (HEAD.format(duration=1.0) + VESSEL + f'[[bodies]]\nname = "barge"\nposition = [0.0, {y}]\n'
            + BOX.format(t="bodies"))
    got, out = _check(tmp_path, capsys, text)
    assert got == status, out.err
    if status:
        assert "bodies[0].position" in out.err and "hull's plan" in out.err and "overlap at rest by 0.5 m" in out.err


def test_a_bodys_box_hull_gives_its_large_angle_gz_curve(tmp_path, capsys):
    """`stability` on a body with a box hull: its curve from its hull (free to sink and trim), the
    wall-sided box's GZ = sin(phi) (GM + BM tan^2(phi) / 2) while the bilge stays wet (26.6 deg)
    within 1e-8 m, GM0 = KB + BM - KG within 1e-6 m; the command line prints its table and criteria."""
    text = (HEAD.format(duration=1.0) + VESSEL.replace("kg = 3.0", "kg = 3.0\ndepth = 5.0")
            + f'[[bodies]]\nname = "barge"\nposition = [{X0}, 200.0]\n' + BOX.format(t="bodies"))
    phi = np.radians([0.0, 5.0, 10.0, 20.0, 25.0])
    b = js.stability(js.load_scene(text), phi, criteria=False).bodies["barge"]
    bm = B ** 2 / (12 * T)
    gm = T / 2 + bm - KG
    assert b["model"] == "hull"
    np.testing.assert_allclose(b.gz, np.sin(phi) * (gm + bm * np.tan(phi) ** 2 / 2), rtol=0, atol=1e-8)
    assert b.gm0 == pytest.approx(gm, abs=1e-6)
    p = tmp_path / "scene.toml"
    p.write_text(text)
    from jaxslosh.cli import main
    assert main(["stability", str(p), "--angles", "0:40:5"]) == 0
    out = capsys.readouterr().out
    after = out.split("body barge:")[1]
    assert "the body free to sink and trim" in after and "IS Code 2008 Part A 2.2 (liquids level):" in after


def test_a_bodys_hull_takes_the_waves_in_its_rao():
    """Without tables, a body's RAO has the Froude-Krylov force on its wetted hull at its place (the
    small-wave limit of the pressure its runs integrate): the lone box's RAO shifted by the phase
    k X0, within 1e-4 of its size (the lone vessel's box force is in closed form, the body's the
    quadrature of its hull's panels)."""
    w = np.array([0.6, 1.0, 2.0 * np.pi / 5.0])
    a = js.rao(js.load_scene(on_body()), w, [0.0]).bodies["barge"][:, 0]
    b = js.rao(js.load_scene(alone()), w, [0.0]).vessel[:, 0]
    assert np.abs(b[:, 2]).min() > 0.5                           # it heaves
    shifted = b * np.exp(-1j * w ** 2 / G * X0)[:, None]
    np.testing.assert_allclose(a, shifted, rtol=0, atol=1e-4 * np.abs(b).max())


def test_a_bodys_tables_lose_the_froude_krylov_share_its_hull_takes():
    """A nonlinear body whose excitation tables hold exactly its hull's Froude-Krylov force (the
    quadrature the run integrates): the linear excitation term the run adds is zero (the hull's
    pressure carries it all), where it would count that force twice."""
    from jaxslosh.assemble.bodyhydro import time_terms
    from jaxslosh.assemble.hull import froude_krylov_surface
    scene = js.load_scene(on_body())
    hull = scene.bodies[0].hull
    w = np.array([0.5, OMEGA, 2.0, 3.0])
    X = froude_krylov_surface(hull.triangles(hull.divisions(scene.waves)), hull.water_height(), w, 0.0, RHO, G)
    tables = (f"[bodies.hydrodynamics]\nfrequencies = {w.tolist()}\nheadings = [0.0]\n"
              f"excitation_amplitude = {np.abs(X).tolist()}\nexcitation_phase = {np.angle(X).tolist()}\n")
    text = on_body().replace("[bodies.initial]", tables + "[bodies.initial]")
    _, _, Xs = time_terms(js.load_scene(text), {})
    assert np.abs(X).max() > 1e5
    np.testing.assert_allclose(Xs[0], 0.0, atol=1e-9 * np.abs(X).max())


def test_a_bodys_mesh_hull_rows_are_the_lone_vessels(tmp_path):
    """`type = "mesh"` on a body: the box written as a closed mesh (waterline at z = 0, COG at
    kg - draft); the body's six rows in the waves equal the lone vessel's with the same mesh."""
    from jaxslosh.hull.box import box_hull
    from jaxslosh.hull.surface import write_hull_mesh
    path = tmp_path / "barge.obj"
    write_hull_mesh(str(path), np.asarray(box_hull(L, B, KG, 5.0, (4, 2, 2))) + np.array([0.0, 0.0, KG - T]))
    mesh = f'type = "mesh"\nfile = "{path}"\ncog = [0.0, 0.0, {KG - T}]\n'
    box = f"length = {L}\nbeam = {B}\ndraft = {T}\nkg = {KG}\ndepth = 5.0\n"
    text = on_body(ramp=0.0).replace(box, mesh)
    assert js.load_scene(text).bodies[0].hull.type == "mesh"
    ours, ref = rows_and_residual(text, alone(ramp=0.0).replace(box, mesh), seed=7)
    assert np.abs(ours).max() > 1e4
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-12 * np.abs(ours).max())


def test_a_bodys_hull_is_watched_for_capsize_as_the_lone_vessels():
    """The run's capsize watch takes each body on its own hull: its angles of vanishing stability are
    the same box's as the only vessel of a scene, and frames whose roll passes them are said naming
    the body (the vessel, upright, is not)."""
    from jaxslosh.run.capsize import body_vanishing_angles, vanishing_angles
    from jaxslosh.run.validity import Watch
    scene = js.load_scene(on_body())
    got = body_vanishing_angles(build(scene).system)
    want = vanishing_angles(build(js.load_scene(alone())).system)
    assert set(got) == {"barge"} and want[0] is not None and np.radians(30.0) < want[0] < np.radians(90.0)
    np.testing.assert_allclose([a for a in got["barge"] if a is not None], [a for a in want if a is not None],
                               rtol=1e-12)
    watch = Watch(scene)
    watch.watch_capsize(vanishing_angles(build(scene).system), got, ("barge",))
    t = np.linspace(0.0, 1.0, 11)
    rolls = np.linspace(0.0, want[0] + 0.1, 11)
    frames = np.zeros((11, 1, 10))
    frames[:, 0, 3], frames[:, 0, 4] = np.cos(rolls / 2), np.sin(rolls / 2)     # pure rolls
    upright = np.tile([1.0, 0.0, 0.0, 0.0], (11, 1))
    watch.update(t, np.zeros((11, 0, 2)), np.zeros(11), None, upright, None, frames[:6])
    assert not [w for w in watch.warnings() if "capsized" in w]
    watch.update(t, np.zeros((11, 0, 2)), np.zeros(11), None, upright, None, frames)
    said = [w for w in watch.warnings() if "capsized" in w]
    assert len(said) == 1 and said[0].startswith("capsized: the body 'barge''s roll reached") \
        and f"{np.degrees(rolls[-1]):.1f} deg at t = 1 s" in said[0], said


LINE = """
[[mooring]]
name = "{name}"
body = "{body}"
fairlead = [9.0, 0.0, -1.0]
anchor = [{x}, {y}, -60.0]
length = 330.0
weight = 800.0
ea = 5.0e8
"""


def test_a_body_on_its_hull_bears_its_lines_pull_as_the_vessel_on_its_hull():
    """Lines on a body with linear hydrostatics: its buoyancy carries their vertical pull at rest (the
    rows vanish there, as the vessel's on linear springs). On a body with its own hull the hull's
    pressure bears only the weight, so at rest the lines' pull is the whole of its mooring rows (it
    sinks under it, as the vessel on its hull does: its own carried force is zero too)."""
    from jaxslosh.mooring.term import mooring_term
    spring = ('[[bodies]]\nname = "buoy"\nposition = [0.0, -300.0]\nmass = 4.0e5\ninertia = [5.0e6, 1.5e7, 1.7e7]\n'
              '[bodies.hydrostatics]\nwaterplane_area = 200.0\ndisplaced_volume = 390.0\ngm_t = 1.5\ngm_l = 15.0\n')
    text = (HEAD.format(duration=1.0).replace("water_density = 1025.0\n", "water_density = 1025.0\ndepth = 60.0\n")
            + VESSEL
            + f'[[bodies]]\nname = "barge"\nposition = [{X0}, 200.0]\n' + BOX.format(t="bodies") + spring
            + LINE.format(name="a", body="barge", x=X0 + 300.0, y=200.0)
            + LINE.format(name="b", body="buoy", x=300.0, y=-300.0))
    term = mooring_term(build(js.load_scene(text)).system)
    per = np.asarray(term.frame_rows(term.rest_X, term.rest_A))       # vessel, barge, buoy
    pull = np.asarray(term.state(term.rest_X, term.rest_A).force)      # each line's force on its fairlead
    assert pull[0, 2] < -1e4 and pull[1, 2] < -1e4                     # both lines pull down
    np.testing.assert_allclose(np.asarray(term.carried_bodies)[0], 0.0, atol=0)
    np.testing.assert_allclose(per[1, :3], pull[0], rtol=1e-12)        # the barge: the line's pull itself
    assert abs(per[2, 2]) < 1e-9 * abs(pull[1, 2])                     # the buoy's buoyancy carries it
