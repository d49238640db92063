"""Runs of the face-normal liquid element "rt" (issue 30, liquid/face/element.py) beyond the plain
reduced run of tests/fem/test_liquid_element_rt.py: modal damping (`[tanks.damping]`) on its sloshing
modes, the U-tube's exchange in a forced roll near its frequency against an independent linear
theory (tests/u_tube_response.py), the default element, and rao / sweep on an rt tank."""
import math
import os
import sys

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.damping import build_damping
from jaxslosh.assemble.liquid import build_liquid_block
from jaxslosh.liquid.damping import rectangular_ratio

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))    # tests/: the references
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_damping import HELD, decrement, free_decay, target  # noqa: E402

RT = '[tanks.fluid]\nelement = "rt"\n[tanks.reduction]\nmodes = 6\n'


def held_rt(extra="", duration=7.0, dt=0.01):
    return js.load_scene(HELD.format(duration=duration, dt=dt, scheme="newmark", alpha=0.0) + RT + extra)


def test_free_decay_of_an_rt_tank_has_the_decrement_of_its_ratio():
    """ratio = 0.02 on the first sloshing mode of the held 1.0 x 0.4 m tank (8 x 2 x 4, "rt" on 6
    modes), trapezoidal rule: the corner's heave decays with 2 pi 0.02 / sqrt(1 - 0.02^2) within 3 %;
    the undamped run's decrement is below 1 % of it."""
    t, z, omega, mode = free_decay(held_rt("[tanks.damping]\nratio = [0.02]\n"))
    assert 5.0 < omega < 5.6
    assert abs(decrement(z) / target(0.02) - 1) < 0.03, decrement(z)
    _, z0, _, _ = free_decay(held_rt("[tanks.damping]\nratio = [0.0]\n"), mode=mode)     # the damped run's program
    assert abs(decrement(z0)) < 0.01 * target(0.02), decrement(z0)


def test_rt_boundary_layer_ratio_against_the_closed_form():
    """The laminar boundary-layer ratio of the first mode from the rt element's own wall field
    (liquid/damping.py) against the rectangular tank's closed form within 3 % (8 x 2 x 4) and 1 %
    (16 x 4 x 8); a ratio adds to it; every mode of the basis that is sloshing is damped."""
    closed = rectangular_ratio(1.0, 0.4, 0.5, 9.81, 1e-6)
    for mesh, tol in (([8, 2, 4], 0.03), ([16, 4, 8], 0.01)):
        text = HELD.format(duration=1.0, dt=0.01, scheme="newmark", alpha=0.0).replace("[8, 2, 4]", str(mesh))
        scene = js.load_scene(text + RT + "[tanks.damping]\nratio = 0.01\nviscosity = 1e-6\n")
        damping, table = build_damping(scene, None, build_liquid_block(scene, None, 9.81))
        zeta = np.asarray(table[0].zeta)
        assert abs((zeta[0] - 0.01) / closed - 1) < tol, (mesh, zeta[0], closed)
        assert len(zeta) == 6 and np.all(zeta > 0.01)
        assert damping.B.shape[0] > 6            # the basis: 6 modes, the static correction, circulation


U_TUBE = """
title = "u-tube forced roll"
[simulation]
duration = 160.0
dt = 0.1
[vessel]
mass = 4.1e5
inertia = [6.0e6, 1.6e7, 2.0e7]
[vessel.forced]
dof = "roll"
amplitude = 0.005
frequency = {frequency}
ramp = 20.0
[[tanks]]
name = "u"
origin = [-0.1, -4.0, -0.5]
size = [0.2, 8.0, 2.0]
shape = "mesh"
file = "{file}"
[tanks.fluid]
element = "rt"
[tanks.reduction]
modes = 4
[tanks.damping]
ratio = 0.05
[[probes]]
name = "L"
tank = "u"
point = [0.1, 0.5, 1.0]
[[probes]]
name = "R"
tank = "u"
point = [0.1, 7.5, 1.0]
"""


def test_u_tube_exchange_near_its_frequency_against_linear_theory(tmp_path):
    """The issue's must-show: an 8 m U-tube (1 m reservoirs, 0.3 m duct, filled to 1 m; a mesh file
    of 380 hexahedra) rolled harmonically (0.005 rad) at 0.9, 1.0 and 1.1 of its U-tube frequency,
    every sloshing mode damped by 5 %. The exchange (the two reservoirs' levels' difference relative
    to the tank, the probes' rise less the tank's tilt across them) in the steady state against the
    independent linear modal response of the 2-D potential-flow modes of the same section with the
    same damping (tests/u_tube_response.py): within 5 % (measured +1.6, -0.8, -2.9 %; halved on
    2x80x20). The reference itself gives the level surface at zero frequency (exchange = tilt x 7 m)."""
    import meshio

    import sloshing_reference as ref
    from section_meshes import u_tube_hex
    from u_tube_response import roll_exchange
    nodes, elements = u_tube_hex(8.0, 1.0, 0.3, 1.0, 40, 10, 0.2)
    meshio.write(str(tmp_path / "u.vtu"), meshio.Mesh(nodes, [("hexahedron", elements)]))
    w_u = ref.rectilinear_sloshing_omegas(ref.u_tube(8.0, 1.0, 0.3, 2.0), 1.0, n=1, h_target=0.05)[0]
    Ws = w_u * np.array([0.9, 1.0, 1.1])
    expected, _ = roll_exchange(ref.u_tube(8.0, 1.0, 0.3, 2.0), 1.0, (-4.0, -0.5), 0.5, 7.5,
                                np.concatenate([[1e-6], Ws]), 0.05)
    assert abs(expected[0] - 7.0) < 1e-4          # a level surface in a static tilt
    assert abs(expected[2]) > 8 * 7.0             # resonant: the exchange is many times the tilt's
    for W, exp in zip(Ws, expected[1:]):
        r = js.simulate(js.load_scene(U_TUBE.format(frequency=W, file=tmp_path / "u.vtu")))
        t = np.asarray(r.time)
        roll = np.asarray(r.vessel.roll_pitch_yaw)[:, 0]
        dz = np.asarray(r.probes["L"].displacement)[:, 2] - np.asarray(r.probes["R"].displacement)[:, 2]
        exchange = dz + 7.0 * np.sin(roll)       # the probes' inertial rise less the tank's tilt
        keep = t > t[-1] - 10 * math.pi / W       # the last five periods: steady
        A = np.column_stack([np.sin(W * t[keep]), np.cos(W * t[keep])])
        amp = np.hypot(*np.linalg.lstsq(A, exchange[keep], rcond=None)[0]) / 0.005
        assert abs(amp / abs(exp) - 1) < 0.05, (W / w_u, amp, abs(exp))


# --- full order -------------------------------------------------------------------------------

FULL = '[tanks.fluid]\nelement = "rt"\n'


def test_full_order_free_decay_has_the_decrement_of_its_ratio():
    """The held tank at full order ("rt" without [tanks.reduction]: every free face an unknown):
    the hydrostatic start is at rest, and ratio = 0.02 on the first sloshing mode gives the
    decrement of 2 pi 0.02 / sqrt(1 - 0.02^2) within 3 %; undamped, below 1 % of it."""
    scene = js.load_scene(HELD.format(duration=7.0, dt=0.01, scheme="newmark", alpha=0.0) + FULL
                          + "[tanks.damping]\nratio = [0.02]\n")
    t, z, omega, mode = free_decay(scene)
    assert 5.0 < omega < 5.6
    assert abs(decrement(z) / target(0.02) - 1) < 0.03, decrement(z)
    # undamped: the same table at ratio 0 (a run of the damped one's structure: its compiled program)
    still = js.load_scene(HELD.format(duration=7.0, dt=0.01, scheme="newmark", alpha=0.0) + FULL
                          + "[tanks.damping]\nratio = [0.0]\n")
    _, z0, _, _ = free_decay(still, mode=mode)
    assert abs(decrement(z0)) < 0.01 * target(0.02), decrement(z0)


ROLLED = """
title = "rolled tank"
[simulation]
duration = 3.0
dt = 0.01
[vessel]
mass = 1.0e4
inertia = [1.0e4, 1.0e4, 1.0e4]
[vessel.forced]
dof = "roll"
amplitude = 0.02
frequency = 4.0
ramp = 0.5
[[tanks]]
name = "tank"
origin = [-0.2, -0.5, -0.3]
size = [0.4, 1.0, 0.6]
fill_depth = 0.5
mesh = [2, 8, 4]
[tanks.fluid]
element = "rt"
[[probes]]
name = "corner"
tank = "tank"
point = [0.2, 0.0, 0.5]
"""


def test_full_order_follows_the_reduced_run_and_the_still_tank_stays_still():
    """A tank rolled from rest near its first mode (0.02 rad at 4 rad/s): the full-order run's surface
    at the wall follows the run on 12 modes (with the static correction) within 1 % of its peak, and
    the full-order liquid starts in its discrete hydrostatic equilibrium (a held tank does not move)."""
    full = js.simulate(js.load_scene(ROLLED))
    red = js.simulate(js.load_scene(ROLLED + "[tanks.reduction]\nmodes = 12\n"))
    a = np.asarray(full.probes["corner"].displacement)[:, 2]
    b = np.asarray(red.probes["corner"].displacement)[:, 2]
    assert np.abs(b).max() > 0.005
    assert np.abs(a - b).max() < 0.01 * np.abs(b).max(), (np.abs(a - b).max(), np.abs(b).max())
    still = js.simulate(js.load_scene(ROLLED.replace("amplitude = 0.02", "amplitude = 0.0")))
    assert np.abs(np.asarray(still.probes["corner"].displacement)).max() < 1e-9


# --- the default element ----------------------------------------------------------------------

BAFFLED = """
title = "baffled"
[simulation]
duration = 0.2
dt = 0.02
[vessel]
mass = 4.1e5
inertia = [6.0e6, 1.6e7, 2.0e7]
[[tanks]]
name = "tank"
origin = [0.0, 0.0, 0.0]
size = [5.0, 5.0, 4.0]
fill_depth = 3.0
mesh = {mesh}
{extra}
[[tanks.baffles]]
normal = "x"
position = 2.5
from = "bottom"
height = 1.0
"""


def test_the_default_element_is_rt_where_the_stabilized_one_locks(tmp_path, capsys):
    """Left out, the element is "rt" for a tank with baffles (and a mesh file that is not a box grid,
    tests/fem/test_liquid_element_rt.py's U-tube) on any mesh (a large one at full order through the
    blocks without dense matrices on the faces), "stabilized" for a plain box and a box grid given as
    a mesh file; "rt" for prismatic and cylindrical
    tanks on modes and at full order where the liquid touches a chamfer or a curved wall (a prismatic
    tank filled below its top chamfers, with no bottom ones, is a box: "stabilized"); `check` says
    which and why; a given element stays."""
    from jaxslosh.cli.main import main
    small = js.load_scene(BAFFLED.format(mesh="[10, 4, 6]", extra=""))
    assert small.tanks[0].fluid.element == "rt" and "baffles" in small.tanks[0].fluid.element_default
    big = js.load_scene(BAFFLED.format(mesh="[40, 20, 12]", extra=""))
    assert big.tanks[0].fluid.element == "rt"
    reduced = js.load_scene(BAFFLED.format(mesh="[40, 20, 12]", extra="[tanks.reduction]\nmodes = 6"))
    assert reduced.tanks[0].fluid.element == "rt"
    given = js.load_scene(BAFFLED.format(mesh="[10, 4, 6]", extra='[tanks.fluid]\nelement = "stabilized"'))
    assert given.tanks[0].fluid.element == "stabilized" and given.tanks[0].fluid.element_default == ""
    plain = js.load_scene(BAFFLED.format(mesh="[10, 4, 6]", extra="").split("[[tanks.baffles]]")[0])
    assert plain.tanks[0].fluid.element == "stabilized"
    # prismatic and cylindrical tanks: "rt" on modes and at full order (the stabilized element's modes
    # are off at sloping and curved walls)
    for shape in ('shape = "prismatic"\nchamfers = [[1.0, 1.0], [1.0, 1.0]]', 'shape = "cylinder"\naxis = "z"\n'
                  'size = [5.0, 5.0, 4.0]'):
        text = BAFFLED.format(mesh="[6, 6, 4]", extra="").split("[[tanks.baffles]]")[0].replace(
            "size = [5.0, 5.0, 4.0]\n", "") + shape + "\n"
        if "size" not in shape:
            text += "size = [5.0, 5.0, 4.0]\n"
        full = js.load_scene(text)
        on_modes = js.load_scene(text + "[tanks.reduction]\nmodes = 6\n")
        assert full.tanks[0].fluid.element == "rt" and on_modes.tanks[0].fluid.element == "rt", shape
        assert "on modes" in on_modes.tanks[0].fluid.element_default
        assert "sloping or curved walls" in full.tanks[0].fluid.element_default
        given = js.load_scene(text + '[tanks.fluid]\nelement = "stabilized"\n')
        assert given.tanks[0].fluid.element == "stabilized"
    boxlike = BAFFLED.format(mesh="[6, 6, 4]", extra="").split("[[tanks.baffles]]")[0] + \
        'shape = "prismatic"\nchamfers = [[0.0, 0.0], [1.0, 0.5]]\n'
    assert js.load_scene(boxlike).tanks[0].fluid.element == "stabilized"         # filled to 3 m of 4 m
    assert js.load_scene(boxlike.replace("fill_depth = 3.0", "fill_depth = 3.8")).tanks[0].fluid.element == "rt"
    path = tmp_path / "s.toml"
    path.write_text(BAFFLED.format(mesh="[10, 4, 6]", extra=""))
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "element 'rt' at full order (by default: a tank with baffles" in out
    r = js.simulate(small)
    assert r.status == "ok"


def test_structures_in_the_vessel_frame_with_a_sloped_tank():
    """A chamfered prismatic tank beside a structure in the vessel's frame: the default "rt" takes it
    (the structure's dofs sit beside the faces, tests/physics/test_rt_vessel_structures.py), the
    stabilized element, whose node frames do not go with those structures, is refused naming the
    shape; a prismatic tank whose liquid touches no chamfer stays "stabilized" and takes it."""
    mast = ('[[structures]]\nname = "mast"\norigin = [0.5, 0.5, 4.0]\nsize = [0.3, 0.3, 2.0]\nmesh = [1, 1, 2]\n'
            'attach = "z-"\nframe = "vessel"\n[structures.material]\nyoung = 2.1e11\npoisson = 0.3\n'
            'density = 7850.0\n')
    base = BAFFLED.format(mesh="[2, 4, 3]", extra="").split("[[tanks.baffles]]")[0]
    sloped = base + 'shape = "prismatic"\nchamfers = [[1.0, 1.0], [0.0, 0.0]]\n'
    rt = js.load_scene(sloped + mast)
    assert rt.tanks[0].fluid.element == "rt"
    assert build_liquid_block(rt).liquid is not None
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.shape: .*liquid touches only walls along the axes"):
        build_liquid_block(js.load_scene(sloped + '[tanks.fluid]\nelement = "stabilized"\n' + mast))
    boxlike = js.load_scene(base + 'shape = "prismatic"\nchamfers = [[0.0, 0.0], [1.0, 0.5]]\n' + mast)
    assert boxlike.tanks[0].fluid.element == "stabilized"
    assert build_liquid_block(boxlike).liquid.n_nodes > 0


def test_rt_with_elastic_walls_check_names_the_element(tmp_path, capsys):
    """"rt" in elastic walls (liquid/face/walls.py; tests/fem/test_walls_rt.py and
    tests/physics/test_rt_elastic_walls.py check it): `check` accepts it and prints the element, how
    it runs, and how the walls hold the liquid."""
    from jaxslosh.cli.main import main
    walls = '[tanks.walls]\nthickness = 0.05\n[tanks.walls.material]\nyoung = 2.1e11\npoisson = 0.3\ndensity = 7850.0\n'
    text = BAFFLED.format(mesh="[5, 5, 5]", extra=walls + '[tanks.fluid]\nelement = "rt"').split("[[tanks.baffles]]")[0]
    path = tmp_path / "s.toml"
    path.write_text(text)
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "element 'rt' at full order, elastic walls (slip)" in out, out
    assert "each wall face's flux is the volume the wall sweeps there" in out, out


# --- rao and sweep ----------------------------------------------------------------------------


def test_rao_of_an_rt_tank_full_and_reduced():
    """js.rao on the paper ship (box hull, Froude-Krylov) with its tank on "rt" (6 x 6 x 4): the
    roll and the probe on the surface from the full-order face fluxes and from 20 modes with the
    static correction within 1 % of the peak, and the roll resonance within 1 % of the stabilized
    element's (the liquid's inertia is the same ideal liquid's)."""
    from test_frequency import ROOT, with_hull
    text = (ROOT / "scenes" / "paper_ship_tank.toml").read_text().replace("mesh = [5, 5, 5]", "mesh = [6, 6, 4]")
    rt = text.replace("sound_speed = 1500.0", 'sound_speed = 1500.0\nelement = "rt"')
    w = np.linspace(0.5, 3.0, 26)
    full = js.rao(with_hull(rt), w, [math.pi / 4])
    red = js.rao(with_hull(rt.replace("[[probes]]", "[tanks.reduction]\nmodes = 20\n\n[[probes]]", 1)), w,
                 [math.pi / 4])
    st = js.rao(with_hull(text), w, [math.pi / 4])
    for name in ("roll", "B"):
        a = full.vessel[:, 0, 3] if name == "roll" else full.probes["B"][:, 0, 2]
        b = red.vessel[:, 0, 3] if name == "roll" else red.probes["B"][:, 0, 2]
        assert np.abs(a - b).max() < 0.01 * np.abs(a).max(), name
    peak = lambda r: w[np.argmax(np.abs(r.vessel[:, 0, 3]))]   # noqa: E731
    assert abs(peak(full) / peak(st) - 1) < 0.01, (peak(full), peak(st))


@pytest.mark.slow          # the sweep over density and sound speed covers rt tank values in a batch
def test_a_sweep_of_the_damping_ratio_on_an_rt_tank_equals_the_single_runs():
    """js.simulate_batch (what `jaxslosh sweep` runs) over tanks.<name>.damping.ratio on an rt tank,
    full order and reduced: each run equals its single run."""
    for extra in ("", "[tanks.reduction]\nmodes = 6\n"):
        text = HELD.format(duration=1.0, dt=0.01, scheme="newmark", alpha=0.0).replace(
            'dof = "surge"\namplitude = 0.0', 'dof = "roll"\namplitude = 0.02').replace(
            "frequency = 1.0", "frequency = 5.0") + FULL + extra + "[tanks.damping]\nratio = 0.01\n"
        text += '[[probes]]\nname = "c"\ntank = "tank"\npoint = [0.0, 0.0, 0.5]\n'
        batch, statuses = js.simulate_batch(js.load_scene(text), {"tanks.tank.damping.ratio": np.array([0.01, 0.2])})
        assert statuses == ["ok", "ok"]
        zb = np.asarray(batch.probes["c"].displacement)[..., 2]
        one = js.simulate(js.load_scene(text.replace("ratio = 0.01", "ratio = 0.2")))
        za = np.asarray(one.probes["c"].displacement)[:, 2]
        assert np.abs(zb[1] - za).max() < 1e-9 + 1e-6 * np.abs(za).max()
        assert np.abs(zb[0] - zb[1]).max() > 0.01 * np.abs(za).max()


def test_a_sweep_over_density_and_sound_speed_of_an_rt_tank_equals_the_single_runs():
    """Traced tank values with "rt": the model is built at the scene's values and its mass,
    compression and free-surface blocks scale with the density, rho c^2 and rho g. At full order a
    batch over the density and the sound speed equals the single runs with those values (1e-6 of
    the peak). The fill depth on modes (their shapes are the scene's fill's) is refused naming the key."""
    base = _sweep_base()
    _sweep_equals_single_runs(base, "", {"fluid.density": [1000.0, 1300.0], "fluid.sound_speed": [1500.0, 900.0]})
    with pytest.raises(js.SceneError, match=r"tanks\[0\].fill_depth"):      # on modes (full order: test_gradients_rt)
        js.simulate_batch(js.load_scene(base + FULL + "[tanks.reduction]\nmodes = 6\n"),
                          {"tanks.tank.fill_depth": np.array([0.5, 0.45])})


# slow, to keep the default suite within its budget: the full-order sweep above stays in it
@pytest.mark.slow
def test_a_density_sweep_of_a_reduced_rt_tank_equals_the_single_runs():
    """On modes, whose shapes do not depend on the density, a batch over it equals the single runs."""
    _sweep_equals_single_runs(_sweep_base(), "[tanks.reduction]\nmodes = 6\n", {"fluid.density": [1000.0, 1300.0]})


def _sweep_base():
    base = HELD.format(duration=1.0, dt=0.01, scheme="newmark", alpha=0.0).replace(
        'dof = "surge"\namplitude = 0.0', 'dof = "roll"\namplitude = 0.02').replace("frequency = 1.0", "frequency = 5.0")
    return base + '[[probes]]\nname = "c"\ntank = "tank"\npoint = [0.0, 0.0, 0.5]\n'


def _sweep_equals_single_runs(base, extra, keys):
    """A batch over the tank's `keys` (two values each) equals the single run with the second values."""
    text = base + FULL.replace("[tanks.fluid]\n", "[tanks.fluid]\ndensity = 1000.0\nsound_speed = 1500.0\n") + extra
    batch, statuses = js.simulate_batch(js.load_scene(text), {f"tanks.tank.{k}": np.array(v) for k, v in keys.items()})
    assert statuses == ["ok", "ok"]
    one_text = text
    for k, v in keys.items():
        name = k.split(".")[-1]
        one_text = one_text.replace(f"{name} = {v[0]}", f"{name} = {v[1]}")
    one = js.simulate(js.load_scene(one_text))
    za = np.asarray(one.probes["c"].displacement)[:, 2]
    zb = np.asarray(batch.probes["c"].displacement)[1, :, 2]
    assert np.abs(zb - za).max() < 1e-6 * np.abs(za).max(), (extra, np.abs(zb - za).max(), np.abs(za).max())
    ra, rb = np.asarray(one.energy.kinetic), np.asarray(batch.energy.kinetic)[1]
    assert np.abs(ra - rb).max() < 1e-6 * np.abs(ra).max()
