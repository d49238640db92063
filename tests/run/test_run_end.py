"""A run stepped in chunks ends at its duration: the last chunk's steps past it are neither run nor
counted, so a failure there cannot mark a run that has all its steps as failed."""
import os

import h5py

import jaxslosh as js
from jaxslosh.run import loop
from jaxslosh.run.tofile import run_to_file

SCENES = os.path.join(os.path.dirname(__file__), "..", "..", "scenes")


def _violent(duration):
    """The paper ship set rolling hard: a step fails at t = 11.14 s (step 1114)."""
    text = open(os.path.join(SCENES, "paper_ship_tank.toml")).read()
    text = text.replace("angular_velocity = [0.1, 0.05, 0.0]",
                        "angular_velocity = [0.5, 0.3, 0.2]\nroll_pitch_yaw = [0.6, 0.0, 0.0]")
    text = text.replace("duration = 20.0", f"duration = {duration}\nchunk = 400")
    return js.load_scene(text)


def test_a_run_that_ends_before_a_failure_in_its_last_chunk_is_ok(tmp_path):
    """1100 steps in chunks of 400: the third chunk reaches step 1200, past the failure at 1114.
    Those steps are skipped, so the run is ok with 1100 steps, and the iterations of its frames past
    the end were never taken."""
    out = str(tmp_path / "r.h5")
    rep = run_to_file(_violent(11.0), out, progress=False)
    assert rep.status == "ok" and rep.code == js.Status.OK and rep.steps == 1100
    with h5py.File(out, "r") as f:
        assert f.attrs["status"] == "ok" and int(f.attrs["steps_done"]) == 1100
        assert f["time"].shape == (1101,) and abs(f["time"][-1] - 11.0) < 1e-9


def test_skipped_steps_leave_the_state_and_count_nothing():
    scene = _violent(0.05)
    stepper = js.Stepper(scene)
    c = loop.ending_at(stepper.init(), 2)
    for _ in range(4):
        c = stepper.step(c)
    assert int(c.k) == 2 and int(c.n) == 2 and abs(float(c.s.t) - 0.02) < 1e-12 and stepper.status(c) == "ok"
