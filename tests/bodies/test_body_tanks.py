"""Tanks on [[bodies]] (docs/guide/bodies-and-connections.md): a body's tank is the vessel's model
evaluated with the body's own kinematics. A body with a tank beside the vessel moves, and its
liquid sloshes, as the same body carrying the same tank as the only vessel of a scene (an
independent path: the vessel's own liquid block); the vessel beside it does not feel it."""
import h5py
from meshio.xdmf import TimeSeriesReader
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.analysis.coupled import coupled_modes
from jaxslosh.cli import main

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


@pytest.fixture(scope="module")
def runs():
    """(the vessel and the carrier with its tank, the carrier alone as the vessel, the vessel alone)."""
    return js.simulate(scene_on_body()), js.simulate(scene_alone()), js.simulate(scene_vessel_only())


def test_a_body_with_a_tank_moves_as_the_same_vessel_with_the_same_tank(runs):
    """Over 300 steps of a roll decay: the body's motion and its tank's free surface equal the lone
    vessel's and its tank's within 1e-8 (m, rad), and the vessel beside it equals the vessel alone."""
    a, b, v = runs
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


def test_an_undamped_body_with_a_tank_keeps_its_energy(runs):
    """Nothing dissipates: the total energy (the result's /energy, the body's and its liquid's
    included) stays within 1e-5 of its start over 300 steps (the trapezoidal rule's drift on the
    rotations: the lone vessel with the same tank drifts as much), and it is the lone vessel's with
    its tank plus the vessel's alone, to 1e-8."""
    a, b, v = runs
    E = [np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential) for r in runs]
    assert np.ptp(np.asarray(b.energy.kinetic)) > 0.5 * E[1][0]        # energy moves between its forms
    assert np.max(np.abs(E[0] - E[0][0])) < 1e-5 * E[0][0]
    np.testing.assert_allclose(E[0], E[1] + E[2], rtol=0, atol=1e-8 * E[0][0])


DAMPED = "[tanks.reduction]\nmodes = 6\n[tanks.damping]\nratio = 0.05\n"


def test_a_damped_body_tank_is_the_damped_vessel_tank():
    """[tanks.damping] on a body's tank: 100 steps equal the lone carrier's with the same damped tank
    within 1e-8, and the total energy decreases."""
    a = js.simulate(js.load_scene(scene_on_body(duration=2.0).text.replace("[tanks.reduction]\nmodes = 6\n", DAMPED)))
    b = js.simulate(js.load_scene(scene_alone(duration=2.0).text.replace("[tanks.reduction]\nmodes = 6\n", DAMPED)))
    np.testing.assert_allclose(a.bodies["carrier"].roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.tanks["cargo"].displacement, b.tanks["cargo"].displacement, rtol=0, atol=1e-8)
    E = np.asarray(a.energy.kinetic) + np.asarray(a.energy.potential)
    # (rises no more than the undamped run's drift, 1e-6 of it, and loses 1 % over the run)
    assert np.all(np.diff(E) < 1e-6 * E[0]) and E[-1] < 0.99 * E[0]


def _heavy(text):
    """The carrier a hundred times heavier (its liquid's loads hardly move it)."""
    heavy = text.replace("mass = 3.0e5\ninertia = [2.0e6, 8.0e6, 9.0e6]", "mass = 3.0e7\ninertia = [2.0e8, 8.0e8, 9.0e8]")
    return heavy.replace(f"displaced_volume = {VOLUME}", f"displaced_volume = {(3.0e7 + 48000.0) / 1025.0}")


def test_the_coupled_modes_show_the_body_tanks_sloshing():
    """`modes --coupled` of a heavy carrier: its tank's first sloshing mode along x is labelled the
    carrier's liquid, within 1 % of the closed form sqrt(g k tanh(k h)), k = pi / L (8 x 2 x 4
    hexahedra, a heavy body: the coupling shifts it by less than the mesh), and at the frequency of the
    same tank on the lone carrier as the vessel (to 1e-6)."""
    text = scene_on_body().text.replace("mesh = [2, 4, 3]", "mesh = [8, 2, 4]")
    on_body = coupled_modes(js.load_scene(_heavy(text)), n=8)
    alone = coupled_modes(js.load_scene(_heavy(scene_alone().text.replace("mesh = [2, 4, 3]", "mesh = [8, 2, 4]"))),
                          n=8)
    k, h = np.pi / 8.0, 1.5
    closed = np.sqrt(9.81 * k * np.tanh(k * h))
    slosh = [w for w, d in zip(on_body.omega, on_body.dominant) if d == "carrier liquid"]
    assert slosh and slosh[0] == pytest.approx(closed, rel=1e-2)
    lone = [w for w, d in zip(alone.omega, alone.dominant) if d == "liquid"]
    assert slosh[0] == pytest.approx(lone[0], rel=1e-6)


HAWSER = """
[[connections]]
name = "hawser"
kind = "hawser"
bodies = ["vessel", "carrier"]
points = [[0.0, 5.0, 2.0], [0.0, -5.0, 2.0]]
length = 189.0
stiffness = 1.0e5
damping = 1.0e4
"""


def test_a_body_with_a_tank_on_a_hawser_runs_from_the_command_line(tmp_path, capsys):
    """`jaxslosh check` describes the body's tank; `jaxslosh run` exits 0 and the result file holds
    the body's motion, its tank's field (/tanks/cargo) and its probe."""
    p = tmp_path / "carrier.toml"
    p.write_text(scene_on_body(duration=0.4).text.replace("position = [0.0, 200.0]", "position = [0.0, 200.0]", 1)
                 + HAWSER)
    assert main(["check", str(p)]) == 0
    out = capsys.readouterr().out
    assert "liquid in tank 'cargo'" in out and "carried by the body 'carrier'" in out
    assert "connection: 'hawser'" in out
    out_file = tmp_path / "r.h5"
    assert main(["run", str(p), "-o", str(out_file), "--no-progress"]) == 0
    with h5py.File(out_file) as f:
        assert f["bodies/carrier/roll_pitch_yaw"].shape == (21, 3)
        assert f["tanks/cargo/displacement"].shape[0] == 21
        assert f["tanks/cargo/nodes"].shape[1] == 3
        assert np.abs(f["tanks/cargo/displacement"][-1]).max() > 0
        assert f["probes/crest/position"].shape == (21, 3)
        assert np.all(f["connections/hawser/force"][:] >= 0)
    # ParaView: the body's tank beside the body, carried by it (jaxslosh/io/paraview.py)
    assert main(["export", "--paraview", str(tmp_path / "view.xdmf"), str(out_file)]) == 0
    reader = TimeSeriesReader(str(tmp_path / "view_carrier_liquid.xdmf"))
    points, _ = reader.read_points_cells()
    assert reader.num_steps == 21 and len(points) == len(h5py.File(out_file)["tanks/cargo/nodes"])


def test_without_the_liquid_a_probe_in_a_body_tank_follows_the_body():
    """[effects] liquid = false: no liquid unknowns, the probe moves rigidly with the carrier."""
    r = js.simulate(js.load_scene(scene_on_body(duration=0.2).text + "[effects]\nliquid = false\n"))
    p = np.asarray(r.probes["crest"].position)
    rpy = np.asarray(r.bodies["carrier"].roll_pitch_yaw)
    assert "cargo" not in r.tanks
    # the point (0, 2, 2.5) from the carrier's COG, the carrier at (0, 200) rolling about x
    np.testing.assert_allclose(p[:, 1], 200.0 + 2.0 * np.cos(rpy[:, 0]) - 2.5 * np.sin(rpy[:, 0]), atol=1e-6)
