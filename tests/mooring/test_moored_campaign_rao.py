"""A moored box (three catenary lines 120 deg apart, fairleads at the COG so that the lines hold
the translations alone): its lines' fairlead tensions as campaign channels `mooring.<line>`, and its
surge RAO against the free box's through the lines' stiffness (docs/guide/moorings.md)."""
from types import SimpleNamespace

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.campaign.cases import case_scene
from jaxslosh.campaign.run import channel_names
from jaxslosh.campaign.stats import channels, statistics
from jaxslosh.campaign.worker import run_batch
from jaxslosh.scene.types import SceneError

BOX = """
title = "moored box"
[environment]
gravity = 9.81
water_density = 1025.0
depth = 50.0
[simulation]
duration = 60.0
dt = 0.1
scheme = "newmark"
save_every = 2
[vessel]
mass = 4.1e5
inertia = [6.0e6, 1.6e7, 2.0e7]
[vessel.hull]
length = 20.0
beam = 10.0
draft = 2.0
kg = 2.5
[vessel.hydrodynamics]
viscous_damping = [0.0, 0.0, 1.0e5, 1.5e6, 5.0e6, 0.0]
"""
WAVES = """
[waves]
type = "pierson-moskowitz"
hs = 0.5
tp = 7.0
heading = 0.3
seed = 0
components = 30
frequency_range = [0.3, 2.5]
ramp = 10.0
"""
LINE = """
[[mooring]]
name = "line{i}"
fairlead = [0.0, 0.0, 0.0]
anchor = [{x:.6f}, {y:.6f}, -50.0]
length = 260.0
weight = 300.0
ea = 5.0e8
"""


def lines(radius=240.0):
    return "".join(LINE.format(i=i + 1, x=radius * np.cos(np.radians(a)), y=radius * np.sin(np.radians(a)))
                   for i, a in enumerate((180.0, 300.0, 60.0)))


@pytest.mark.slow      # about 100 s on a shared 2-core machine; the fast test below checks the channels
def test_a_moored_campaign_has_each_lines_fairlead_tension_as_a_channel():
    """The worker's statistics of `mooring.<line>` against the same case run alone: its fairlead
    tension's statistics over the frames after the ramp."""
    text = BOX + WAVES + lines()
    template = js.load_scene(text)
    assert channel_names(template) == ["roll", "pitch", "heave", "mooring.line1", "mooring.line2", "mooring.line3"]
    values = [{"hs": 0.5, "tp": 7.0, "heading": 0.3, "seed": k} for k in range(2)]
    out = run_batch(text, "", None, values, 2)
    assert [o["status"] for o in out] == ["ok", "ok"]
    alone = js.simulate(case_scene(template, values[1]))
    t = np.asarray(alone.time)
    keep = t >= 10.0 - 1e-9
    for name in ("line1", "line2", "line3"):
        st = out[1]["stats"][f"mooring.{name}"]
        ref = statistics(t[keep], np.asarray(alone.mooring[name].fairlead_tension)[keep])
        assert st["std"] > 10.0                              # N: the lines respond to the sea
        for k in ("std", "max", "tz"):
            assert abs(st[k] - ref[k]) <= 1e-6 * abs(ref[k])
    # the seeds differ, so do their tensions
    assert abs(out[0]["stats"]["mooring.line1"]["std"] / out[1]["stats"]["mooring.line1"]["std"] - 1) > 1e-3


def test_the_channels_of_a_result_take_each_lines_fairlead_tension():
    line = SimpleNamespace(fairlead_tension=np.arange(8.0).reshape(2, 4) + 1e6, anchor_tension=np.zeros((2, 4)))
    result = SimpleNamespace(vessel=SimpleNamespace(roll_pitch_yaw=np.zeros((2, 4, 3)), position=np.zeros((2, 4, 3))),
                             probes={}, mooring={"bow": line})
    ch = channels(result, 1)
    assert list(ch) == ["roll", "pitch", "heave", "mooring.bow"]
    np.testing.assert_array_equal(ch["mooring.bow"], [1e6 + 4, 1e6 + 5, 1e6 + 6, 1e6 + 7])


def test_line_tension_limits_in_the_campaign_table():
    limits = '\n[campaign]\n[campaign.limits]\nroll = 0.1\n"mooring.line1" = 2.0e4\nmooring.line2 = 3.0e4\n'
    s = js.load_scene(BOX + WAVES + lines() + limits)
    assert dict(s.campaign.limits) == {"roll": 0.1, "mooring.line1": 2.0e4, "mooring.line2": 3.0e4}
    with pytest.raises(SceneError, match=r"campaign\.limits\.mooring\.line9.*mooring\.line3"):
        js.load_scene(BOX + WAVES + lines() + '\n[campaign]\n[campaign.limits]\nmooring.line9 = 1.0\n')
    with pytest.raises(SceneError, match=r"campaign\.limits\.mooring\.line1.*positive limit in N"):
        js.load_scene(BOX + WAVES + lines() + '\n[campaign]\n[campaign.limits]\nmooring.line1 = -1.0\n')


@pytest.mark.slow      # about 50 s on a shared 2-core machine (two RAOs' linearisations)
def test_the_lines_stiffness_divides_the_free_surge_rao():
    """With no radiation tables and fairleads at the COG the box's surge is one dof: free,
    X0 = F / (-m w^2); moored, X = F / (K11 - m w^2), K11 from js.mooring. So X / X0 =
    m w^2 / (m w^2 - K11) at every frequency, through the resonance at sqrt(K11 / m) (a 70 s
    period here)."""
    free, moored = js.load_scene(BOX), js.load_scene(BOX + lines())
    K = np.asarray(js.mooring(moored).stiffness)
    m = 4.1e5
    assert abs(2 * np.pi * np.sqrt(m / K[0, 0]) - 70.08) < 0.1
    w = np.array([0.05, 0.08, 0.1, 0.2, 0.5, 1.0])
    x0 = np.asarray(js.rao(free, w, [0.0]).vessel)[:, 0, 0]
    x = np.asarray(js.rao(moored, w, [0.0]).vessel)[:, 0, 0]
    expected = m * w ** 2 / (m * w ** 2 - K[0, 0])
    np.testing.assert_allclose(x / x0, expected, rtol=1e-6)   # the damped heave and pitch: 1e-8
    # below the resonance the moored box lags the free one by half a turn and tends to the static
    # offset: X -> F / K11, so X / X0 -> -m w^2 / K11
    assert x[0] / x0[0] < 0
