"""The command line's progress and `jaxslosh plot`'s input (issue 21): compilation as a phase of its
own with one clock shared by the bar and the summary line, the animation's frames counted, sweep
files plotted, and every unreadable file, folder or bad number refused in one line (exit 2)."""
import dataclasses
import importlib.util
import io
import os
import re
import threading
import types

import h5py
import jax
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.text import Text
import pytest

from jaxslosh.cli import main
from jaxslosh.io.result import Result, ResultFileError, load_result, save_result
from jaxslosh.io.sweep import load_sweep, write_sweep
from jaxslosh.plot.results import plot_result, plot_sweep, scene_title
from jaxslosh.run.progress import ENV, Progress, wanted

from helpers import VESSEL
from test_plot import hand_result

GOOD = VESSEL.format(duration=1.0, dt=0.01, scheme="hht", alpha=0.01, omega=[0.02, 0.01, 0.0], position=[0, 0, 0])
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _one_line_error(capsys, *needles):
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    for n in needles:
        assert n in lines[0], lines[0]
    return lines[0]


# -- progress ---------------------------------------------------------------------------------------

class _Tty(io.StringIO):
    def __init__(self, tty):
        super().__init__()
        self.tty = tty

    def isatty(self):
        return self.tty


def test_progress_is_drawn_on_a_terminal_or_when_forced(monkeypatch):
    monkeypatch.delenv(ENV, raising=False)
    assert wanted(False, _Tty(True)) and not wanted(False, _Tty(False))
    monkeypatch.setenv(ENV, "1")
    assert wanted(False, _Tty(False))
    assert not wanted(True, _Tty(True))              # --no-progress wins over everything
    monkeypatch.setenv(ENV, "0")
    assert not wanted(False, _Tty(True))


class _Clock:
    """A clock that moves only when the test moves it (for progress.py's `_time`): the phases'
    bookkeeping is then checked exactly, whatever the machine's speed."""

    def __init__(self, t=100.0):
        self.t = t

    def perf_counter(self):
        return self.t


def test_progress_phases_share_one_clock_and_estimate_only_after_units_are_done(monkeypatch):
    import jaxslosh.run.progress as progress
    clock = _Clock()
    monkeypatch.setattr(progress, "_time", clock)
    out = io.StringIO()
    bar = Progress(enabled=True, stream=out, tick=0.01)
    bar.phase("compile", "compiling the step")
    clock.t += 7.25
    bar.phase("stepping", "stepping", total=10)
    first = out.getvalue().split("\r")[-1]
    assert "0/10" in first and "estimating" in first and "left" not in first
    clock.t += 0.05                                   # past the redraw interval: update draws
    bar.update(5)
    assert "5/10" in out.getvalue() and "left" in out.getvalue().split("\r")[-1]
    clock.t += 0.05
    bar.update(10)
    times = bar.close()
    assert list(times) == ["compile", "stepping"] and all(t >= 0 for t in times.values())
    # contiguous phases: their sum is the elapsed time since the bar was made
    assert times == pytest.approx({"compile": 7.25, "stepping": 0.1}, abs=1e-12)
    assert abs(sum(times.values()) - bar.elapsed()) < 1e-12
    assert "compiling the step ... " in out.getvalue() and "100.0%" in out.getvalue()
    quiet = io.StringIO()
    q = Progress(enabled=False, stream=quiet)
    q.phase("a", "a")
    assert list(q.close()) == ["a"] and quiet.getvalue() == ""     # timed, not drawn


class _StepClock(_Clock):
    """Moves 1 ms each time the command's own thread reads it (the redrawing thread reads it as it
    is): the run's phases then take as many clock steps as the calls between them, whatever the
    machine's speed."""

    def perf_counter(self):
        if threading.current_thread() is threading.main_thread():
            self.t += 1e-3
        return self.t


def test_run_shows_the_compile_phase_and_a_summary_on_the_bar_clock(tmp_path, capsys, monkeypatch):
    import jaxslosh.run.progress as progress
    monkeypatch.setattr(progress, "_time", _StepClock())
    monkeypatch.setenv(ENV, "1")                      # capsys' stderr is no terminal: forced on
    scene = tmp_path / "v.toml"
    scene.write_text(GOOD)
    out = tmp_path / "v.h5"
    assert main(["run", str(scene), "-o", str(out)]) == 0
    cap = capsys.readouterr()
    draws = [d.strip() for d in re.split(r"[\r\n]", cap.err) if d.strip()]
    assert any(d.startswith("compiling the step ... ") for d in draws)
    stepping = [d for d in draws if d.startswith("stepping")]
    # the first draw of the steps comes before any chunk ran: no estimate yet
    assert "step 0/100" in stepping[0] and "estimating" in stepping[0]
    assert "100.0% step 100/100" in stepping[-1]
    # no compile line after the steps began: compilation is over before the first chunk runs
    assert max(i for i, d in enumerate(draws) if d.startswith("compiling")) < draws.index(stepping[0])
    m = re.search(r"in ([\d.]+) s wall \(build ([\d.]+) s, compile ([\d.]+) s, stepping ([\d.]+) s\)", cap.out)
    assert m, cap.out
    total, build, comp, step = map(float, m.groups())
    assert min(total, build, comp, step) >= 0
    assert comp + step <= total + 0.01                 # printed to 0.01 s
    assert abs(build + comp + step - total) <= 0.02
    shown = float(re.search(r"([\d.]+) s elapsed", stepping[-1]).group(1))
    assert abs(shown - total) <= 0.06                  # the bar's last elapsed time, printed to 0.1 s
    assert load_result(str(out)).steps_done == 100


# -- the animation's progress ---------------------------------------------------------------------

def test_animation_counts_its_frames_on_stderr(tmp_path, capsys, monkeypatch):
    h5 = tmp_path / "r.h5"
    save_result(hand_result(), str(h5))
    monkeypatch.setenv(ENV, "1")
    args = ["plot", str(h5), "-o", str(tmp_path / "r.png"), "--animate", str(tmp_path / "a.gif"), "--every", "4"]
    assert main(args) == 0
    err = capsys.readouterr().err
    assert "writing the animation" in err and "frame 4/4" in err and "100.0%" in err
    assert main(args + ["--no-progress"]) == 0
    assert "writing the animation" not in capsys.readouterr().err


# -- bad numbers, folders ---------------------------------------------------------------------------

@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "0", "-2"])
def test_scale_must_be_positive_and_finite(tmp_path, capsys, value):
    h5 = tmp_path / "r.h5"
    save_result(hand_result(), str(h5))
    assert main(["plot", str(h5), "--surface", str(tmp_path / "s.png"), f"--scale={value}"]) == 2
    _one_line_error(capsys, "--scale")
    assert not (tmp_path / "s.png").exists()


def test_a_folder_is_refused_in_one_line(tmp_path, capsys):
    assert main(["plot", str(tmp_path)]) == 2
    _one_line_error(capsys, str(tmp_path), "directory")
    assert main(["run", str(tmp_path)]) == 2
    _one_line_error(capsys, str(tmp_path), "directory")
    h5 = tmp_path / "r.h5"
    save_result(hand_result(), str(h5))
    assert main(["plot", str(h5), "-o", str(tmp_path)]) == 2
    _one_line_error(capsys, "-o", "folder")


def test_a_figure_name_that_is_no_image_is_refused_before_drawing(tmp_path, capsys, monkeypatch):
    """Issue 31, item 7: `-o fig.txt` (or .toml) exits 2 at once, naming the flag and the formats,
    before any figure is drawn; the same for --surface."""
    import jaxslosh.cli.plot as cli_plot
    drawn = []
    monkeypatch.setattr(cli_plot, "plot_result", lambda *a: drawn.append(a))
    h5 = _saved(tmp_path)
    for flag, name in (("-o", "fig.txt"), ("-o", "fig.toml"), ("--surface", "s.h5")):
        assert main(["plot", str(h5), flag, str(tmp_path / name)]) == 2
        _one_line_error(capsys, flag, name, ".png", ".pdf")
        assert not (tmp_path / name).exists()
    assert drawn == []


def test_a_figure_name_without_extension_gets_png_and_is_said(tmp_path, capsys):
    """Issue 31, item 13: `-o figure_noext` writes figure_noext.png and says so (not "wrote
    figure_noext"); an upper-case extension is an image too."""
    h5 = _saved(tmp_path)
    assert main(["plot", str(h5), "-o", str(tmp_path / "figure_noext"), "--surface", str(tmp_path / "surf")]) == 0
    out = capsys.readouterr().out
    assert f"wrote {tmp_path / 'figure_noext.png'}\n" in out and f"wrote {tmp_path / 'surf.png'}\n" in out
    assert (tmp_path / "figure_noext.png").stat().st_size > 1000 and not (tmp_path / "figure_noext").exists()
    assert (tmp_path / "surf.png").exists()
    assert main(["plot", str(h5), "-o", str(tmp_path / "fig.PDF")]) == 0
    assert (tmp_path / "fig.PDF").read_bytes()[:4] == b"%PDF"


# -- unreadable result files -----------------------------------------------------------------------

def _saved(tmp_path, name="r.h5"):
    h5 = tmp_path / name
    save_result(hand_result(), str(h5))
    return h5


def test_truncated_and_corrupt_files_exit_2_naming_the_file(tmp_path, capsys):
    whole = _saved(tmp_path).read_bytes()
    cut = tmp_path / "cut.h5"
    cut.write_bytes(whole[: len(whole) // 3])
    bad = tmp_path / "bad.h5"                        # the header intact, the data after it overwritten
    bad.write_bytes(whole[:4096] + b"\xff" * (len(whole) - 4096))
    text = tmp_path / "text.h5"
    text.write_text("not HDF5 at all\n")
    for path in (cut, bad, text):
        assert main(["plot", str(path), "-o", str(tmp_path / "x.png")]) == 2
        _one_line_error(capsys, str(path))
        with pytest.raises(ResultFileError, match=re.escape(str(path))):
            load_result(str(path))
    assert not (tmp_path / "x.png").exists()


def test_a_missing_dataset_is_named(tmp_path, capsys):
    h5 = _saved(tmp_path)
    with h5py.File(h5, "a") as f:
        del f["vessel/quaternion"]
    assert main(["plot", str(h5)]) == 2
    _one_line_error(capsys, str(h5), "/vessel/quaternion", "missing")


def test_frames_are_cut_to_those_every_dataset_holds(tmp_path):
    """A run stopped inside a chunk's append: the datasets grown so far are longer than the rest."""
    h5 = _saved(tmp_path)
    with h5py.File(h5, "a") as f:
        f["energy/kinetic"].resize(9, axis=0)
    r = load_result(str(h5))
    assert r.time.shape == (9,) and r.vessel.quaternion.shape == (9, 4) and r.tanks["tank"].displacement.shape[0] == 9


def test_a_newer_format_version_is_refused_and_a_missing_one_is_1(tmp_path, capsys):
    h5 = _saved(tmp_path)
    with h5py.File(h5, "a") as f:
        f.attrs["format_version"] = 2
    with pytest.raises(ResultFileError, match="format_version 2 is newer"):
        load_result(str(h5))
    assert main(["plot", str(h5)]) == 2
    _one_line_error(capsys, str(h5), "format_version 2")
    with h5py.File(h5, "a") as f:
        f.attrs["format_version"] = "one"
    with pytest.raises(ResultFileError, match="format_version"):
        load_result(str(h5))
    with h5py.File(h5, "a") as f:
        del f.attrs["format_version"]
    assert isinstance(load_result(str(h5)), Result)


# -- titles -----------------------------------------------------------------------------------------

def test_the_figure_is_titled_with_the_scene(tmp_path):
    r = hand_result()
    assert plot_result(r, str(tmp_path / "a.png")).get_suptitle() == "test vessel"
    failed = dataclasses.replace(hand_result(), status="diverged")
    assert plot_result(failed, str(tmp_path / "b.png")).get_suptitle() == "test vessel  [diverged]"
    assert scene_title("") == "jaxslosh result" and scene_title("not = [toml") == "jaxslosh result"


# -- sweep files ------------------------------------------------------------------------------------

def _sweep(tmp_path, runs=3):
    rs = [hand_result(tanks=False, roll=0.02 * (i + 1)) for i in range(runs)]
    batch = jax.tree_util.tree_map(lambda *x: np.stack([np.asarray(v) for v in x]), *rs)
    params = {"vessel.hydrostatics.gm_t": np.array([1.2, 1.5, 1.8][:runs])}
    path = tmp_path / "sweep.h5"
    write_sweep(str(path), types.SimpleNamespace(text=rs[0].scene_text), params, batch,
                ["ok"] * (runs - 1) + ["step 5: did not converge"])
    return path


def test_a_sweep_file_is_plotted_with_its_runs_overlaid(tmp_path, capsys):
    path = _sweep(tmp_path)
    sw = load_sweep(str(path))
    assert sw.result.time.shape == (3, 13) and list(sw.params) == ["vessel.hydrostatics.gm_t"]
    png = tmp_path / "sweep.png"
    assert main(["plot", str(path), "-o", str(png)]) == 0
    assert "3 runs" in capsys.readouterr().out and png.stat().st_size > 1000
    fig = plot_sweep(sw.params, sw.result, sw.statuses, str(tmp_path / "again.png"), sw.scene_text)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["gm_t = 1.2", "gm_t = 1.5", "gm_t = 1.8 [failed]"]
    assert fig.get_suptitle().startswith("test vessel: 3 runs (gm_t 1.2 to 1.8)")
    # a single result's reader and the surface figures say what a sweep file is
    with pytest.raises(ResultFileError, match="sweep file"):
        load_result(str(path))
    assert main(["plot", str(path), "--animate", str(tmp_path / "a.gif")]) == 2
    _one_line_error(capsys, "--animate", "sweep file", "jaxslosh run")


# -- the accuracy-cost map --------------------------------------------------------------------------

def test_the_accuracy_cost_maps_labels_do_not_overlap(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(ROOT)      # the benchmarks are a package of the repository root
    mod = importlib.import_module("benchmarks.speed.accuracy_cost")
    rows, host = mod.read_csv(os.path.join(ROOT, "docs", "accuracy_cost.csv"))
    assert len(rows) == 12 and "cores" in host
    fig = mod.plot(rows, str(tmp_path / "map.png"), host)
    try:
        renderer = fig.canvas.get_renderer()
        for ax in fig.axes:
            # the text's own box (an Annotation's extent includes its leader line)
            boxes = [Text.get_window_extent(t, renderer) for t in ax.texts]
            assert len(boxes) >= 10                 # every point labelled (coincident points share one)
            for i in range(len(boxes)):
                for j in range(i + 1, len(boxes)):
                    assert not boxes[i].overlaps(boxes[j]), (ax.texts[i].get_text(), ax.texts[j].get_text())
    finally:
        plt.close(fig)
