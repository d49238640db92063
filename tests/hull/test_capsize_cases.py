"""A capsized campaign case (issue 32 item 4): its status says so, and it counts as not operable
and as exceeding every limit, as a failed case does."""
import math

import numpy as np

from jaxslosh.campaign.stats import operability
from jaxslosh.run.capsize import capsize_reason


def test_a_record_past_the_angle_of_vanishing_stability_is_capsized():
    t = np.linspace(0.0, 10.0, 201)
    roll = np.radians(80.0) * np.sin(t)           # peaks at 80 deg
    pitch = np.radians(2.0) * np.sin(t)
    angles = (np.radians(75.0), np.radians(60.0))
    why = capsize_reason(roll, pitch, angles)
    assert why is not None and why.startswith("capsized: the roll reached 80.0 deg") and "75.0 deg" in why
    # within both angles, or a hull whose GZ never vanishes on an axis, or no nonlinear hull: not capsized
    assert capsize_reason(0.5 * roll, pitch, angles) is None
    assert capsize_reason(roll, pitch, (None, np.radians(60.0))) is None
    assert capsize_reason(roll, pitch, None) is None
    assert capsize_reason(0.5 * roll, np.radians(61.0) * np.sin(t), angles).startswith("capsized: the pitch")


def test_a_capsized_case_is_not_operable_and_exceeds_every_limit():
    # two cases of equal weight: one rode out the sea well within the limit, one capsized (no statistics)
    stats = {"roll": {"std": np.array([0.01, np.nan]), "tz": np.array([8.0, np.nan]),
                      "max": np.array([0.03, np.nan])}}
    status = ["ok", capsize_reason(np.array([1.5]), np.array([0.0]), (1.3, None))]
    ok = np.array([s == "ok" for s in status])
    out = operability(stats, [0.5, 0.5], ok, {"roll": 0.2}, 3600.0, failed=~ok)
    assert math.isclose(out["operability"], 50.0, rel_tol=1e-12)
    assert math.isclose(out["failed"], 50.0, rel_tol=1e-12)
    assert 0.5 <= out["exceedance"]["roll"] < 0.5 + 1e-6


def test_a_case_whose_body_capsized_is_marked_naming_the_body():
    """A campaign case (campaign/worker.py) is capsized when a [[bodies]] body on its own hull passes
    its angle of vanishing stability, the vessel upright: its status names the body and its axis;
    within every angle it is not, and the vessel's own capsize is said first."""
    from jaxslosh.run.capsize import case_capsize
    t = np.linspace(0.0, 10.0, 201)
    upright = np.zeros((t.size, 3))
    heeled = np.stack([np.radians(80.0) * np.sin(t), np.radians(2.0) * np.sin(t), 0 * t], axis=1)
    angles = (np.radians(75.0), np.radians(60.0))
    why = case_capsize(upright, angles, {"tug": (0.5 * heeled, angles), "barge": (heeled, angles)})
    assert why is not None and why.startswith("capsized: the body 'barge''s roll reached 80.0 deg") and "75.0 deg" in why
    assert case_capsize(upright, angles, {"barge": (0.5 * heeled, angles)}) is None
    assert case_capsize(upright, None, {"barge": (heeled, (None, None))}) is None
    assert case_capsize(heeled, angles, {"barge": (heeled, angles)}).startswith("capsized: the roll")


def test_a_campaign_batch_marks_the_case_whose_body_capsized(monkeypatch):
    """The worker's wiring (campaign/worker.py run_batch), the batch's runs replaced by their records:
    of two cases, the one whose barge rolled past the barge's angle is capsized naming the barge and
    has no statistics; the other, upright, is ok."""
    from types import SimpleNamespace
    from jaxslosh.campaign import worker
    from test_body_campaign import SCENE
    t = np.linspace(0.0, 30.0, 151)
    rpy = np.zeros((2, t.size, 3))
    barge = np.zeros((2, t.size, 3))
    barge[1, :, 0] = np.radians(70.0) * np.sin(t)
    track = lambda r: SimpleNamespace(roll_pitch_yaw=r, position=np.zeros_like(r))  # noqa: E731
    result = SimpleNamespace(time=np.stack([t, t]), vessel=track(rpy), probes={}, mooring=None,
                             bodies={"barge": track(barge)},
                             connections={n: SimpleNamespace(force=np.ones((2, t.size))) for n in ("bow", "stern")})
    monkeypatch.setattr(worker, "simulate_seas", lambda *a: (result, ["ok", "ok"]))
    monkeypatch.setattr(worker, "capsize_angles", lambda s: None)        # the ship has no hull of its own here
    monkeypatch.setattr(worker, "body_capsize_angles", lambda s: {"barge": (np.radians(60.0), None)})
    cases = [{"hs": 0.6, "tp": 7.0, "heading": 1.2, "seed": k} for k in (1, 2)]
    out = worker.run_batch(SCENE, "", None, cases, 2)
    assert out[0]["status"] == "ok" and out[0]["stats"] is not None
    assert out[1]["status"].startswith("capsized: the body 'barge''s roll reached 70.0 deg") and out[1]["stats"] is None
