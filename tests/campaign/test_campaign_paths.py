"""A campaign's statistics whatever the path its batches take: numbers recorded from the code
before the campaign's speed work (issue 47: the wave force formed once per step, the batch's
program read back from the exported programs' folder, one worker in the campaign's own process)
are met within 1e-8; the one-worker campaign starts no process and says where its time went."""
import multiprocessing
import os

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cache import programs
from jaxslosh.campaign.worker import run_batch
from jaxslosh.run import batch

from test_campaign import BEAM, CACHE, env, files, scene_text  # noqa: F401 (env: the fixture)

#: the box alone (test_campaign's scene, 60 s, 30 components), two cases: run_batch's statistics
#: before the change (main at 28906eb), {channel: (std, max, tz)}
BOX_CASES = [{"hs": 0.6, "tp": 7.0, "heading": BEAM, "seed": 1}, {"hs": 0.9, "tp": 8.0, "heading": 1.2, "seed": 0}]
BOX = [{"roll": (0.04037945256572338, 0.10794239889738408, 4.96149044471181),
        "heave": (0.13789039024989425, 0.3245289914620216, 5.227357160577807)},
       {"roll": (0.04370930555615958, 0.11651470789975549, 5.607254623181307),
        "pitch": (0.01119582439314142, 0.0255810107598941, 4.48051382032271),
        "heave": (0.203234849926251, 0.432725359948402, 5.6710240026306025)}]

#: the campaign benchmark's ship (benchmarks/speed/campaign.py: its tank on 20 modes, 200
#: components), 40 s, two cases, recorded the same way
SHIP_CASES = [{"hs": 0.8, "tp": 6.0, "heading": BEAM, "seed": 1}, {"hs": 0.4, "tp": 8.0, "heading": 0.0, "seed": 2}]
SHIP = [{"roll": (0.0359781116551836, 0.08137466194895474, 6.701918277906561),
         "heave": (0.3122830782443682, 0.7214063229848193, 4.711453729897244),
         "probe.A": (0.3119749190442923, 0.7187389029108502, 4.711267773119285),
         "probe.B": (0.3139866472093867, 0.7269928936226349, 4.683123880096376)},
        {"pitch": (0.021528753567837518, 0.038788887867851514, 5.695385453435698),
         "heave": (0.11658056036425042, 0.24687726962407713, 5.054759286495649),
         "probe.A": (0.10556559473470768, 0.23784726998604658, 4.955439810177898),
         "probe.B": (0.12539020010749674, 0.2650134973733186, 5.044078068290105)}]


def _check(out, expected):
    assert [o["status"] for o in out] == ["ok"] * len(expected)
    for o, exp in zip(out, expected):
        for ch, (std, mx, tz) in exp.items():
            st = o["stats"][ch]
            np.testing.assert_allclose([st["std"], st["max"], st["tz"]], [std, mx, tz], rtol=1e-8, err_msg=ch)


def test_a_batchs_statistics_are_those_recorded_before():
    _check(run_batch(scene_text(60.0, 30), "", None, BOX_CASES, 2), BOX)


def test_the_batch_read_back_from_the_programs_folder_gives_the_same_statistics(tmp_path, monkeypatch):
    before = programs.folder()
    text = scene_text(60.0, 30).replace("box alone in irregular seas", "box alone, read back")
    try:
        run_batch(text, "", None, BOX_CASES, 2, None, str(tmp_path))
        assert any(f.startswith("seas-batch-") for f in os.listdir(tmp_path))
        assert any(f.startswith("model-") for f in os.listdir(tmp_path))
        # as a new worker process would: nothing kept in this process, and neither the model built
        # nor the vmapped loop traced again (both read from the folder)
        batch._SEAS_PROGRAMS.clear()
        batch._kept_setup.cache_clear()

        def no(*a, **k):
            raise AssertionError("built or traced again")
        monkeypatch.setattr(batch, "_vmapped", no)
        monkeypatch.setattr(batch, "prepare", no)
        _check(run_batch(text, "", None, BOX_CASES, 2, None, str(tmp_path)), BOX)
    finally:
        programs.use(before)


@pytest.mark.slow
def test_the_paper_ships_batch_gives_the_statistics_recorded_before():
    from benchmarks.speed.campaign import campaign_scene
    _check(run_batch(campaign_scene().text, "", 40.0, SHIP_CASES, 2), SHIP)


def test_one_worker_runs_in_this_process_with_its_phases(env):  # noqa: F811 (the env fixture)
    p, s = files(env)
    before = set(multiprocessing.active_children())
    r = js.campaign(js.load_scene(str(p)), str(s), headings=[1.2, BEAM], seeds=1, cache_dir=str(CACHE), batch=4,
                    workers=1, progress=False)
    assert r.status == ["ok"] * 6
    assert set(multiprocessing.active_children()) == before
    assert r.phases["start"] == 0.0 and r.phases["first"] > 0 and set(r.phases) >= {"setup", "cases", "write"}
    # "write" is a part of "first" and "cases"
    assert sum(v for k, v in r.phases.items() if k != "write") == pytest.approx(r.wall, rel=1e-9)
    # the same cases batch by batch: statistics equal to round-off
    one = run_batch(js.load_scene(str(p)).text, "", None, [{"hs": 0.6, "tp": 7.0, "heading": BEAM, "seed": 0}], 4)
    i = [k for k in range(6) if (r.cases.hs[k], r.cases.heading[k]) == (0.6, BEAM)][0]
    np.testing.assert_allclose(r.statistics["roll"]["std"][i], one[0]["stats"]["roll"]["std"], rtol=1e-12)
