"""Identification with bodies: a body's GM_T and a connection's stiffness fitted from a record of
the body's channels (`bodies.<name>.roll`, ..., `connections.<name>`), and the gradient of a run
in a body's traced values against finite differences (docs/guide/identification.md)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.bodies import build_bodies
from jaxslosh.cli import main
from jaxslosh.fit.params import make_params, positive
from jaxslosh.physics.vessel import AbstractRestoring, RigidBody
from jaxslosh.scene.keys import resolve_params
from jaxslosh.fit.identify import identify
from jaxslosh.fit.problem import add_noise, channel_unit, channels_of
from jaxslosh.scene.types import SceneError

# the vessel held by a stiff spring to a fixed point is not needed: the body rolls on its own
# (an initial roll rate) and pulls on a spring to the vessel, which it sets rolling
SCENE = """
title = "ship and barge on a spring"
[simulation]
duration = 6.0
dt = 0.05
[vessel]
name = "ship"
mass = 4.1e5
inertia = [5.13e6, 1.474e7, 1.63e7]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 400.0
gm_t = 1.67
gm_l = 14.2
[[bodies]]
name = "barge"
position = [0.0, 20.0]
mass = 2.05e5
inertia = [1.5e6, 6.0e6, 7.0e6]
[bodies.hydrostatics]
waterplane_area = 120.0
displaced_volume = 200.0
gm_t = 2.5
gm_l = 20.0
[bodies.initial]
angular_velocity = [0.1, 0.0, 0.0]
velocity = [0.0, 0.3, 0.0]
[[connections]]
name = "link"
kind = "spring"
bodies = ["ship", "barge"]
points = [[0.0, 5.0, 2.0], [0.0, -4.0, 1.0]]
length = 11.0
stiffness = 2.0e5
damping = 1.0e4
"""
GM_T = "bodies.barge.hydrostatics.gm_t"
K = "connections.link.stiffness"


@pytest.fixture(scope="module")
def record():
    scene = js.load_scene(SCENE)
    return scene, js.simulate(scene)


def test_the_channels_of_a_record_with_bodies(record):
    _, r = record
    ch = channels_of(r)
    assert list(ch)[3:] == ["bodies.barge.roll", "bodies.barge.pitch", "bodies.barge.heave", "connections.link"]
    np.testing.assert_array_equal(ch["bodies.barge.roll"], r.bodies["barge"].roll_pitch_yaw[:, 0])
    np.testing.assert_array_equal(ch["connections.link"], r.connections["link"].force)
    assert [channel_unit(c) for c in ch] == ["rad", "rad", "m", "rad", "rad", "m", "N"]
    noisy = add_noise(r, {"bodies.barge.roll": 1e-3, "connections.link": 10.0}, seed=1)
    d = np.asarray(noisy.bodies["barge"].roll_pitch_yaw)[:, 0] - np.asarray(r.bodies["barge"].roll_pitch_yaw)[:, 0]
    assert 5e-4 < d.std() < 2e-3 and np.array_equal(noisy.vessel.roll_pitch_yaw, r.vessel.roll_pitch_yaw)
    with pytest.raises(SceneError, match="noise.bodies.tug.roll"):
        add_noise(r, {"bodies.tug.roll": 1e-3})


@pytest.mark.slow      # about 45 s on a loaded 2-core machine; test_a_bodys_values_reach_its_terms is its fast twin
def test_a_noiseless_fit_recovers_a_bodys_gm_and_a_connections_stiffness(record):
    scene, r = record
    # the record's body channels and the connection's force alone: the vessel's are left out
    weights = {"roll": 0.0, "pitch": 0.0, "heave": 0.0}
    fit = identify(scene, r, [GM_T, K], x0={GM_T: 2.5 * 1.25, K: 2.0e5 * 0.7}, weights=weights)
    assert fit.converged, fit.message
    assert abs(fit.values[GM_T] / 2.5 - 1) < 1e-4 and abs(fit.values[K] / 2.0e5 - 1) < 1e-4, fit.values
    assert fit.channels["bodies.barge.roll"] > 0 and fit.channels["connections.link"] > 0
    assert fit.channels["roll"] == 0.0


@pytest.mark.slow      # about 50 s on a loaded 2-core machine
def test_the_gradient_in_a_bodys_values_matches_central_differences(record):
    scene, _ = record
    keys = [GM_T, "bodies.barge.hydrostatics.waterplane_area", "bodies.barge.mass", K]
    p0 = np.array([2.5, 120.0, 2.05e5, 2.0e5])

    def loss(p):
        r = js.simulate(scene, params=dict(zip(keys, p)))
        b = r.bodies["barge"]
        return (jnp.sum(b.roll_pitch_yaw[:, 0] ** 2) + 100.0 * jnp.sum(b.position[:, 2] ** 2)
                + 1e-10 * jnp.sum(r.connections["link"].force ** 2))

    g = np.asarray(jax.grad(loss)(jnp.asarray(p0)))
    for i in range(len(keys)):
        h = 1e-5 * p0[i]
        e = np.zeros(len(keys))
        e[i] = h
        fd = (float(loss(jnp.asarray(p0 + e))) - float(loss(jnp.asarray(p0 - e)))) / (2 * h)
        assert abs(fd) > 0 and abs(g[i] - fd) <= 1e-5 * abs(fd), (keys[i], g[i], fd)


def test_a_bodys_values_reach_its_terms():
    """What params gives for a body's keys is what its terms hold (traced: jax.grad sees them), and
    its positive values are fitted in log."""
    scene = js.load_scene(SCENE)
    params = {GM_T: 3.0, "bodies.barge.hydrostatics.gm_l": 21.0, "bodies.barge.hydrostatics.waterplane_area": 110.0,
              "bodies.barge.hydrostatics.displaced_volume": 190.0, "bodies.barge.mass": 1.9e5, K: 3.0e5}
    term = build_bodies(scene, resolve_params(scene, params), 9.81)[0]
    rigid = next(t for t in term.bodies[0].terms if isinstance(t, RigidBody))
    h = next(t for t in term.bodies[0].terms if isinstance(t, AbstractRestoring))
    assert (float(h.gm_t), float(h.gm_l), float(h.waterplane_area), float(h.displaced_volume)) == (3.0, 21.0, 110.0,
                                                                                                  190.0)
    assert float(rigid.mass) == 1.9e5 and float(term.links[0].fs[1]) == 3.0e5

    def gm(x):
        t = build_bodies(scene, {GM_T: x}, 9.81)[0]
        return next(t for t in t.bodies[0].terms if isinstance(t, AbstractRestoring)).gm_t

    assert float(jax.grad(gm)(2.0)) == 1.0
    assert positive(GM_T) and positive(K) and positive("bodies.barge.mass")
    assert not positive("connections.link.damping")
    (p,) = make_params(scene, [GM_T], None, None)
    assert (p.lo, p.hi) == (0.0, None)


def test_cli_identify_names_a_bad_body_key(tmp_path, capsys, record):
    scene, r = record
    data = tmp_path / "data.h5"
    js.save_result(r, str(data))
    path = tmp_path / "s.toml"
    path.write_text(SCENE)
    assert main(["identify", str(path), "--data", str(data), "--fit", "bodies.tug.hydrostatics.gm_t"]) == 2
    assert "bodies.tug.hydrostatics.gm_t" in capsys.readouterr().err
    assert main(["identify", str(path), "--data", str(data), "--fit", "bodies.barge.heading"]) == 2
    assert "bodies.barge.heading: cannot be traced" in capsys.readouterr().err
    assert main(["identify", str(path), "--data", str(data), "--fit", "bodies.nosuch.hull.kg"]) == 2
    assert "bodies.nosuch.hull.kg: not a value of this scene" in capsys.readouterr().err
    # the barge has no hull: its springs are what it has
    assert main(["identify", str(path), "--data", str(data), "--fit", "bodies.barge.hull.kg"]) == 2
    assert "bodies.barge.hull.kg: not a value of this scene" in capsys.readouterr().err
