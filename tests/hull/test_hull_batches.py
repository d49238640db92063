"""Batches with the nonlinear hydrostatics (`model = "nonlinear"`): js.simulate_batch, `jaxslosh sweep`
and a campaign on a local Dask cluster (started here) against the same cases run one by one, and
the RAO of the nonlinear model against the linear model of the same hull (its linearisation).
Small cases: a box 20 x 10 x 3 m with its deck, coarse steps, a few seconds."""
import os
from pathlib import Path

import h5py
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.campaign.cases import case_scene, sea_arrays
from jaxslosh.campaign.stats import case_statistics, channels
from jaxslosh.campaign.worker import structure_scene
from jaxslosh.cli import main
from jaxslosh.hull.box import box_hull
from jaxslosh.hull.surface import write_hull_mesh
from jaxslosh.io.rao import load_rao
from jaxslosh.run.batch import simulate_seas

ROOT = Path(__file__).resolve().parents[2]
BOX_HULL = "[vessel.hull]\nlength = 20.0\nbeam = 10.0\ndraft = 3.0\nkg = 3.5\ndepth = 6.0\n"

SCENE = """
title = "box, nonlinear hydrostatics"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
dt = {dt}
scheme = "newmark"
save_every = 2
[vessel]
mass = 615000.0
inertia = [7.5e6, 2.5e7, 2.8e7]
{hull}
[vessel.hydrostatics]
model = "{model}"
[vessel.initial]
roll_pitch_yaw = [0.2, 0.0, 0.0]
"""

WAVES = """
[vessel.hydrodynamics]
viscous_damping = [0.0, 0.0, 1.0e5, 1.5e6, 5.0e6, 0.0]
[waves]
type = "pierson-moskowitz"
hs = 0.5
tp = 7.0
heading = 1.2
seed = 0
components = 6
frequency_range = [0.4, 1.2]
ramp = 4.0
"""


def scene_text(model="nonlinear", duration=2.0, dt=0.05, hull=BOX_HULL, waves=False):
    return SCENE.format(model=model, duration=duration, dt=dt, hull=hull) + (WAVES if waves else "")


def test_batch_equals_single_runs_and_is_nonlinear():
    """Rolls released from 0.1 and 0.5 rad in one vmapped batch: each equals its single run, and
    the batch's restoring is the hull's, not the linear model's springs."""
    scene = js.load_scene(scene_text())
    rpy = np.array([[0.1, 0.0, 0.0], [0.5, 0.0, 0.0]])
    batch, statuses = js.simulate_batch(scene, {"vessel.initial.roll_pitch_yaw": rpy})
    assert statuses == ["ok", "ok"]
    for i in range(2):
        single = js.simulate(scene, params={"vessel.initial.roll_pitch_yaw": rpy[i]})
        # the batch refreshes its Newton preconditioner every 4 steps, a single run when it slows:
        # both converge to the Newton tolerance, not bitwise alike
        np.testing.assert_allclose(np.asarray(batch.vessel.quaternion[i]), np.asarray(single.vessel.quaternion),
                                   atol=1e-10)
    lin, _ = js.simulate_batch(js.load_scene(scene_text("linear")), {"vessel.initial.roll_pitch_yaw": rpy})
    dev = (np.abs(np.asarray(batch.vessel.roll_pitch_yaw)[:, :, 0] - np.asarray(lin.vessel.roll_pitch_yaw)[:, :, 0])
           .max(axis=1) / rpy[:, 0])
    # from 0.1 rad the two models stay within a few per cent of the release angle; from 0.5 rad
    # (the deck edge immerses at 0.54 rad) the hull's restoring departs from the spring's, the
    # relative difference growing about as the angle squared
    assert dev[0] < 0.03 and dev[1] > 0.1 and dev[1] > 5 * dev[0], dev


def test_sweep_command_equals_single_runs(tmp_path):
    p = tmp_path / "box.toml"
    p.write_text(scene_text(duration=1.0))
    out = tmp_path / "sw.h5"
    assert main(["sweep", str(p), "--param", "environment.water_density=1000,1025", "-o", str(out)]) == 0
    with h5py.File(out) as f:
        assert f.attrs["runs"] == 2
        rpy = f["vessel/roll_pitch_yaw"][()]
    for i, rho in enumerate((1000.0, 1025.0)):
        single = js.simulate(js.load_scene(str(p)), params={"environment.water_density": rho})
        np.testing.assert_allclose(rpy[i], np.asarray(single.vessel.roll_pitch_yaw), atol=1e-10)
    # lighter water floats the same ship deeper: the runs differ
    assert np.abs(rpy[0] - rpy[1]).max() > 1e-4


def test_seas_of_a_batch_equal_the_cases_run_alone():
    """The campaign's batch of seas (run/batch.simulate_seas): each run's incident waves on the
    wetted hull are its own case's, as `jaxslosh run` of the case scene takes them."""
    text = scene_text(duration=12.0, dt=0.1, waves=True)
    template = js.load_scene(text)
    cases = [case_scene(template, {"hs": hs, "tp": 7.0, "heading": 1.2, "seed": k}) for hs, k in ((0.5, 0), (1.0, 1))]
    seas = [sea_arrays(c) for c in cases]
    assert seas[0][4] is not None and np.abs(seas[0][1]).max() == 0.0    # Froude-Krylov all on the hull
    stack = lambda k: np.stack([s[k] for s in seas])                       # noqa: E731
    incident = tuple(np.stack([s[4][j] for s in seas]) for j in range(5))
    res, statuses = simulate_seas(structure_scene(template, cases[0]), stack(0), stack(1), stack(2), stack(3),
                                  incident)
    assert statuses == ["ok", "ok"]
    for i, c in enumerate(cases):
        single = js.simulate(c)
        np.testing.assert_allclose(np.asarray(res.vessel.roll_pitch_yaw[i]), np.asarray(single.vessel.roll_pitch_yaw),
                                   atol=1e-9)
    # the larger sea heaves the ship more
    heave = np.asarray(res.vessel.position)[:, :, 2]
    assert heave[1].std() > 1.5 * heave[0].std()


# slow: the default suite has a batch of seas of the nonlinear model equal to the cases run alone
# (test_seas_of_a_batch_equal_the_cases_run_alone) and campaigns on local clusters (tests/campaign)
@pytest.mark.slow
def test_campaign_on_a_local_cluster_equals_the_cases_run_alone(tmp_path, monkeypatch):
    from dask.distributed import Client, LocalCluster
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), str(ROOT / "tests"),
                                                      os.environ.get("PYTHONPATH", "")]))
    monkeypatch.setenv("JAXSLOSH_PROGRESS", "0")
    p = tmp_path / "box.toml"
    p.write_text(scene_text(duration=12.0, dt=0.1, waves=True))
    s = tmp_path / "scatter.csv"
    s.write_text("hs,tp,occurrences\n0.8,7.0,1\n")
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cl, \
            Client(cl) as client:
        c = js.campaign(js.load_scene(str(p)), str(s), headings=[1.2], seeds=2, batch=2, client=client,
                        output=str(tmp_path / "c.h5"))
    assert c.status == ["ok", "ok"]
    template = js.load_scene(str(p))
    for k in range(2):
        case = case_scene(template, {"hs": 0.8, "tp": 7.0, "heading": 1.2, "seed": k})
        r = js.simulate(case)
        st = case_statistics(np.asarray(r.time), channels(r, None), case.waves.ramp)
        for ch in ("roll", "heave"):
            np.testing.assert_allclose(c.statistics[ch]["std"][k], st[ch]["std"], rtol=1e-7)


@pytest.mark.parametrize("hull", ["box", "mesh"])
def test_rao_of_the_nonlinear_model_is_the_linear_models(tmp_path, hull):
    """js.rao linearises the nonlinear model about rest: the RAO of the linear model of the same
    box (closed-form hydrostatics and Froude-Krylov forces). A closed mesh of the box gives it to
    the midpoint rule's error on its panels (its Froude-Krylov forces from the wetted surface)."""
    w = np.linspace(0.3, 1.5, 7)
    ref = js.rao(js.load_scene(scene_text("linear", waves=True)), w, [0.0, 1.2])
    if hull == "mesh":
        mesh = tmp_path / "box.obj"
        write_hull_mesh(str(mesh), box_hull(20.0, 10.0, 3.5, 6.0, 3) + [0.0, 0.0, 0.5])
        text = scene_text(waves=True, hull=f'[vessel.hull]\ntype = "mesh"\nfile = "{mesh}"\ncog = [0.0, 0.0, 0.5]\n')
    else:
        text = scene_text(waves=True)
    got = js.rao(js.load_scene(text), w, [0.0, 1.2])
    scale = np.abs(np.asarray(ref.vessel)).max(axis=(0, 1))          # per dof
    err = np.abs(np.asarray(got.vessel) - np.asarray(ref.vessel)).max(axis=(0, 1)) / np.maximum(scale, 1e-12)
    assert err.max() < (1e-9 if hull == "box" else 0.01), err
    # the command writes the same RAOs
    p = tmp_path / "nl.toml"
    p.write_text(text)
    out = tmp_path / "nl_rao.h5"
    assert main(["rao", str(p), "--frequencies", "0.3:1.5:7", "--headings", "0,1.2", "-o", str(out)]) == 0
    np.testing.assert_allclose(load_rao(str(out)).vessel, np.asarray(got.vessel), rtol=1e-12, atol=1e-14)
