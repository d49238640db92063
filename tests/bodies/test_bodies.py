"""[[bodies]] and [[connections]] (docs/guide/bodies-and-connections.md): a body beside the vessel
behaves as the same body alone (closed-form heave and roll periods), an undamped contact conserves
the energy, a hawser's force law, a gradient in a connection's stiffness against finite
differences, and bad input exits 2 naming its key."""
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli import main
from jaxslosh.physics.bodies import BAND, FIXED, VESSEL, Link
from jaxslosh.scene.types import SceneError

RHO, G = 1025.0, 9.81
M, IXX, AW, VOL, GMT = 4.0e5, 5.0e6, 200.0, 390.0, 1.5

HEAD = """
title = "bodies"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
dt = {dt}
scheme = "newmark"
[vessel]
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 390.0
gm_t = 1.5
gm_l = 15.0
[vessel.initial]
position = {vessel_position}
angular_velocity = {vessel_omega}
"""

BODY = """
[[bodies]]
name = "{name}"
position = {position}
heading = {heading}
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
[bodies.hydrostatics]
waterplane_area = 200.0
displaced_volume = 390.0
gm_t = 1.5
gm_l = 15.0
[bodies.initial]
position = {initial}
velocity = {velocity}
angular_velocity = {omega}
"""


def head(duration=2.0, dt=0.01, vessel_position=(0, 0, 0), vessel_omega=(0, 0, 0)):
    return HEAD.format(duration=duration, dt=dt, vessel_position=list(vessel_position), vessel_omega=list(vessel_omega))


def body(name="barge", position=(0.0, 200.0), heading=0.0, initial=(0, 0, 0), velocity=(0, 0, 0), omega=(0, 0, 0)):
    return BODY.format(name=name, position=list(position), heading=heading, initial=list(initial),
                       velocity=list(velocity), omega=list(omega))


def _period(t, x):
    """The mean period of x(t) from its upward zero crossings (linearly interpolated)."""
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    return (tc[-1] - tc[0]) / (len(tc) - 1)


def test_a_body_far_away_behaves_as_the_same_body_alone():
    """The vessel and a body of the same values (one heading turned by 90 degrees), both released
    with a heave offset and a roll rate: each heaves and rolls with the single body's closed-form
    periods, and the body's heave and roll follow the vessel's (no coupling without a connection)."""
    text = head(duration=12.0, dt=0.01, vessel_position=(0, 0, 0.1), vessel_omega=(0.01, 0, 0)) \
        + body(position=(0.0, 200.0), heading=0.5 * math.pi, initial=(0, 0, 0.1), omega=(0.01, 0, 0))
    r = js.simulate(js.load_scene(text))
    t = np.asarray(r.time)
    heave = np.asarray(r.bodies["barge"].position[:, 2])
    rpy = np.asarray(r.bodies["barge"].roll_pitch_yaw)
    T_heave = 2 * math.pi * math.sqrt(M / (RHO * G * AW))
    T_roll = 2 * math.pi * math.sqrt(IXX / (RHO * G * VOL * GMT))
    assert _period(t, heave) == pytest.approx(T_heave, rel=1e-2)
    assert _period(t, rpy[:, 0]) == pytest.approx(T_roll, rel=1e-2)
    assert rpy[:, 2] == pytest.approx(0.5 * math.pi, abs=1e-6)          # its heading, held
    np.testing.assert_allclose(heave, np.asarray(r.vessel.position[:, 2]), atol=1e-9)
    np.testing.assert_allclose(rpy[:, 0], np.asarray(r.vessel.roll_pitch_yaw[:, 0]), atol=1e-9)
    assert np.max(np.abs(np.asarray(r.bodies["barge"].position[:, :2]))) < 1e-9   # no drift


def test_coupled_modes_of_a_body_beside_the_vessel():
    """Linearised about rest (JAX's derivative of the same residual): a body far from the vessel,
    of the same values, heaves and rolls at the single body's frequencies, and the mode names it."""
    from jaxslosh.analysis.coupled import coupled_modes
    modes = coupled_modes(js.load_scene(head() + body(position=(0.0, 200.0))), n=6)
    w = dict(zip(modes.dominant, modes.omega))
    assert w["barge heave"] == pytest.approx(math.sqrt(RHO * G * AW / M), rel=1e-8)
    assert w["barge roll"] == pytest.approx(math.sqrt(RHO * G * VOL * GMT / IXX), rel=1e-8)
    assert w["heave"] == pytest.approx(w["barge heave"], rel=1e-10)


def test_the_vessel_alone_on_springs_to_fixed_points():
    """Without [[bodies]] the connections act on the vessel alone (no unknowns of their own): two
    springs fore and aft of it, along x, give surge the period 2 pi sqrt(m / 2 k)."""
    k = 2.0e5
    scene = js.load_scene(head(duration=12.0, dt=0.01, vessel_position=(0.2, 0, 0)) + f"""
[[connections]]
name = "fore"
kind = "spring"
bodies = ["vessel", "fixed"]
points = [[10.0, 0.0, 0.0], [30.0, 0.0, 0.0]]
length = 20.0
stiffness = {k}
[[connections]]
name = "aft"
kind = "spring"
bodies = ["vessel", "fixed"]
points = [[-10.0, 0.0, 0.0], [-30.0, 0.0, 0.0]]
length = 20.0
stiffness = {k}
""")
    r = js.simulate(scene)
    x = np.asarray(r.vessel.position[:, 0])
    assert _period(np.asarray(r.time), x) == pytest.approx(2 * math.pi * math.sqrt(M / (2 * k)), rel=1e-3)
    np.testing.assert_allclose(np.asarray(r.connections["fore"].force), -k * x, rtol=1e-9, atol=1e-6)
    assert r.bodies is None


def _bouncing(kind_second="fender", duration=170.0, dt=0.0025, stiffness=1.0e7, damping=0.0):
    """A body on a spring to a fixed point, released in surge towards a fender on a fixed point:
    one contact per oscillation (about 1.3 s)."""
    return js.load_scene(head(duration=duration, dt=dt) + body(velocity=(0.5, 0, 0)) + f"""
[[connections]]
name = "spring"
kind = "spring"
bodies = ["barge", "fixed"]
points = [[0.0, 0.0, 0.0], [-20.0, 200.0, 0.0]]
length = 20.0
stiffness = 4.0e6
[[connections]]
name = "fender"
kind = "{kind_second}"
bodies = ["barge", "fixed"]
points = [[0.0, 0.0, 0.0], [20.0, 200.0, 0.0]]
length = 19.95
stiffness = {stiffness}
damping = {damping}
""")


# both fender runs this long: the damped one then runs the undamped one's compiled program (the
# damping is a value); 24 contacts hold the energy as 102 do (measured: 2.45e-5 and 2.48e-5 of it)
BOUNCING = 40.0


def test_an_undamped_fender_contact_conserves_the_energy():
    r = js.simulate(_bouncing(duration=BOUNCING))
    f = np.asarray(r.connections["fender"].force)
    contacts = np.count_nonzero((f[:-1] > -1.0) & (f[1:] <= -1.0))
    assert contacts >= 20
    assert np.all(f <= 0.0)                                               # a fender pushes only
    E = np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)
    assert np.max(np.abs(E - E[0])) / E[0] < 1e-4, np.max(np.abs(E - E[0])) / E[0]


def test_a_damped_fender_loses_energy_only_in_contact():
    """(Where its damping cancels its push, while the body leaves it faster than it expands, the
    energy it still holds is lost too: a fender does not pull.)"""
    r = js.simulate(_bouncing(duration=BOUNCING, damping=2.0e5))
    e = np.asarray(r.connections["fender"].extension)
    E = np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)
    dE = np.diff(E)
    slack = (e[:-1] > BAND) & (e[1:] > BAND)
    assert slack.sum() > 100
    assert np.max(np.abs(dE[slack])) < 1e-6 * E[0]
    assert E[-1] < 0.99 * E[0]


def _link(kind, k=1.0e5, L=10.0, c=0.0):
    return Link(ends=(VESSEL, FIXED), kind=kind, pa=jnp.zeros(3), pb=jnp.array([L, 0.0, 0.0]), length=jnp.asarray(L),
                xs=jnp.array([0.0, 1.0]), fs=jnp.array([0.0, k]), damping=jnp.asarray(c))


def _tension(link, x):
    pose = {VESSEL: (jnp.array([x, 0.0, 0.0]), jnp.eye(3), jnp.zeros(3), jnp.zeros(3))}
    return link.state(pose)


@pytest.mark.parametrize("e", [-0.3, -0.01, -0.6 * BAND, 0.6 * BAND, 0.01, 0.25])
def test_a_hawsers_force_is_zero_when_slack_and_k_times_the_extension_beyond_the_band(e):
    """The vessel's point at x, the fixed point 10 m away: the extension is -x."""
    k = 1.0e5
    T, ext, U, _ = _tension(_link("hawser", k), -e)
    assert float(ext) == pytest.approx(e, abs=1e-12)
    if e < 0:
        assert float(T) == 0.0 and float(U) == 0.0
    else:
        assert float(T) == pytest.approx(k * e, rel=1e-12)
    Tf, _, _, _ = _tension(_link("fender", k), -e)           # the fender: the mirror image
    assert float(Tf) == (0.0 if e > 0 else pytest.approx(k * e, rel=1e-12))


@pytest.mark.parametrize("kind", ["hawser", "fender"])
def test_a_damped_contact_never_pushes_a_hawser_or_pulls_a_fender(kind):
    """A hawser 1 cm taut (a fender 1 cm in) whose points close (open) fast: the damping would
    reverse the force; it cancels it at most."""
    link = _link(kind, k=1.0e5, c=1.0e6)
    sign = 1.0 if kind == "hawser" else -1.0
    for rate in (-1.0, -1e-4, 1e-4, 1.0):
        pose = {VESSEL: (jnp.array([-sign * 0.01, 0.0, 0.0]), jnp.eye(3), jnp.array([sign * rate, 0.0, 0.0]),
                         jnp.zeros(3))}
        T = float(link.state(pose)[0])
        assert sign * T >= 0.0
        expected = max(0.0, 1.0e3 - 1.0e6 * rate) if rate else 1.0e3
        assert sign * T == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_the_contact_force_is_the_derivative_of_its_energy_and_continuous():
    link = _link("hawser")
    xs = jnp.linspace(-2 * BAND, 2 * BAND, 401)
    # one compiled program for both (eagerly, each operation its own)
    T, dU = jax.jit(lambda xs: (jax.vmap(lambda x: _tension(link, -x)[0])(xs),
                                jax.vmap(jax.grad(lambda x: _tension(link, -x)[2]))(xs)))(xs)
    np.testing.assert_allclose(np.asarray(T), np.asarray(dU), rtol=1e-10, atol=1e-9)
    # no jump: within the band the slope k (rho'^2 + rho rho'') stays below 1.5 k
    assert np.max(np.abs(np.diff(np.asarray(T)))) < 1.5e5 * 4 * BAND / 400 * 1.01


def test_a_curve_is_its_piecewise_linear_force_and_extended_with_its_last_slope():
    link = Link(ends=(VESSEL, FIXED), kind="spring", pa=jnp.zeros(3), pb=jnp.array([10.0, 0.0, 0.0]),
                length=jnp.asarray(10.0), xs=jnp.array([0.0, 0.1, 0.3]), fs=jnp.array([0.0, 1.0e4, 5.0e4]),
                damping=jnp.asarray(0.0))
    for e, f in ((0.05, 5.0e3), (0.2, 3.0e4), (0.5, 9.0e4), (-0.2, -3.0e4)):
        assert float(_tension(link, -e)[0]) == pytest.approx(f, rel=1e-12)


def _pair(duration=1.0):
    return js.load_scene(head(duration=duration, dt=0.01) + body(position=(0.0, 30.0)) + """
[[connections]]
name = "hawser"
kind = "hawser"
bodies = ["vessel", "barge"]
points = [[5.0, 5.0, 2.0], [5.0, -5.0, 2.0]]
length = 19.0
stiffness = 1.0e5
""")


def test_a_hawser_between_two_bodies_pulls_them_together_by_its_law():
    r = js.simulate(_pair(4.0))
    f, e = np.asarray(r.connections["hawser"].force), np.asarray(r.connections["hawser"].extension)
    assert e[0] == pytest.approx(1.0, abs=1e-12)           # 20 m between the points, 19 m long
    taut, slack = e > BAND, e < -BAND
    assert taut.any() and slack.any()
    np.testing.assert_allclose(f[taut], 1.0e5 * e[taut], rtol=1e-12)
    assert np.all(f[slack] == 0.0)
    vy, by = np.asarray(r.vessel.position[:, 1]), np.asarray(r.bodies["barge"].position[:, 1])
    assert vy[20] > 0 and by[20] < 0                        # towards each other
    np.testing.assert_allclose(vy, -by, atol=1e-9)          # mirror images


@pytest.mark.slow
def test_the_gradient_of_the_hawsers_mean_force_in_its_stiffness():
    scene = _pair(0.5)

    def mean_force(k):
        return jnp.mean(js.simulate(scene, params={"connections.hawser.stiffness": k}).connections["hawser"].force)

    k = 1.0e5
    g = float(jax.grad(mean_force)(k))
    h = 1e-3 * k
    fd = (float(mean_force(k + h)) - float(mean_force(k - h))) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-5)
    assert abs(g) > 0


def test_the_gradient_of_the_connections_rows_in_the_stiffness():
    """The fast check of the slow one above: the bodies' term built with a traced stiffness, its
    rows at a displaced pose (vessel and barge turned and moving) against finite differences."""
    from jaxslosh.assemble.bodies import build_bodies
    from jaxslosh.physics.kinematics import quat_from_rpy
    from jaxslosh.physics.terms import Config
    scene = _pair()
    c = Config(jnp.array([0.1, 0.3, -0.05]), quat_from_rpy(jnp.array([0.02, -0.01, 0.05])), jnp.zeros(0),
               Xs=jnp.array([[0.0, 29.6, 0.02]]), qs=quat_from_rpy(jnp.array([-0.03, 0.01, 0.02]))[None, :])
    vy = jnp.array([0.1, 0.2, 0.0, 0.01, 0.0, 0.02, -0.1, -0.3, 0.0, 0.0, 0.01, 0.0])

    @jax.jit
    def forces(k):
        term, _ = build_bodies(scene, {"connections.hawser.stiffness": k}, jnp.asarray(G))
        return term.link_forces(term.poses(c, vy))

    k = 1.0e5
    g = np.asarray(jax.jacfwd(forces)(k))
    fd = (np.asarray(forces(k * (1 + 1e-6))) - np.asarray(forces(k * (1 - 1e-6)))) / (2e-6 * k)
    assert np.max(np.abs(g)) > 0
    np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-9 * np.max(np.abs(g)))


def test_the_connections_forces_are_the_gradient_of_their_energy_along_the_increments():
    """Translations and body-frame rotations of the vessel and the barge (q exp(theta)), at a
    turned pose with the hawser taut: the forces (moment arms included) are minus the gradient of
    the connections' potential."""
    from jaxslosh.assemble.bodies import build_bodies
    from jaxslosh.physics.kinematics import quat_exp, quat_from_rpy, quat_multiply
    from jaxslosh.physics.terms import Config
    scene = _pair()

    # the term built, its forces and the energy's gradient in one compiled program (eagerly, two
    # hundred one-operation programs)
    @jax.jit
    def forces_and_gradient():
        term, _ = build_bodies(scene, {}, jnp.asarray(G))
        c = Config(jnp.array([0.1, 0.3, -0.05]), quat_from_rpy(jnp.array([0.02, -0.01, 0.05])), jnp.zeros(0),
                   Xs=jnp.array([[0.0, 29.6, 0.02]]), qs=quat_from_rpy(jnp.array([-0.03, 0.01, 0.02]))[None, :])
        zero = jnp.zeros(12)

        def energy(x):
            moved = c._replace(X0=c.X0 + x[:3], q=quat_multiply(c.q, quat_exp(x[3:6])), Xs=c.Xs + x[None, 6:9],
                               qs=quat_multiply(c.qs[0], quat_exp(x[9:12]))[None, :])
            return term.link_potential(term.poses(moved, zero))

        return term.link_forces(term.poses(c, zero)), jax.grad(energy)(zero)

    F, grad = (np.asarray(x) for x in forces_and_gradient())
    assert np.max(np.abs(F)) > 1e4
    np.testing.assert_allclose(F, -grad, rtol=1e-9, atol=1e-6)


BAD = [
    ("unknown body", 'bodies = ["vessel", "barge"]', 'bodies = ["vessel", "tug"]', "connections[0].bodies"),
    ("fixed first", 'bodies = ["vessel", "barge"]', 'bodies = ["fixed", "barge"]', "connections[0].bodies"),
    ("both fixed", 'bodies = ["vessel", "barge"]', 'bodies = ["fixed", "fixed"]', "connections[0].bodies"),
    ("overlap", "position = [0.0, 30.0]", "position = [0.0, 10.0]", "bodies[0].position"),
    ("curve not increasing", "stiffness = 1.0e5", "curve = [[0.1, 1.0e4], [0.2, 0.5e4]]", "connections[0].curve"),
    ("no law", "stiffness = 1.0e5", "", "connections[0].stiffness"),
    ("unknown kind", 'kind = "hawser"', 'kind = "chain"', "connections[0].kind"),
    ("body named vessel", 'name = "barge"', 'name = "vessel"', "bodies[0].name"),
    ("hull on a body", "[bodies.hydrostatics]", "hull = 1\n[bodies.hydrostatics]", "bodies[0].hull"),
    ("database on a body", "[bodies.hydrostatics]", "[bodies.hydrodynamics]\nfile = \"x.nc\"\n[bodies.hydrostatics]",
     "bodies[0].hydrodynamics.file"),
]


def _pair_text():
    return head() + body(position=(0.0, 30.0)) + """
[[connections]]
name = "hawser"
kind = "hawser"
bodies = ["vessel", "barge"]
points = [[5.0, 5.0, 2.0], [5.0, -5.0, 2.0]]
length = 19.0
stiffness = 1.0e5
"""


@pytest.mark.parametrize("what,old,new,key", BAD, ids=[b[0] for b in BAD])
def test_bad_input_names_its_key(what, old, new, key):
    text = _pair_text()
    assert old in text
    with pytest.raises(SceneError) as e:
        js.load_scene(text.replace(old, new, 1))
    assert e.value.key == key, str(e.value)


@pytest.mark.parametrize("extra,key", [
    ('[environment2]\n', "environment2"),
])
def test_what_a_body_cannot_have_yet_exits_2_naming_the_key(tmp_path, capsys, extra, key):
    p = tmp_path / "s.toml"
    p.write_text(_pair_text() + extra)
    assert main(["check", str(p)]) == 2
    assert key in capsys.readouterr().err


def test_check_lists_the_bodies_and_the_connections(tmp_path, capsys):
    p = tmp_path / "pair.toml"
    p.write_text(_pair_text())
    assert main(["check", str(p)]) == 0
    out = capsys.readouterr().out
    assert "floating body: 'barge': 6 unknowns of its own floating frame" in out
    assert "connection: 'hawser': hawser vessel - barge, length 19 m, stiffness 100000 N/m" in out
    assert "unknowns per step: 12" in out


def test_a_bodys_viscous_damping_gives_its_roll_decay():
    """Roll damped by B44 = 2 zeta sqrt(K I): successive peaks shrink by exp(-2 pi zeta / sqrt(1 - zeta^2))."""
    K = RHO * G * VOL * GMT
    zeta = 0.05
    B = 2 * zeta * math.sqrt(K * IXX)
    r = js.simulate(js.load_scene(head(duration=15.0, dt=0.005) + body(omega=(0.02, 0, 0))
                                  + f"[bodies.hydrodynamics]\nviscous_damping = [0, 0, 0, {B}, 0, 0]\n"))
    roll = np.asarray(r.bodies["barge"].roll_pitch_yaw[:, 0])
    i = np.flatnonzero((roll[1:-1] > roll[:-2]) & (roll[1:-1] >= roll[2:])) + 1
    ratio = roll[i[1]] / roll[i[0]]
    assert ratio == pytest.approx(math.exp(-2 * math.pi * zeta / math.sqrt(1 - zeta ** 2)), rel=2e-3)
    assert np.max(np.abs(np.asarray(r.vessel.roll_pitch_yaw))) == 0.0      # the vessel is left at rest
