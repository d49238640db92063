"""A campaign with a face-normal ("rt") tank: the batched loop on a local Dask cluster gives each
case the statistics of the same case run alone (`jaxslosh run` of its scene file), as the box
alone does in test_campaign.py. A small tank on its modal basis, coarse dt, short records."""
import os
from pathlib import Path

import numpy as np
import pytest
from dask.distributed import Client, LocalCluster

import jaxslosh as js
from jaxslosh.campaign.cases import case_scene
from jaxslosh.cli import main
from test_campaign import scene_text

ROOT = Path(__file__).resolve().parents[2]
BEAM = 1.5707963267948966
CACHE = Path(os.environ.get("TMPDIR", "/tmp")) / f"jaxslosh-test-campaign-cache-{os.getuid()}"

# test_campaign.py's box in irregular seas (30 s, 20 components), with a small rt tank on 4 modes
SCENE = scene_text(duration=30.0, components=20).replace("box alone in irregular seas",
                                                         "box with an rt tank in irregular seas") + """
[[tanks]]
name = "tank"
origin = [0.0, 0.0, 1.0]
size = [2.0, 6.0, 2.0]
fill_depth = 1.0
mesh = [2, 8, 4]
[tanks.fluid]
element = "rt"
[tanks.reduction]
modes = 4
[tanks.damping]
ratio = 0.05
"""

SCATTER = "hs,tp,occurrences\n0.6,7.0,100\n"


# slow, for the default suite's budget: it keeps an rt tank's batches equal to its single runs
# (tests/analysis/test_rt_runs.py) and campaigns on local clusters (tests/campaign/test_campaign.py)
@pytest.mark.slow
def test_a_campaign_with_an_rt_tank_gives_the_statistics_of_single_runs(tmp_path, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    monkeypatch.setenv("JAXSLOSH_PROGRESS", "0")
    p = tmp_path / "rt.toml"
    p.write_text(SCENE)
    s = tmp_path / "scatter.csv"
    s.write_text(SCATTER)
    template = js.load_scene(str(p))
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cl, \
            Client(cl) as client:
        r = js.campaign(template, str(s), headings=[BEAM], seeds=2, cache_dir=str(CACHE), batch=2, client=client,
                        output=str(tmp_path / "c.h5"))
    assert r.status == ["ok"] * 2
    stds = r.statistics["roll"]["std"]
    assert abs(stds[0] / stds[1] - 1) > 1e-3                      # two seeds, two seas, one batch
    for k in (1,):
        case = case_scene(template, {"hs": 0.6, "tp": 7.0, "heading": BEAM, "seed": k})
        cp = tmp_path / f"case{k}.toml"
        cp.write_text(case.text)
        assert main(["run", str(cp), "-o", str(tmp_path / f"case{k}.h5"), "--no-progress"]) == 0
        res = js.load_result(str(tmp_path / f"case{k}.h5"))
        t = np.asarray(res.time)
        roll = np.asarray(res.vessel.roll_pitch_yaw)[:, 0][t >= 10.0 - 1e-9]
        assert roll.std() > 1e-4                                   # the sea rolls the vessel
        # batches refresh their Newton preconditioner every few steps, single runs when convergence
        # slows: both converge to Newton's tolerance
        np.testing.assert_allclose(roll.std(), r.statistics["roll"]["std"][k], rtol=1e-7)
        np.testing.assert_allclose(np.abs(roll - roll.mean()).max(), r.statistics["roll"]["max"][k], rtol=1e-6)
