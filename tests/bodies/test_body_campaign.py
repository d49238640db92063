"""Campaign channels of a scene with bodies: `<body>.roll`, `<body>.pitch`, `<body>.heave` per body
and `connection.<name>` (its force), their statistics equal to those of a plain `jaxslosh run` of
the same case, and their limits (docs/guide/campaigns.md, docs/guide/bodies-and-connections.md)."""
from types import SimpleNamespace

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.campaign.cases import case_scene
from jaxslosh.campaign.run import channel_names
from jaxslosh.campaign.stats import channels, statistics
from jaxslosh.campaign.worker import run_batch
from jaxslosh.cli import main
from jaxslosh.scene.campaign import unit

# a box ship (its waves' Froude-Krylov force) with a barge beside it on two springs: the waves
# reach the barge through the springs alone (it has no excitation tables)
SCENE = """
title = "box and barge in irregular seas"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = 30.0
dt = 0.1
scheme = "newmark"
save_every = 2
[vessel]
name = "ship"
mass = 4.1e5
inertia = [6.0e6, 1.6e7, 2.0e7]
[vessel.hull]
length = 20.0
beam = 10.0
draft = 2.0
kg = 2.5
[vessel.hydrodynamics]
viscous_damping = [0.0, 0.0, 1.0e5, 1.5e6, 5.0e6, 0.0]
[waves]
type = "pierson-moskowitz"
hs = 0.3
tp = 7.0
heading = 1.5707963267948966
seed = 0
components = 20
frequency_range = [0.3, 2.5]
ramp = 10.0
[[bodies]]
name = "barge"
position = [0.0, 16.0]
mass = 2.05e5
inertia = [1.5e6, 6.0e6, 7.0e6]
[bodies.hydrostatics]
waterplane_area = 120.0
displaced_volume = 200.0
gm_t = 2.5
gm_l = 20.0
[bodies.hydrodynamics]
viscous_damping = [1.0e4, 1.0e4, 5.0e4, 2.0e5, 5.0e5, 5.0e5]
[[connections]]
name = "bow"
kind = "spring"
bodies = ["ship", "barge"]
points = [[8.0, 5.0, 1.0], [6.0, -4.0, 1.0]]
length = 7.0
stiffness = 2.0e5
damping = 2.0e4
[[connections]]
name = "stern"
kind = "spring"
bodies = ["ship", "barge"]
points = [[-8.0, 5.0, 1.0], [-6.0, -4.0, 1.0]]
length = 7.0
stiffness = 2.0e5
damping = 2.0e4
"""
CHANNELS = ["roll", "pitch", "heave", "barge.roll", "barge.pitch", "barge.heave", "connection.bow",
            "connection.stern"]


@pytest.mark.slow      # two compilations (the batch's and the run's), about 80 s on a loaded 2-core machine
def test_a_campaigns_body_and_connection_statistics_are_those_of_a_plain_run(tmp_path):
    template = js.load_scene(SCENE)
    values = {"hs": 0.6, "tp": 7.0, "heading": 1.2, "seed": 1}
    out = run_batch(SCENE, "", None, [values], 1)
    assert out[0]["status"] == "ok" and list(out[0]["stats"]) == CHANNELS
    case = tmp_path / "case.toml"
    case.write_text(case_scene(template, values).text)
    assert main(["run", str(case), "-o", str(tmp_path / "case.h5"), "--no-progress"]) == 0
    r = js.load_result(str(tmp_path / "case.h5"))
    t = np.asarray(r.time)
    keep = t >= 10.0 - 1e-9
    series = {"barge.roll": np.asarray(r.bodies["barge"].roll_pitch_yaw)[:, 0],
              "barge.pitch": np.asarray(r.bodies["barge"].roll_pitch_yaw)[:, 1],
              "barge.heave": np.asarray(r.bodies["barge"].position)[:, 2],
              "connection.bow": np.asarray(r.connections["bow"].force),
              "connection.stern": np.asarray(r.connections["stern"].force)}
    for ch, x in series.items():
        st, ref = out[0]["stats"][ch], statistics(t[keep], x[keep])
        assert st["std"] > (1e-4 if ch.startswith("barge.") else 10.0), ch     # they respond to the sea
        # a batch refreshes its Newton preconditioner every 4 steps, a run when convergence slows:
        # both to Newton's tolerance
        for k in ("std", "max", "tz"):
            assert abs(st[k] - ref[k]) <= 1e-6 * abs(ref[k]), (ch, k)


def test_the_channels_of_a_scene_and_a_result_with_bodies():
    assert channel_names(js.load_scene(SCENE)) == CHANNELS
    frames = np.arange(8.0).reshape(2, 4)
    body = SimpleNamespace(roll_pitch_yaw=np.stack([frames, 2 * frames, 3 * frames], -1),
                           position=np.stack([0 * frames, 0 * frames, 5 * frames], -1))
    result = SimpleNamespace(vessel=SimpleNamespace(roll_pitch_yaw=np.zeros((2, 4, 3)), position=np.zeros((2, 4, 3))),
                             probes={}, mooring=None, bodies={"barge": body},
                             connections={"bow": SimpleNamespace(force=frames + 1e5)})
    ch = channels(result, 1)
    assert list(ch) == ["roll", "pitch", "heave", "barge.roll", "barge.pitch", "barge.heave", "connection.bow"]
    np.testing.assert_array_equal(ch["barge.pitch"], 2 * frames[1])
    np.testing.assert_array_equal(ch["barge.heave"], 5 * frames[1])
    np.testing.assert_array_equal(ch["connection.bow"], frames[1] + 1e5)
    assert [unit(c) for c in CHANNELS] == ["rad", "rad", "m", "rad", "rad", "m", "N", "N"]
    assert unit("probe.roll") == "m"            # a probe named roll: a displacement


def test_limits_on_body_and_connection_channels():
    limits = '\n[campaign.limits]\nroll = 0.1\nbarge.roll = 0.15\n"barge.heave" = 0.5\n"connection.bow" = 1e5\n'
    s = js.load_scene(SCENE + limits)
    assert dict(s.campaign.limits) == {"roll": 0.1, "barge.roll": 0.15, "barge.heave": 0.5, "connection.bow": 1e5}


@pytest.mark.parametrize("limits, key", [
    ('tug.roll = 0.1', "campaign.limits.tug.roll"),
    ('"connection.aft" = 1e5', "campaign.limits.connection.aft"),
    ('"barge.yaw" = 0.1', "campaign.limits.barge.yaw"),
    ('"connection.bow" = -1.0', "campaign.limits.connection.bow"),
])
def test_a_bad_body_limit_exits_2_naming_the_key(tmp_path, capsys, limits, key):
    p = tmp_path / "s.toml"
    p.write_text(SCENE + "\n[campaign.limits]\n" + limits + "\n")
    s = tmp_path / "scatter.csv"
    s.write_text("hs,tp,occurrences\n0.3,6.0,1\n")
    assert main(["campaign", str(p), "--scatter", str(s), "-o", str(tmp_path / "c.h5")]) == 2
    assert key in capsys.readouterr().err
    assert not (tmp_path / "c.h5").exists()


def test_a_bad_body_limit_on_the_command_line_exits_2(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(SCENE)
    s = tmp_path / "scatter.csv"
    s.write_text("hs,tp,occurrences\n0.3,6.0,1\n")
    assert main(["campaign", str(p), "--scatter", str(s), "--limits", "tug.heave=0.5",
                 "-o", str(tmp_path / "c.h5")]) == 2
    assert "tug.heave" in capsys.readouterr().err
    assert not (tmp_path / "c.h5").exists()
