"""Every notebook runs clean, at a small size (JAXSLOSH_NOTEBOOK_SMALL=1).
(notebooks/identify_metacentric_heights.ipynb runs in tests/fit/test_identify.py.)"""
import re
from pathlib import Path

import pytest

from helpers import printed, run_notebook

ROOT = Path(__file__).resolve().parents[2]


def test_quickstart_notebook_runs():
    gif = ROOT / "notebooks" / "surface.gif"
    gif.unlink(missing_ok=True)
    text = printed(run_notebook("quickstart.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}))
    assert "ok" in text and "sloshing" in text and "d(peak roll)/d(GM_T)" in text
    # the free-surface animation: 2 s saved every step, every 50th frame shown
    assert "5 frames written to surface.gif" in text
    from PIL import Image
    with Image.open(gif) as im:
        assert im.format == "GIF" and im.n_frames == 5


def test_accuracy_vs_cost_notebook_runs():
    """Draws the committed map (docs/accuracy_cost.csv): no simulation, only the CSV."""
    text = printed(run_notebook("accuracy_vs_cost.ipynb", timeout=300))
    assert "Pareto front (probe B)" in text and "machine" in text


# slow, for the default suite's budget: the quickstart notebook and the fitting one run in it
@pytest.mark.slow
def test_waves_notebook_runs():
    text = printed(run_notebook("waves.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}))
    assert "with liquid: ok | frozen: ok" in text and "roll std" in text and "ok" in text


def numbers(pattern: str, text: str) -> list:
    m = re.search(pattern, text)
    assert m, (pattern, text)
    return [float(x) for x in m.groups()]


@pytest.mark.slow
def test_anti_roll_tank_notebook_runs():
    """A few minutes at the small size (the full-order dense liquid's gradient compiles once)."""
    text = printed(run_notebook("anti_roll_tank.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}, timeout=1800))
    # the three shapes' first sloshing modes within 1 % of their closed forms
    pct = [float(x) for x in re.findall(r"closed form [\d.]+ \(([+-][\d.]+) %\)", text)]
    assert len(pct) == 3 and max(abs(p) for p in pct) < 1.0, pct
    # the sloshing mass from the mesh against the equivalent mechanical model's, mu about 0.12
    m1, m1_closed = numbers(r"sloshing mass ([\d.]+) t of the liquid's [\d.]+ t \(closed form ([\d.]+) t\)", text)
    assert abs(m1 / m1_closed - 1) < 0.01, (m1, m1_closed)
    (mu,) = numbers(r"mass ratio mu = ([\d.]+)", text)
    assert 0.10 < mu < 0.14, mu
    # jax.grad through js.rao against central differences of the same objective
    g = numbers(r"gradient \[\s*([-\d.e]+)\s+([-\d.e]+)\s*\] finite differences "
                r"\[\s*([-\d.e]+)\s+([-\d.e]+)\s*\]", text)
    for a, b in ((g[0], g[2]), (g[1], g[3])):
        assert abs(a - b) <= 0.01 * abs(b) + 1e-5, g
    # a few L-BFGS iterations lower the peak, and the re-read scene agrees that the new design is better
    start, end = numbers(r"grid max ([\d.]+) rad/m \(start ([\d.]+)\)", text)[::-1]
    assert end < start, (start, end)
    scene_peak = numbers(r"scene's tank\s+[\d.]+\s+[\d.]+\s+([\d.]+)", text)[0]
    opt_peak = numbers(r"gradient optimum\s+[\d.]+\s+[\d.]+\s+([\d.]+)", text)[0]
    frozen_peak = numbers(r"liquid frozen\s+([\d.]+)", text)[0]
    assert opt_peak < scene_peak < 0.5 * frozen_peak, (opt_peak, scene_peak, frozen_peak)
    assert "Den Hartog" in text


@pytest.mark.slow
def test_campaign_notebook_runs():
    """A few minutes at the small size (two Dask workers each compile a batch)."""
    text = printed(run_notebook("campaign.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}, timeout=1800))
    assert "4 cases (2 sea states x 2 headings), 40 s each: 4 ok, 0 failed" in text
    (op,) = numbers(r"operability ([\d.]+) %", text)
    assert 0.0 <= op <= 100.0
    # beam seas roll the ship and head seas pitch it, at their coupled modes' frequencies
    roll_w = numbers(r"heading\s+90.0 deg: roll peak\s+[\d.]+ deg/m at ([\d.]+) rad/s", text)[0]
    pitch_w = numbers(r"heading\s+0.0 deg: roll peak\s+[\d.]+ deg/m at [\d.]+ rad/s, pitch peak\s+[\d.]+ deg/m "
                      r"at ([\d.]+) rad/s", text)[0]
    modes = dict((d, float(w)) for w, d in re.findall(r"^\s*\d+\s+([\d.]+)\s+[\d.]+\s+[\d.]+\s+(\w+) \(", text, re.M))
    assert abs(roll_w - modes["roll"]) < 0.06 and abs(pitch_w - modes["pitch"]) < 0.06, (roll_w, pitch_w, modes)
    assert "liquid" in modes


@pytest.mark.slow
def test_parametric_roll_notebook_runs():
    """A few minutes at the small size (each wave frequency of the map compiles once)."""
    text = printed(run_notebook("parametric_roll.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}, timeout=1800))
    (start,) = numbers(r"roll disturbance ([\d.]+) deg", text)
    peaks = {name: float(v) for name, v in re.findall(
        r"^(nonlinear|linear|anti-roll tank)\s+ok: roll peak over the last 10 s\s+([\d.]+) deg", text, re.M)}
    # 20 s: the nonlinear roll has grown, the linear one and the tank's have decayed
    assert peaks["nonlinear"] > start > peaks["linear"] and peaks["anti-roll tank"] < 0.5 * start, peaks
    # the tank frozen and added back is the plain ship
    (d,) = numbers(r"largest difference ([\d.e+-]+) deg", text)
    assert d < 1e-6, d
    # the hull's GM on the scene's wave swings about its mean by about 30 %, above the damping's threshold
    (h,) = numbers(r"mean [\d.]+ m, h = ([\d.]+)", text)
    (threshold,) = numbers(r"threshold h = 4 lambda / omega_0 = ([\d.]+)", text)
    assert threshold < 0.2 < h < 0.4, (h, threshold)
    assert "not ok" not in text


@pytest.mark.slow
def test_nonlinear_sloshing_notebook_runs():
    """A few minutes at the small size (4 s runs of each tank, two batches of 3 frequencies)."""
    text = printed(run_notebook("nonlinear_sloshing.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}, timeout=1800))
    # 1 mm: the multimodal tank (8 modes) and the finite elements (16 x 1 x 6) within a few per cent
    (d,) = numbers(r"multimodal against finite elements: largest difference ([\d.]+) %", text)
    assert d < 5.0, d
    # 32 mm: the multimodal crests stand higher above the troughs than the linear ones
    ratio = {name: float(v) for name, v in re.findall(
        r"^(multimodal|fem)\s+[\d.]+%\s+[+-][\d.]+%\s+[+-][\d.]+%\s+([\d.]+)$", text, re.M)}
    assert ratio["multimodal"] > 1.4 and ratio["fem"] < 1.2, ratio
    assert text.count("3 runs, 3 ok") == 2, text


@pytest.mark.slow
def test_moored_spar_notebook_runs():
    """Several minutes on a shared 2-core machine at the small size (three compilations)."""
    text = printed(run_notebook("moored_spar.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}, timeout=1800))
    assert "with the tank: ok | without: ok" in text
    closed, fem = numbers(r"first mode ([\d.]+) rad/s \(closed form\), ([\d.]+) rad/s", text)
    assert abs(fem / closed - 1) < 0.005
    g, fd = numbers(r"jax.grad ([-\d.e+]+) N/m, finite difference ([-\d.e+]+) N/m", text)
    assert abs(g - fd) <= 1e-3 * abs(fd), (g, fd)


@pytest.mark.slow
def test_flng_side_by_side_notebook_runs():
    """Minutes at the small size (two builds of the FLNG with its lines and tanks, two compiles)."""
    text = printed(run_notebook("flng_side_by_side.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}, timeout=1800))
    assert "sloshing: ok" in text and "frozen: ok" in text
    # the frozen LNG: the four tanks' 35,127 t (their sections by hand, tests/bodies/test_flng_side_by_side.py)
    (tonnes,) = numbers(r"LNG ([\d,]+) t;", text.replace(",", ""))
    assert abs(tonnes / 35127 - 1) < 0.002, tonnes
    assert "largest fender kN" in text and "manifold y m" in text
