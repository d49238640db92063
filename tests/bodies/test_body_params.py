"""A body's values as traced params, by the vessel's names after `bodies.<name>.` (docs/guide/
bodies-and-connections.md, a body's values in params): its mass, inertia, hydrostatics, initial state
and its hull's KG reach its terms as leaves (one compile for several values), the gradient of a run
in them equals central differences, and a name that is not a body's value is refused naming it."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.bodies import build_bodies
from jaxslosh.fit.params import fit_keys, implied_keys, implied_values, make_params, positive
from jaxslosh.physics.hull import HullPressure
from jaxslosh.physics.kinematics import quat_from_rpy
from jaxslosh.physics.vessel import RigidBody
from jaxslosh.scene.compare import differences
from jaxslosh.scene.keys import resolve_params, traceable_keys
from jaxslosh.scene.types import SceneError

RHO, G = 1025.0, 9.81
L, B, T, KG = 10.0, 6.0, 1.5, 2.0
# a small box vessel on its springs and a small box barge beside it on its hull (the nonlinear
# hydrostatics), kicked in roll, pitch and heave: a short run in still water
SCENE = f"""
[environment]
gravity = {G}
water_density = {RHO}
[simulation]
duration = 0.6
dt = 0.1
scheme = "newmark"
tolerance = 1e-9
[vessel]
mass = 1.0e5
inertia = [5.0e5, 1.5e6, 1.7e6]
[vessel.hydrostatics]
waterplane_area = 60.0
displaced_volume = 97.56
gm_t = 1.5
gm_l = 10.0
[[bodies]]
name = "barge"
position = [0.0, 30.0]
mass = {RHO * L * B * T}
inertia = [4.0e5, 9.0e5, 1.1e6]
[bodies.hull]
length = {L}
beam = {B}
draft = {T}
kg = {KG}
depth = 4.0
[bodies.hydrostatics]
model = "nonlinear"
[bodies.initial]
roll_pitch_yaw = [0.1, 0.0, 0.0]
angular_velocity = [0.05, 0.02, 0.0]
velocity = [0.0, 0.0, 0.2]
"""
KEYS = ["bodies.barge.hull.kg", "bodies.barge.inertia", "bodies.barge.mass", "bodies.barge.initial.roll_pitch_yaw",
        "bodies.barge.initial.velocity"]
P0 = np.array([KG, 4.0e5, RHO * L * B * T, 0.1, 0.2])


@pytest.fixture(scope="module")
def scene():
    return js.load_scene(SCENE)


def _params(p):
    """The run's params from the five scalars (the inertia's and the initial state's other components the scene's)."""
    return {KEYS[0]: p[0], KEYS[1]: jnp.stack([p[1], 9.0e5, 1.1e6]), KEYS[2]: p[2],
            KEYS[3]: jnp.stack([p[3], 0.0, 0.0]), KEYS[4]: jnp.stack([0.0, 0.0, p[4]])}


def _loss(scene, traces):
    @jax.jit
    def loss(p):
        traces.append(1)       # once per trace: a value baked into the program would trace again
        b = js.simulate(scene, params=_params(p)).bodies["barge"]
        return jnp.sum(b.roll_pitch_yaw[:, :2] ** 2) + jnp.sum(b.position[:, 2] ** 2)
    return loss


@pytest.mark.slow      # about 15 s of CPU, 55 s on a loaded 2-core machine; the two tests below are its fast twins
def test_the_gradient_in_a_bodys_values_matches_central_differences(scene):
    """The gradient of a run in the barge's KG, roll inertia, mass, initial heel and heave rate within
    1e-7 of central differences of the same compiled loss (relative steps 1e-5; measured: 1e-9)."""
    loss = _loss(scene, [])
    g = np.asarray(jax.grad(loss)(jnp.asarray(P0)))
    for i, key in enumerate(KEYS):
        h = 1e-5 * P0[i]
        e = np.zeros(len(P0))
        e[i] = h
        fd = (float(loss(jnp.asarray(P0 + e))) - float(loss(jnp.asarray(P0 - e)))) / (2 * h)
        assert abs(fd) > 0 and abs(g[i] - fd) <= 1e-7 * abs(fd), (key, g[i], fd)


def test_a_bodys_values_are_compiled_once(scene):
    """One compiled run for every value of the body's params (leaves of the program, not
    constants), each of which changes the run."""
    traces = []
    loss = _loss(scene, traces)
    base = float(loss(jnp.asarray(P0)))
    for i in range(len(P0)):
        p = P0.copy()
        p[i] *= 1.01
        assert abs(float(loss(jnp.asarray(p))) - base) > 1e-6 * base, KEYS[i]
    assert len(traces) == 1


def test_a_bodys_values_reach_its_terms(scene):
    """The values params gives are what the body's terms and initial state hold, and jax.grad sees
    them: the hull's shift is kg0 - kg along z (d/dkg = -1), the water plane at draft - kg."""
    p = _params(jnp.asarray([2.2, 5.0e5, 9.0e4, 0.05, 0.3]))
    term = build_bodies(scene, resolve_params(scene, p), G)[0]
    f = term.bodies[0]
    rigid = next(t for t in f.terms if isinstance(t, RigidBody))
    hull = next(t for t in f.terms if isinstance(t, HullPressure))
    np.testing.assert_allclose(np.diag(np.asarray(rigid.inertia)), [5.0e5, 9.0e5, 1.1e6], rtol=0, atol=0)
    assert float(rigid.mass) == 9.0e4
    np.testing.assert_allclose(np.asarray(hull.shift), [0.0, 0.0, KG - 2.2], rtol=0, atol=1e-15)
    assert float(hull.z_water) == pytest.approx(T - 2.2, abs=1e-15)
    np.testing.assert_allclose(np.asarray(f.x0 - f.rest), 0.0, atol=0)
    np.testing.assert_allclose(np.asarray(f.v0), [0.0, 0.0, 0.3, 0.05, 0.02, 0.0], rtol=0, atol=0)
    np.testing.assert_allclose(np.asarray(f.q0), np.asarray(quat_from_rpy(jnp.array([0.05, 0.0, 0.0]))), atol=1e-15)

    def shift(kg):
        t = build_bodies(scene, {"bodies.barge.hull.kg": kg}, G)[0]
        return next(t for t in t.bodies[0].terms if isinstance(t, HullPressure)).shift[2]

    assert float(jax.grad(shift)(2.1)) == -1.0


def test_a_bodys_keys_are_the_vessels(scene):
    """The body's traceable keys are the vessel's after `bodies.barge.` (no forced motion: a body has
    none; its hull's KG: it has the nonlinear hydrostatics), fitted as the vessel's (KG, mass and inertia
    in log, the inertia by its diagonal), and a fitted KG implies the body's GM0s as the vessel's."""
    keys = traceable_keys(scene)
    ves = {k.partition(".")[2] for k in keys if k.startswith("vessel.")} - {"hull.kg", "hull.cog"}
    body = {k[len("bodies.barge."):] for k in keys if k.startswith("bodies.barge.")}
    assert body == (ves - {"forced.amplitude", "forced.frequency", "forced.phase"}) | {"hull.kg"}
    assert all(positive(k) for k in ("bodies.barge.hull.kg", "bodies.barge.inertia", "bodies.barge.mass"))
    (p,) = make_params(scene, ["bodies.barge.inertia"], None, None)
    np.testing.assert_array_equal(p.start, [4.0e5, 9.0e5, 1.1e6])
    np.testing.assert_array_equal(np.asarray(p.param_value(jnp.array([1.0, 2.0, 3.0]))), np.diag([1.0, 2.0, 3.0]))
    # a record made with another KG differs in these too (its COG height is the box's kg - draft)
    assert implied_keys(["bodies.barge.hull.kg"]) == ("bodies.barge.hydrostatics.gm_t",
                                                      "bodies.barge.hydrostatics.gm_l", "bodies.barge.cog_height")
    other = js.load_scene(SCENE.replace(f"kg = {KG}", "kg = 2.1"))
    assert {d[0] for d in differences(scene, other)} == {"bodies.barge.cog_height", "bodies.barge.hydrostatics.gm_t",
                                                        "bodies.barge.hydrostatics.gm_l", "bodies.barge.hull.kg"}
    assert differences(scene, other, ignore=("bodies.barge.hull.kg",) + implied_keys(["bodies.barge.hull.kg"])) == []
    h = scene.bodies[0].hydrostatics
    out, se = implied_values(scene, {"bodies.barge.hull.kg": KG + 0.1}, {"bodies.barge.hull.kg": 0.01})
    assert out == pytest.approx({"bodies.barge.hydrostatics.gm_t": h.gm_t - 0.1,
                                 "bodies.barge.hydrostatics.gm_l": h.gm_l - 0.1}, abs=1e-12)
    assert h.gm_t == pytest.approx(T / 2 + B ** 2 / (12 * T) - KG, rel=1e-9)   # the box's GM0 = KB + BM - KG
    assert se == {"bodies.barge.hydrostatics.gm_t": 0.01, "bodies.barge.hydrostatics.gm_l": 0.01}


@pytest.mark.parametrize("key,words", [
    ("bodies.nosuch.hull.kg", "bodies.nosuch.hull.kg: not a value of this scene"),
    ("bodies.barge.hull.draft", "bodies.barge.hull.draft: not a value of this scene"),
    ("bodies.barge.heading", "bodies.barge.heading: cannot be traced"),
])
def test_a_bad_body_key_is_refused_naming_it(scene, key, words):
    with pytest.raises(SceneError, match=words.replace(".", r"\.")):
        js.simulate(scene, params={key: 1.0})
    with pytest.raises(SceneError, match=words.replace(".", r"\.")):
        fit_keys(scene, [key])


def test_a_hull_key_needs_the_bodys_nonlinear_hydrostatics():
    """A body on its linear springs: its hull's KG is refused (the springs were fixed at load), and
    a nonlinear body's springs are refused by the fit (its restoring is its hull's), each naming the body's key."""
    linear = js.load_scene(SCENE.replace('model = "nonlinear"', 'model = "linear"'))
    with pytest.raises(SceneError, match=r"bodies\.barge\.hull\.kg: is traced by the nonlinear hydrostatics only "
                                         r"\(\[bodies\.barge\.hydrostatics\] model"):
        resolve_params(linear, {"bodies.barge.hull.kg": 2.1})
    assert "bodies.barge.hull.kg" not in traceable_keys(linear)
    with pytest.raises(SceneError, match=r"bodies\.barge\.hydrostatics\.gm_t: .*fit bodies\.barge\.hull\.kg"):
        fit_keys(js.load_scene(SCENE), ["bodies.barge.hydrostatics.gm_t"])
