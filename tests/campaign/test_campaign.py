"""Campaigns: response statistics against the frequency domain and Rayleigh, the Dask path (a local
cluster started here: 1 vs 2 workers, a killed worker, a killed campaign resumed), the command's
bad input. Small cases: the box alone (Froude-Krylov, a viscous roll damping), coarse dt."""
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from dask.distributed import Client, LocalCluster

import jaxslosh as js
from jaxslosh.campaign.cases import case_scene, read_scatter, ScatterError
from jaxslosh.campaign.stats import exceedance, statistics
from jaxslosh.campaign.worker import run_batch
from jaxslosh.cli import main
from jaxslosh.hydro.spectra import spectrum
from jaxslosh.io.campaign import load_campaign
from jaxslosh.io.output import OutputLock

ROOT = Path(__file__).resolve().parents[2]
BEAM = 1.5707963267948966

SCENE = """
title = "box alone in irregular seas"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
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
[waves]
type = "pierson-moskowitz"
hs = 0.3
tp = 7.0
heading = 1.5707963267948966
seed = 0
components = {components}
frequency_range = [0.3, 2.5]
ramp = 10.0
"""

SCATTER = "hs,tp,occurrences\n0.3,6.0,30\n0.6,7.0,50\n0.9,8.0,20\n"


def scene_text(duration=60.0, components=30):
    return SCENE.format(duration=duration, components=components)


def _environment():
    """Workers (and subprocesses) import this worktree's package, share one compilation cache."""
    return {"PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "tests"), os.environ.get("PYTHONPATH", "")]),
            "JAXSLOSH_CACHE_DIR": str(CACHE), "JAXSLOSH_PROGRESS": "0"}


@pytest.fixture
def env(tmp_path, monkeypatch):
    for k, v in _environment().items():
        monkeypatch.setenv(k, v)
    return tmp_path


CACHE = Path(os.environ.get("TMPDIR", "/tmp")) / f"jaxslosh-test-campaign-cache-{os.getuid()}"


def files(tmp_path, duration=60.0):
    p = tmp_path / "box.toml"
    p.write_text(scene_text(duration))
    s = tmp_path / "scatter.csv"
    s.write_text(SCATTER)
    return p, s


# --------------------------------------------------------------------------------------------
# statistics against theory


def test_statistics_of_a_sine_and_the_rayleigh_exceedance():
    t = np.arange(0.0, 1000.0, 0.05)
    st = statistics(t, 2.0 * np.sin(2 * np.pi * t / 8.0) + 5.0)
    assert abs(st["std"] - np.sqrt(2.0)) < 1e-3 and abs(st["significant"] - 4 * np.sqrt(2.0)) < 4e-3
    assert abs(st["tz"] - 8.0) < 0.01 and abs(st["max"] - 2.0) < 1e-3
    f = np.fft.rfftfreq(len(t) // 4, 0.05) * 2 * np.pi
    assert abs(np.trapezoid(st["spectrum"], f) - 2.0) < 0.05          # the spectrum holds the variance
    # P(max > mpm) over the record where N = duration / tz: 1 - exp(-1)
    n = 1000.0 / 8.0
    mpm = np.sqrt(2 * np.log(n))
    assert abs(exceedance(1.0, 8.0, 1000.0, mpm) - (1 - np.exp(-1))) < 1e-12


def test_roll_std_equals_the_rao_integral_and_max_follows_rayleigh():
    """The box alone (linear: Hs 0.3 m) in a beam Pierson-Moskowitz sea, 16 seeds x 600 s: the time
    domain's roll std against sqrt(int |RAO|^2 S dw) from js.rao (the frequency-domain
    linearisation), and the records' largest roll against the Rayleigh most probable maximum."""
    text = scene_text(duration=600.0, components=80)
    template = js.load_scene(text)
    out = run_batch(text, "", None, [{"hs": 0.3, "tp": 7.0, "heading": BEAM, "seed": k} for k in range(16)], 16)
    assert all(o["status"] == "ok" for o in out)
    w = np.linspace(0.3, 2.5, 1500)
    case = case_scene(template, {"hs": 0.3, "tp": 7.0, "heading": BEAM, "seed": 0})
    H = np.abs(np.asarray(js.rao(case, w, [BEAM]).vessel)[:, 0, 3])
    theory = np.sqrt(np.trapezoid(H ** 2 * spectrum(case.waves, w), w))
    std = np.array([o["stats"]["roll"]["std"] for o in out])
    assert abs(np.sqrt(np.mean(std ** 2)) / theory - 1) < 0.03
    # the largest of N Rayleigh peaks: mean mpm (1 + 0.5772 / (2 ln N)), scatter pi / sqrt(6) / sqrt(2 ln N) std
    mx = np.array([o["stats"]["roll"]["max"] for o in out])
    mpm = np.array([o["stats"]["roll"]["mpm"] for o in out])
    two_ln_n = (mpm / std) ** 2
    expected = mpm * (1 + 0.5772 / two_ln_n)
    sigma = np.pi / np.sqrt(6) / np.sqrt(two_ln_n) * std
    assert abs(np.mean(mx - expected)) < 3 * np.sqrt(np.mean(sigma ** 2) / mx.size)


# --------------------------------------------------------------------------------------------
# the Dask path


def _campaign(p, s, seeds=2, **kw):
    return js.campaign(js.load_scene(str(p)), str(s), headings=[1.2, BEAM], seeds=seeds, cache_dir=str(CACHE),
                       batch=4, **kw)


@pytest.fixture(scope="module")
def two_workers(tmp_path_factory):
    """A local cluster of two worker processes and the campaign it ran (the two tests below share
    both: the killed worker's campaign is compared with this one, on the same cluster)."""
    folder = tmp_path_factory.mktemp("two")
    with pytest.MonkeyPatch.context() as mp:
        for k, v in _environment().items():
            mp.setenv(k, v)
        p, s = files(folder)
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cl, \
                Client(cl) as client:
            two = _campaign(p, s, client=client, output=str(folder / "two.h5"))
            pids = list(client.run(os.getpid).values())
            yield client, two, pids, folder


def test_one_or_two_workers_give_the_same_statistics_as_jaxslosh_run(env, two_workers):
    _, two, pids, folder = two_workers
    p, s = files(env)
    one = _campaign(p, s, workers=1, output=str(env / "one.h5"))
    assert two.status == ["ok"] * 12 and one.status == ["ok"] * 12 and len(set(pids)) == 2
    for ch in ("roll", "pitch", "heave"):
        for st in ("std", "max", "mpm", "tz"):
            np.testing.assert_allclose(one.statistics[ch][st], two.statistics[ch][st], rtol=1e-12, atol=1e-300)
        np.testing.assert_allclose(one.spectra[ch], two.spectra[ch], rtol=1e-12, atol=1e-300)
    f = load_campaign(str(folder / "two.h5"))
    assert f.attrs["format"] == "jaxslosh.campaign" and f.status == ["ok"] * 12
    np.testing.assert_array_equal(f.statistics["roll"]["std"], two.statistics["roll"]["std"])
    np.testing.assert_allclose(f.cases["weight"].sum(), 1.0, rtol=1e-12)
    # case 7 (cell 1, heading pi/2, seed 1) as its own scene file, run alone by `jaxslosh run`
    case = case_scene(js.load_scene(str(p)), {"hs": 0.6, "tp": 7.0, "heading": BEAM, "seed": 1})
    assert (f.cases["hs"][7], f.cases["heading"][7], f.cases["seed"][7]) == (0.6, BEAM, 1)
    cp = env / "case7.toml"
    cp.write_text(case.text)
    assert main(["run", str(cp), "-o", str(env / "case7.h5"), "--no-progress"]) == 0
    r = js.load_result(str(env / "case7.h5"))
    t = np.asarray(r.time)
    roll = np.asarray(r.vessel.roll_pitch_yaw)[:, 0][t >= 10.0 - 1e-9]
    # single runs refresh their Newton preconditioner when convergence slows, batches every 4 steps:
    # both converge to Newton's tolerance
    np.testing.assert_allclose(roll.std(), two.statistics["roll"]["std"][7], rtol=1e-7)
    np.testing.assert_allclose(np.abs(roll - roll.mean()).max(), two.statistics["roll"]["max"][7], rtol=1e-6)


def test_a_killed_worker_has_its_cases_rerun(env, two_workers):
    client, ref, pids, _ = two_workers
    p, s = files(env)
    out = env / "killed.h5"
    killed = []

    def kill_when_started():         # the first worker, once the campaign has finished a batch
        deadline = time.time() + 300
        n_ok = 0
        while time.time() < deadline and n_ok == 0:
            try:
                with h5py.File(out, "r") as f:
                    n_ok = sum(x == b"ok" for x in f["cases/status"][()])
            except (OSError, KeyError):
                pass
            time.sleep(0.02)
        os.kill(pids[0], signal.SIGKILL)
        killed.append(n_ok)

    th = threading.Thread(target=kill_when_started)
    th.start()
    r = js.campaign(js.load_scene(str(p)), str(s), headings=[1.2, BEAM], seeds=2, cache_dir=str(CACHE), batch=1,
                    client=client, output=str(out))
    th.join()
    assert killed and killed[0] < 12 and r.status == ["ok"] * 12       # killed mid-campaign, yet complete
    for ch in ("roll", "heave"):
        np.testing.assert_allclose(r.statistics[ch]["std"], ref.statistics[ch]["std"], rtol=1e-12)


def _descendants(pid):
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        for task in Path(f"/proc/{p}/task").glob("*"):
            try:
                kids = [int(x) for x in (task / "children").read_text().split()]
            except OSError:
                kids = []
            out += kids
            todo += kids
    return out


def test_an_interrupted_campaign_resumes_without_recomputing_finished_cases(env):
    p, s = files(env)
    # 36 cases, one at a time: with the workers' compilation cached (earlier tests), a case takes a
    # fraction of a second, and twelve were all done before the interrupt reached the campaign
    N = 36
    out = env / "c.h5"
    args = [sys.executable, "-m", "jaxslosh", "campaign", str(p), "--scatter", str(s), "--headings", f"1.2,{BEAM}",
            "--seeds", "6", "--workers", "1", "--batch", "1", "-o", str(out)]
    # its own process group, as a terminal's: Ctrl-C reaches the campaign and its cluster's workers
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=env,
                            start_new_session=True)
    children = []
    try:
        deadline = time.time() + 300
        done = 0
        while time.time() < deadline and proc.poll() is None:
            children = set(children) | set(_descendants(proc.pid))
            try:
                with h5py.File(out, "r") as f:
                    done = sum(x == b"ok" for x in f["cases/status"][()])
            except (OSError, KeyError):
                pass
            if done >= 1:           # stop early: on a loaded machine the poll may see few frames
                break
            time.sleep(0.05)
        assert proc.poll() is None, proc.communicate()[1][-2000:]
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
        for c in children:          # the cluster's processes, were any left behind
            try:
                os.kill(c, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
    before = load_campaign(str(out))
    n_ok = sum(x == "ok" for x in before.status)
    assert 1 <= n_ok < N and all(x in ("ok", "pending") for x in before.status)
    # one line that says what is kept and how to go on; nothing of Dask's shutdown
    assert proc.returncode == 130
    assert err.strip() == (f"interrupted (SIGINT): {n_ok} of {N} cases done ({n_ok} in this run), kept in {out}; "
                           f"the same command with --resume runs the other {N - n_ok}"), err[-3000:]
    res = subprocess.run(args + ["--resume"], capture_output=True, text=True, cwd=env, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stderr == "", res.stderr[-2000:]           # the cluster closed without Dask's warnings
    assert f"{N - n_ok} cases run now, {n_ok} already done, 0 failed" in res.stdout
    after = load_campaign(str(out))
    assert after.status == ["ok"] * N
    ok = np.array([x == "ok" for x in before.status])
    np.testing.assert_array_equal(after.statistics["roll"]["std"][ok], before.statistics["roll"]["std"][ok])
    ref = _campaign(p, s, seeds=6, workers=1)
    np.testing.assert_allclose(after.statistics["roll"]["std"], ref.statistics["roll"]["std"], rtol=1e-12)


# --------------------------------------------------------------------------------------------
# the command's input


@pytest.mark.parametrize("csv, word", [("hs,tp\n1,7\n", "probability"), ("hs,probability\n1,1\n", "'tp'"),
                                       ("hs,tp,probability,colour\n1,7,1,2\n", "'colour'"),
                                       ("hs,tp,probability\n1,x,1\n", "'tp'"),
                                       ("hs,tp,probability\n-1,7,1\n", "'hs'")])
def test_bad_scatter_names_the_column(tmp_path, capsys, csv, word):
    with pytest.raises(ScatterError, match=word):
        read_scatter(csv)
    p, s = files(tmp_path)
    s.write_text(csv)
    assert main(["campaign", str(p), "--scatter", str(s), "-o", str(tmp_path / "c.h5")]) == 2
    err = capsys.readouterr().err
    assert word in err and len(err.strip().splitlines()) == 1


def test_bad_campaign_input_exits_2(tmp_path, capsys):
    p, s = files(tmp_path)
    out = tmp_path / "c.h5"
    for extra, word in ((["--limits", "yaw=0.1"], "yaw"), (["--limits", "roll=-1"], "roll"),
                        (["--headings", "a,b"], "--headings"), (["--seeds", "0"], "--seeds"),
                        (["--duration", "5"], "waves.ramp")):
        assert main(["campaign", str(p), "--scatter", str(s), "-o", str(out)] + extra) == 2, extra
        assert word in capsys.readouterr().err
    q = tmp_path / "regular.toml"
    q.write_text(scene_text().split("[waves]")[0] + '[waves]\ntype = "regular"\namplitude = 0.5\nperiod = 7.0\n')
    assert main(["campaign", str(q), "--scatter", str(s), "-o", str(out)]) == 2
    assert "waves.type" in capsys.readouterr().err
    # a case the scene loader refuses names the key and the case
    s2 = tmp_path / "s2.csv"
    s2.write_text("hs,tp,probability,gamma\n1,7,1,2\n")
    assert main(["campaign", str(p), "--scatter", str(s2), "-o", str(out)]) == 2
    assert "waves.gamma" in capsys.readouterr().err
    # a second writer
    lock = OutputLock(str(out))
    try:
        assert main(["campaign", str(p), "--scatter", str(s), "-o", str(out)]) == 2
        assert "another run" in capsys.readouterr().err
    finally:
        lock.release()
    # --resume of another scene's campaign
    with h5py.File(out, "w") as f:
        f.attrs["format"] = "jaxslosh.campaign"
        f.attrs["scene"] = "title = 'other'"
        f.attrs["channels"] = ["roll"]
        for k in ("hs", "tp", "heading", "seed", "weight"):
            f[f"cases/{k}"] = np.zeros(1)
        f["cases/status"] = np.array([b"ok"])
        for st in ("std", "significant", "max", "mpm", "tz"):
            f[f"statistics/roll/{st}"] = np.zeros(1)
        f["spectra/frequency"] = np.zeros(3)
        f["spectra/roll"] = np.zeros((1, 3))
    assert main(["campaign", str(p), "--scatter", str(s), "-o", str(out), "--resume"]) == 2
    assert "another scene" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# the scene's [campaign] table

TABLE = f"""
[campaign]
headings = [1.2, {BEAM!r}]
seeds = 1
[campaign.limits]
roll = {{roll}}
heave = 0.35
"""


def test_scene_limits_give_the_operability_of_the_same_limits_on_the_command_line(env, capsys):
    """A scene whose [campaign] table holds limits, headings and seeds, run with no options, against
    the plain scene with the same limits, headings and seeds on the command line: the same cases,
    statistics, exceedance and operability, printed and in the file."""
    p, s = files(env)
    roll = 0.1                         # the largest roll of the cases: 0.05 to 0.13 rad, heave 0.15 to 0.44 m
    q = env / "box_limits.toml"
    q.write_text(scene_text() + TABLE.format(roll=roll))
    common = ["--workers", "1", "--batch", "3", "--no-progress"]
    assert main(["campaign", str(q), "--scatter", str(s), "-o", str(env / "scene.h5")] + common) == 0
    from_scene = capsys.readouterr().out
    assert main(["campaign", str(p), "--scatter", str(s), "-o", str(env / "cli.h5"), "--headings", f"1.2,{BEAM}",
                 "--seeds", "1", "--limits", f"roll={roll},heave=0.35"] + common) == 0
    from_cli = capsys.readouterr().out
    def table(out):
        return [ln for ln in out.splitlines() if not ln.startswith("done:")]
    assert table(from_scene) == table(from_cli) and "operability" in from_scene
    a, b = load_campaign(str(env / "scene.h5")), load_campaign(str(env / "cli.h5"))
    assert a.status == ["ok"] * 6 and b.status == ["ok"] * 6
    for k in ("hs", "tp", "heading", "seed", "weight"):
        np.testing.assert_array_equal(a.cases[k], b.cases[k])
    np.testing.assert_array_equal(a.statistics["roll"]["max"], b.statistics["roll"]["max"])
    assert a.attrs["limits"] == b.attrs["limits"] and a.attrs["exceedance"] == b.attrs["exceedance"]
    assert a.attrs["operability"] == b.attrs["operability"]
    np.testing.assert_allclose(a.attrs["operability"], 55.0, rtol=1e-12)    # cases 0-2: within both limits


def test_the_command_line_wins_over_the_scene():
    from jaxslosh.campaign.run import settings
    scene = js.load_scene(scene_text() + TABLE.format(roll=0.1))
    base = settings(scene)
    assert base == ([1.2, BEAM], 1, None, {"roll": 0.1, "heave": 0.35})
    # given limits replace the table's as a whole; {} is none
    assert settings(scene, [0.0], 3, 50.0, {"pitch": 0.2}) == ([0.0], 3, 50.0, {"pitch": 0.2})
    assert settings(scene, limits={}).limits == {}
    plain = settings(js.load_scene(scene_text()))
    assert plain == (None, 1, None, {})
    timed = js.load_scene(scene_text() + "[campaign]\nduration = 40.0\n")
    assert settings(timed).duration == 40.0 and settings(timed, duration=30.0).duration == 30.0


@pytest.mark.parametrize("table, key", [
    ("[campaign.limits]\nroll = -0.1\n", "campaign.limits.roll"),
    ("[campaign.limits]\nroll = 0.0\n", "campaign.limits.roll"),
    ('[campaign.limits]\nroll = "a"\n', "campaign.limits.roll"),
    ("[campaign.limits]\nyaw = 0.1\n", "campaign.limits.yaw"),
    ("[campaign.limits]\nprobe.C = 0.1\n", "campaign.limits.probe.C"),
    ("[campaign]\nlimits = 0.1\n", "campaign.limits"),
    ("[campaign]\nseeds = 0\n", "campaign.seeds"),
    ("[campaign]\nseeds = 1.5\n", "campaign.seeds"),
    ('[campaign]\nheadings = "beam"\n', "campaign.headings"),
    ("[campaign]\nheadings = []\n", "campaign.headings"),
    ("[campaign]\nduration = -600.0\n", "campaign.duration"),
    ("[campaign]\nduration = 5.0\n", "campaign.duration"),        # before waves.ramp
    ("[campaign]\nlimit = {roll = 0.1}\n", "campaign.limit"),
])
def test_a_bad_campaign_table_is_refused_naming_the_key(tmp_path, capsys, table, key):
    p, s = files(tmp_path)
    p.write_text(scene_text() + table)
    with pytest.raises(js.SceneError) as e:
        js.load_scene(str(p))
    assert e.value.key == key
    for argv in (["check", str(p)], ["campaign", str(p), "--scatter", str(s), "-o", str(tmp_path / "c.h5")]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"{key}: ") or f" {key}: " in err, err
        assert len(err.splitlines()) == 1
    assert not (tmp_path / "c.h5").exists()


def test_campaign_table_forms_and_registry():
    """probe.B as a dotted or a quoted key; the limits and duration in the key registry, not
    traceable; a campaign table changes no run (identify's scene comparison passes over it)."""
    from jaxslosh.scene.compare import differences
    from jaxslosh.scene.keys import scene_values, traceable
    probes = '[[probes]]\nname = "B"\ntank = "t"\npoint = [1.0, 1.0, 0.5]\n'
    tank = '[[tanks]]\nname = "t"\norigin = [-1.0, -1.0, 0.0]\nsize = [2.0, 2.0, 1.0]\nfill_depth = 0.5\nmesh = [1, 1, 1]\n'
    plain = scene_text() + tank + probes
    for form in ("probe.B = 0.5", '"probe.B" = 0.5', "probe = {B = 0.5}"):
        scene = js.load_scene(plain + f"[campaign]\nduration = 40.0\n[campaign.limits]\n{form}\n")
        assert scene.campaign.limits == (("probe.B", 0.5),)
        values = scene_values(scene)
        assert values["campaign.limits.probe.B"] == 0.5 and values["campaign.duration"] == 40.0
    with pytest.raises(js.SceneError, match="campaign.limits.probe.B: is given twice"):
        js.load_scene(plain + '[campaign.limits]\n"probe.B" = 0.5\nprobe.B = 0.6\n')
    with pytest.raises(js.SceneError, match="cannot be traced"):
        traceable(scene, ["campaign.limits.probe.B"])
    assert differences(scene, js.load_scene(plain)) == []
    # a regular sea: the table loads, with a warning that a campaign needs an irregular one
    regular = scene_text().split("[waves]")[0] + '[waves]\ntype = "regular"\namplitude = 0.5\nperiod = 7.0\n'
    scene = js.load_scene(regular + "[campaign.limits]\nroll = 0.1\n")
    assert any(w.startswith("campaign:") for w in scene.warnings)


# --------------------------------------------------------------------------------------------
# the figure


def test_plot_of_a_campaign_file(tmp_path, capsys):
    from jaxslosh.io.campaign import create_campaign, write_cases, write_summary
    out = tmp_path / "c.h5"
    hs, tp = np.repeat([1.0, 2.0], 4), np.tile(np.repeat([6.0, 8.0], 2), 2)
    heading = np.tile([0.0, BEAM], 4)
    cases = {"hs": hs, "tp": tp, "heading": heading, "seed": np.zeros(8, int), "weight": np.full(8, 1 / 8)}
    freq = np.linspace(0.0, 3.0, 20)
    create_campaign(str(out), scene_text(), cases, ["roll", "heave"], freq, {"record_duration": 50.0})
    rng = np.random.default_rng(0)
    outcomes = [{"status": "ok", "stats": {ch: dict(std=s, significant=4 * s, max=3 * s, mpm=2.9 * s, tz=6.0,
                                                    spectrum=rng.uniform(size=20))
                                           for ch, s in (("roll", 0.02 * hs[i]), ("heave", 0.3 * hs[i]))}}
                for i in range(7)]
    write_cases(str(out), range(7), outcomes)
    write_summary(str(out), {"roll": 0.1}, {"roll": 0.2}, 75.0)
    assert load_campaign(str(out)).status[-1] == "pending"
    png = tmp_path / "c.png"
    assert main(["plot", str(out), "-o", str(png), "--case", "3"]) == 0 and png.stat().st_size > 10000
    assert main(["plot", str(out), "-o", str(png), "--limits", "heave=0.5"]) == 0
    assert main(["plot", str(out), "-o", str(png), "--case", "9"]) == 2
    assert "--case" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# issue 31: what a new user met


def test_headings_in_degrees_are_refused(tmp_path, capsys):
    """Headings beyond 2 pi are degrees typed where radians are asked for: exit 2 saying so, on
    campaign's and rao's --headings, in [campaign] headings, and from js.campaign."""
    from jaxslosh.campaign.run import CampaignError
    p, s = files(tmp_path)
    out = str(tmp_path / "c.h5")
    for argv in (["campaign", str(p), "--scatter", str(s), "-o", out, "--headings", "45,90"],
                 ["rao", str(p), "--headings", "0,90", "-o", str(tmp_path / "r.h5")]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "--headings" in err and "headings are in radians" in err and len(err.strip().splitlines()) == 1
    p.write_text(scene_text() + "[campaign]\nheadings = [90]\n")
    assert main(["check", str(p)]) == 2
    err = capsys.readouterr().err
    assert "campaign.headings" in err and "headings are in radians" in err
    with pytest.raises(CampaignError, match="headings are in radians"):
        js.campaign(js.load_scene(scene_text()), str(s), headings=[0.0, 180.0])
    assert not os.path.exists(out)
    # 2 pi itself, and negative headings within a turn, stay radians
    assert js.load_scene(scene_text() + f"[campaign]\nheadings = [-3.0, {2 * np.pi!r}]\n").campaign.headings[1] > 6


FAILING_SCATTER = "hs,tp,probability\n0.3,7.0,0.5\n1000.0,7.0,0.5\n"    # Hs 1000 m: Newton gives up near t = 5 s
LIMITS = "[campaign]\nheadings = [1.5707963267948966]\n[campaign.limits]\nroll = 1.0\nheave = 5.0\n"


def _main(argv):
    """main(argv) -> (exit status, stdout, stderr)."""
    import contextlib
    import io
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except Exception as e:          # noqa: BLE001 - a traceback is an outcome the tests look at
            code, _ = f"{type(e).__name__}: {e}", print(f"Traceback: {type(e).__name__}: {e}", file=sys.stderr)
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def failing(tmp_path_factory):
    """Three small campaigns of the box in beam seas, one process each, limits roll 1 rad and heave
    5 m from the scene: `mixed`, Hs 0.3 m and Hs 1000 m at 50 % each (the second fails: Hs 100 m runs
    to the end); `resumed`, that file resumed with --limits "" (the failed case run again); `lost`,
    Hs 1000 m alone."""
    d = tmp_path_factory.mktemp("failing")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), str(ROOT / "tests"), os.environ.get("PYTHONPATH", "")]))
        mp.setenv("JAXSLOSH_CACHE_DIR", str(CACHE))
        mp.setenv("JAXSLOSH_PROGRESS", "0")
        p = d / "box.toml"
        p.write_text(scene_text(40.0).replace('title = "box alone in irregular seas"',
                                              'title = "box alone (Hs 0.3 m, Tp 7 s)"') + LIMITS)
        (d / "mixed.csv").write_text(FAILING_SCATTER)
        (d / "lost.csv").write_text("hs,tp,probability\n1000.0,7.0,1.0\n")
        common = ["--workers", "1", "--batch", "2", "--no-progress"]
        runs = {"mixed": _main(["campaign", str(p), "--scatter", str(d / "mixed.csv"), "-o", str(d / "mixed.h5")]
                               + common)}
        import shutil
        shutil.copy(d / "mixed.h5", d / "resumed.h5")
        runs["resumed"] = _main(["campaign", str(p), "--scatter", str(d / "mixed.csv"), "-o", str(d / "resumed.h5"),
                                 "--resume", "--limits", ""] + common)
        runs["lost"] = _main(["campaign", str(p), "--scatter", str(d / "lost.csv"), "-o", str(d / "lost.h5")] + common)
    return d, runs


def test_a_failed_case_is_not_operable_in_the_summary_the_file_and_the_figure(failing):
    d, runs = failing
    code, out, err = runs["mixed"]
    assert code == 3, err[-2000:]
    c = load_campaign(str(d / "mixed.h5"))
    assert c.status[0] == "ok" and "Newton" in c.status[1]
    assert "operability: 50.00 % of the scatter's weight within every limit; 50.00 % of it in failed cases" in out
    np.testing.assert_allclose(c.attrs["operability"], 50.0, rtol=1e-12)
    np.testing.assert_allclose(c.attrs["failed_weight"], 50.0, rtol=1e-12)
    import json
    exc = json.loads(c.attrs["exceedance"])
    assert exc["roll"] >= 0.5 and exc["heave"] >= 0.5                 # the failed half counts as exceeding
    from jaxslosh.plot.campaign import heading_operability
    heads, per, share = heading_operability(c, {"roll": 1.0, "heave": 5.0})
    np.testing.assert_allclose(per, [50.0], rtol=1e-12)
    assert share == 50.0


def test_a_failed_cases_reason_is_printed(failing):
    _, runs = failing
    code, out, err = runs["mixed"]
    line = [ln for ln in err.splitlines() if ln.startswith("failed:")]
    assert len(line) == 1 and line[0].startswith("failed: case 1 (hs 1000 m, tp 7 s, heading 1.571 rad, seed 0): step ")
    assert "Newton did not converge" in line[0]
    assert out.splitlines()[-1].startswith("done: 2 cases run now, 0 already done, 1 failed")


def test_no_limits_print_no_table(failing):
    _, runs = failing
    code, out, err = runs["resumed"]
    assert code == 3
    assert out.splitlines() == [out.splitlines()[-1]] and out.startswith("done: 1 cases run now, 1 already done, 1 failed")
    assert "failed: case 1" in err


def test_a_campaign_whose_every_case_fails_exits_3_with_its_summary_and_reasons(failing):
    d, runs = failing
    code, out, err = runs["lost"]
    assert code == 3 and "Traceback" not in err and "KeyError" not in err
    assert "operability: 0.00 % of the scatter's weight within every limit; 100.00 % of it in failed cases" in out
    assert out.splitlines()[-1].startswith("done: 1 cases run now, 0 already done, 1 failed")
    assert "failed: case 0 (hs 1000 m" in err and "Newton" in err


def test_the_figure_of_a_campaign_with_failures(failing, tmp_path):
    """Failed cells said, operability as the summary's, spectra on one axis per unit over the
    frequencies that hold energy with their resolution said, a title of the campaign's own seas
    clear of the subplots, no warning from matplotlib (an all-failed campaign included)."""
    import warnings
    from jaxslosh.plot.campaign import plot_campaign
    d, _ = failing
    c = load_campaign(str(d / "mixed.h5"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_campaign(c, str(tmp_path / "m.png"), limits={"roll": 1.0, "heave": 5.0})
        plot_campaign(load_campaign(str(d / "lost.h5")), str(tmp_path / "l.png"), limits={"roll": 1.0})
        assert _main(["plot", str(d / "lost.h5"), "-o", str(tmp_path / "l2.png")])[0] == 0
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert "failed" in texts
    polar = [ax for ax in fig.axes if ax.name == "polar"][0]
    np.testing.assert_allclose(polar.lines[0].get_ydata(), [50.0])
    assert "count as not operable" in polar.get_title()
    by_unit = {ax.get_ylabel(): ax for ax in fig.axes if ax.get_ylabel().startswith("S (")}
    # beam seas on a box: pitch at round-off, below the roll peak by far more than the axis shows
    assert {ln.get_label() for ln in by_unit["S (rad^2 s/rad)"].lines} == {"roll"}
    assert np.nanmax(c.spectra["pitch"][0]) < 1e-5 * np.nanmax(c.spectra["roll"][0])
    assert {ln.get_label() for ln in by_unit["S (m^2 s/rad)"].lines} == {"heave"}
    w = np.asarray(c.frequency)
    for ax in by_unit.values():
        lo, hi = ax.get_xlim()
        assert hi < 0.5 * w[-1]                                  # not to Nyquist's 15.7 rad/s
        top = max(ln.get_ydata().max() for ln in ax.lines)
        assert ax.get_ylim()[0] >= 1e-6 * top                   # not down to round-off
    assert any(f"resolution {w[1] - w[0]:.3g} rad/s" in ax.get_title() for ax in fig.axes)
    sup = fig._suptitle.get_text()
    assert "Hs 0.3 to 1000 m, Tp 7 s" in sup and "(Hs 0.3 m, Tp 7 s)" not in sup
    r = fig.canvas.get_renderer()
    box = fig._suptitle.get_window_extent(r)
    assert all(not box.overlaps(ax.get_tightbbox(r)) for ax in fig.axes)


def test_cell_labels_are_dark_on_light_cells():
    from matplotlib import colormaps
    from jaxslosh.plot.campaign import _label_colour
    cmap = colormaps["viridis"]
    assert _label_colour(cmap, 1.0) == "k" and _label_colour(cmap, 0.9) == "k"     # yellow, light green
    assert _label_colour(cmap, 0.0) == "w" and _label_colour(cmap, 0.3) == "w"     # purple, blue


def test_a_channel_that_does_not_respond_has_no_period():
    """A record at round-off level (the roll of a symmetric box in head seas) has no zero-crossing
    period or most probable maximum; a small real response keeps them."""
    t = np.arange(0.0, 200.0, 0.1)
    st = statistics(t, 1e-17 * np.sin(2 * np.pi * t / 8.0) + 0.02)
    assert np.isnan(st["tz"]) and np.isnan(st["mpm"]) and st["std"] < 1e-16
    st = statistics(t, 1e-6 * np.sin(2 * np.pi * t / 8.0))
    assert abs(st["tz"] - 8.0) < 0.01


def test_a_case_scene_is_the_scene_its_text_parses_to():
    """case_scene reads a case from the template's parsed mapping: the same Scene as parsing the
    case's own text (as `jaxslosh run` of it does), duration and extra sea columns included."""
    import tomllib
    from jaxslosh.scene.load import parse_scene
    template = parse_scene(tomllib.loads(scene_text()), text=scene_text(), path="box.toml")
    for values, duration in (({"hs": 0.6, "tp": 7.0, "heading": BEAM, "seed": 1}, None),
                             ({"hs": 0.9, "tp": 8.5, "heading": 0.3, "seed": 4, "depth": 30.0}, 33.0),
                             ({"hs": 0.3, "tp": 6.0, "heading": 3.0, "seed": 0, "spreading": 4.0, "directions": 3}, 20.5)):
        case = case_scene(template, values, duration)
        again = parse_scene(tomllib.loads(case.text), text=case.text, path="box.toml")
        assert case == again
        assert case.waves.hs == values["hs"] and case.waves.seed == values["seed"]
        assert case.simulation.duration == (duration if duration is not None else 60.0)
    assert template == parse_scene(tomllib.loads(scene_text()), text=scene_text(), path="box.toml")
