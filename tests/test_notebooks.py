"""Every notebook runs clean, at a small size (JAXSLOSH_NOTEBOOK_SMALL=1)."""
import os
from pathlib import Path

import nbclient
import nbformat

ROOT = Path(__file__).resolve().parents[1]


def test_quickstart_notebook_runs():
    nb = nbformat.read(ROOT / "notebooks" / "quickstart.ipynb", as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")
    gif = ROOT / "notebooks" / "surface.gif"
    gif.unlink(missing_ok=True)
    old = os.environ.get("JAXSLOSH_NOTEBOOK_SMALL")
    os.environ["JAXSLOSH_NOTEBOOK_SMALL"] = "1"
    try:
        nbclient.NotebookClient(nb, timeout=900, kernel_name="python3",
                                resources={"metadata": {"path": str(ROOT / "notebooks")}}).execute()
    finally:
        if old is None:
            os.environ.pop("JAXSLOSH_NOTEBOOK_SMALL")
        else:
            os.environ["JAXSLOSH_NOTEBOOK_SMALL"] = old
    outs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outs if o.get("output_type") == "error"]
    text = "".join(o.get("text", "") for o in outs)
    assert "ok" in text and "sloshing" in text and "d(peak roll)/d(GM_T)" in text
    # the free-surface animation: 2 s saved every step, every 50th frame shown
    assert "5 frames written to surface.gif" in text
    from PIL import Image
    with Image.open(gif) as im:
        assert im.format == "GIF" and im.n_frames == 5


def test_accuracy_vs_cost_notebook_runs():
    """Draws the committed map (docs/accuracy_cost.csv): no simulation, only the CSV."""
    nb = nbformat.read(ROOT / "notebooks" / "accuracy_vs_cost.ipynb", as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(ROOT / "notebooks")}}).execute()
    outs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outs if o.get("output_type") == "error"]
    text = "".join(o.get("text", "") for o in outs)
    assert "Pareto front (probe B)" in text and "machine" in text


def test_waves_notebook_runs():
    nb = nbformat.read(ROOT / "notebooks" / "waves.ipynb", as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")
    old = os.environ.get("JAXSLOSH_NOTEBOOK_SMALL")
    os.environ["JAXSLOSH_NOTEBOOK_SMALL"] = "1"
    try:
        nbclient.NotebookClient(nb, timeout=900, kernel_name="python3",
                                resources={"metadata": {"path": str(ROOT / "notebooks")}}).execute()
    finally:
        if old is None:
            os.environ.pop("JAXSLOSH_NOTEBOOK_SMALL")
        else:
            os.environ["JAXSLOSH_NOTEBOOK_SMALL"] = old
    outs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outs if o.get("output_type") == "error"]
    text = "".join(o.get("text", "") for o in outs)
    assert "with liquid: ok | frozen: ok" in text and "roll std" in text and "ok" in text
