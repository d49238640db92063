"""A body's tanks take the vessel's tank keys as traced params (docs/guide/bodies-and-connections.md,
a body's values in params): `tanks.<name>.fill_depth`, `fluid.density`, `fluid.sound_speed` and
`damping.ratio` of a tank on a body reach its liquid; a concrete value gives the run of the scene
file that says it, the gradient of a run equals central differences, the index form `tanks[i]`
counts the scene file's [[tanks]], and a name that is not a tank's value exits 2 naming it."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.bodies import build_bodies
from jaxslosh.cli import main
from jaxslosh.liquid.modal_damping import ModalDamping
from jaxslosh.fit.identify import identify
from jaxslosh.fit.params import fit_keys
from jaxslosh.scene.keys import canonical_key, resolve_params, scene_values, traceable_keys
from jaxslosh.scene.types import SceneError

# a light carrier with a heavy, slow-sound tank (the liquid moves the body; the Newton iterations
# converge to 1e-12, as the vessel's gradient test), kicked in roll; the vessel beside it carries a
# tank of its own, listed after the carrier's (so that tanks[0] is the carrier's)
SCENE = """
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
dt = 0.05
scheme = "hht"
alpha = 0.01
tolerance = 1e-12
[vessel]
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 410.0
gm_t = 1.5
gm_l = 15.0
[vessel.initial]
angular_velocity = [0.02, 0.0, 0.0]
[[bodies]]
name = "carrier"
position = [0.0, 60.0]
mass = 6.0e4
inertia = [4.0e5, 1.0e6, 1.2e6]
[bodies.hydrostatics]
waterplane_area = 60.0
displaced_volume = 130.0
gm_t = 1.2
gm_l = 8.0
[bodies.initial]
angular_velocity = [0.08, 0.03, 0.0]
velocity = [0.0, 0.0, 0.1]
[[tanks]]
name = "cargo"
body = "carrier"
origin = [-2.5, -2.0, -0.5]
size = [5.0, 4.0, 3.0]
fill_depth = {fill}
mesh = [2, 2, 2]
[tanks.fluid]
density = 1000.0
sound_speed = 50.0
[tanks.damping]
ratio = 0.05
[[tanks]]
name = "hold"
origin = [-2.0, -2.0, 0.0]
size = [4.0, 4.0, 2.0]
fill_depth = 1.0
mesh = [2, 2, 1]
[[probes]]
name = "crest"
tank = "cargo"
point = [5.0, 4.0, 1.5]
"""
KEYS = ["tanks.cargo.fill_depth", "tanks[0].fluid.density", "tanks.cargo.fluid.sound_speed",
        "tanks.cargo.damping.ratio"]
P0 = np.array([1.5, 1000.0, 50.0, 0.05])


def _scene(duration=0.5, fill=1.5):
    return js.load_scene(SCENE.format(duration=duration, fill=fill))


@pytest.fixture(scope="module")
def scene():
    return _scene()


def test_a_bodys_tank_keys_are_the_vessels_and_index_the_file(scene):
    """The carrier's tank has the vessel's tank keys; `tanks[0]` is the carrier's (first in the file),
    `tanks[1]` the vessel's."""
    keys = traceable_keys(scene)
    for k in ("fill_depth", "fluid.density", "fluid.sound_speed", "damping.ratio"):
        assert f"tanks.cargo.{k}" in keys and f"tanks.hold.{k.replace('damping.ratio', 'fill_depth')}" in keys
    assert canonical_key(scene, "tanks[0].fill_depth") == "tanks.cargo.fill_depth"
    assert canonical_key(scene, "tanks[1].fill_depth") == "tanks.hold.fill_depth"
    values = scene_values(scene)
    assert values["tanks[0].fill_depth"] == 1.5 and values["tanks[1].fill_depth"] == 1.0
    assert fit_keys(scene, ["tanks[0].fill_depth"]) == ("tanks.cargo.fill_depth",)


def test_a_concrete_fill_depth_gives_the_run_of_the_file_that_says_it():
    """params = {tanks.cargo.fill_depth: 1.2} (and the file form tanks[0]) runs as the scene file
    with fill_depth = 1.2 on the carrier: the same motion of both bodies (the probe aside: its
    weights stay at the scene's mesh); the vessel's tank is left as it is."""
    base, want = _scene(duration=0.3), js.simulate(_scene(duration=0.3, fill=1.2))
    for key in ("tanks.cargo.fill_depth", "tanks[0].fill_depth"):
        got = js.simulate(base, params={key: 1.2})
        a, b = got.bodies["carrier"].roll_pitch_yaw, want.bodies["carrier"].roll_pitch_yaw
        assert np.max(np.abs(np.asarray(a) - np.asarray(b))) <= 1e-12
        assert np.max(np.abs(np.asarray(got.vessel.roll_pitch_yaw) - np.asarray(want.vessel.roll_pitch_yaw))) <= 1e-12
    other = js.simulate(base)
    moved = np.max(np.abs(np.asarray(other.bodies["carrier"].roll_pitch_yaw) - np.asarray(want.bodies["carrier"].roll_pitch_yaw)))
    assert moved > 1e-5        # the fill depth does change the carrier's motion


def _check_gradient(scene, keys, p0):
    """The gradient of the carrier's squared roll, pitch and heave and its probe's rise in `keys`
    against central differences of the same compiled loss at relative steps 1e-4 and 1e-5 (which
    agree with each other first)."""

    def loss(p):
        r = js.simulate(scene, params=dict(zip(keys, p)))
        b = r.bodies["carrier"]
        eta = r.probes["crest"].displacement[:, 2] - b.position[:, 2]
        value = (jnp.sum(b.roll_pitch_yaw[:, :2] ** 2) + jnp.sum(b.position[:, 2] ** 2) + jnp.sum(eta ** 2))
        return value, jnp.max(r.solver.residual)

    value_and_grad = jax.jit(jax.value_and_grad(loss, has_aux=True))

    def value(p):
        (v, residual), _ = value_and_grad(jnp.asarray(p))
        assert float(residual) <= 1e-10, residual
        return float(v)

    (v0, residual), g = value_and_grad(jnp.asarray(p0))
    g = np.asarray(g)
    assert float(residual) <= 1e-10
    assert np.all(np.abs(g * p0) > 1e-6 * float(v0)), g       # every value moves the loss
    for i, key in enumerate(keys):
        fds = []
        for rel in (1e-4, 1e-5):
            e = np.zeros(len(p0))
            e[i] = rel * p0[i]
            fds.append((value(p0 + e) - value(p0 - e)) / (2 * e[i]))
        assert abs(fds[0] - fds[1]) <= 1e-5 * abs(fds[1]), (key, fds, "central differences not converged")
        assert abs(g[i] - fds[1]) <= 1e-5 * abs(fds[1]), (key, g[i], fds[1])


def test_a_bodys_tank_values_reach_its_liquid_as_leaves(scene):
    """The carrier's liquid built from traced values (no run: the fast twin of the test below): its
    mass is rho L B h, so d/dh = rho L B and d/drho = L B h exactly; a traced damping ratio scales
    the damping of each sloshing mode (c = 2 zeta omega: dc/dzeta = 2 omega)."""
    def liquid(p):
        with jax.ensure_compile_time_eval():     # as a run does: the integer mesh stays concrete
            f = build_bodies(scene, resolve_params(scene, dict(zip(KEYS, p))), jnp.asarray(9.81))[0].bodies[0]
        damping = next(t for t in f.tank_terms if isinstance(t, ModalDamping))
        return f.tank.total_mass(), damping.c

    (m, c), (dm, dc) = jax.jit(lambda p: (liquid(p), jax.jacfwd(liquid)(p)))(jnp.asarray(P0))
    assert float(m) == pytest.approx(1000.0 * 5.0 * 4.0 * 1.5, rel=1e-12)
    np.testing.assert_allclose(np.asarray(dm), [1000.0 * 5.0 * 4.0, 5.0 * 4.0 * 1.5, 0.0, 0.0], rtol=1e-12, atol=1e-9)
    omega = np.asarray(c) / (2 * 0.05)
    assert omega.size > 0 and np.all(omega > 0)
    np.testing.assert_allclose(np.asarray(dc)[:, 3], 2 * omega, rtol=1e-12)


@pytest.mark.slow      # about 50 s of CPU (its compile) on a loaded 2-core machine; the test above is its fast twin
def test_the_gradient_in_a_bodys_tank_values_matches_central_differences(scene):
    """10 steps: the gradient of a run in the tank's fill depth, density (by its index form), sound
    speed and damping ratio."""
    _check_gradient(scene, KEYS, P0)


@pytest.mark.parametrize("key,value,words", [
    ("tanks.nosuch.fill_depth", 1.0, "tanks.nosuch.fill_depth: not a value of this scene"),
    ("tanks.cargo.origin", [-2.5, -2.0, -0.5], "tanks.cargo.origin: cannot be traced"),
])
def test_a_bad_tank_key_is_refused_naming_it(scene, key, value, words, tmp_path, capsys):
    with pytest.raises(SceneError, match=words.replace(".", r"\.")):
        js.simulate(scene, params={key: value})
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(duration=0.1, fill=1.5))
    data = tmp_path / "record.h5"
    assert main(["run", str(path), "-o", str(data), "--no-progress"]) == 0
    assert main(["identify", str(path), "--data", str(data), "--fit", key]) == 2
    assert key in capsys.readouterr().err


@pytest.mark.slow      # its Jacobian's compile: about a minute of CPU on a loaded 2-core machine
def test_identify_recovers_a_bodys_tank_fill_depth():
    """A noiseless record of 10 steps made with the carrier's tank 1.4 m deep: identify, started
    from the scene's 1.5 m, returns 1.4 m within 2e-5 m from the carrier's roll, pitch and heave (the
    probe left out: its weights stay at the scene's mesh, whose surface is at 1.5 m). Not closer:
    the damped sloshing modes stay the scene's (at 1.5 m) under a traced depth, the record's are
    at 1.4 m (measured: 9e-6 m off)."""
    made = js.simulate(_scene(fill=1.4))
    fit = identify(_scene(), made, ["tanks.cargo.fill_depth"], data_scene="ignore",
                   weights={"roll": 0.0, "pitch": 0.0, "heave": 0.0, "probes.crest": 0.0})
    assert fit.converged, fit.message
    assert fit.values["tanks.cargo.fill_depth"] == pytest.approx(1.4, abs=2e-5)
    assert fit.channels["bodies.carrier.roll"] > 0
