"""Every notebook runs clean, at a small size (JAXSLOSH_NOTEBOOK_SMALL=1).
(notebooks/identify_metacentric_heights.ipynb runs in tests/test_identify.py.)"""
from pathlib import Path

from helpers import printed, run_notebook

ROOT = Path(__file__).resolve().parents[1]


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


def test_waves_notebook_runs():
    text = printed(run_notebook("waves.ipynb", {"JAXSLOSH_NOTEBOOK_SMALL": "1"}))
    assert "with liquid: ok | frozen: ok" in text and "roll std" in text and "ok" in text
