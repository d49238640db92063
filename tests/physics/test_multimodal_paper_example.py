"""The paper example (scenes/paper_ship_tank.toml) with its tank as a `flow = "3d"` multimodal tank
against the finite elements: probe B's elevation on the free surface (benchmarks/validation/paper_probe_b.py
runs the mesh and mode sequences the tolerances rest on)."""
from pathlib import Path

import numpy as np
import pytest

import jaxslosh as js

SCENE = (Path(__file__).resolve().parents[2] / "scenes" / "paper_ship_tank.toml").read_text()


def _probe_b(text):
    r = js.simulate(js.load_scene(text))
    assert r.status == "ok"
    z = np.asarray(r.probes["B"].displacement)[:, 2]
    return np.abs(z).max(), np.sqrt(np.mean(z ** 2))


@pytest.mark.slow      # two 20 s runs of the ship: about 20 s of CPU
def test_paper_example_probe_b_multimodal_is_the_finite_elements_within_2_percent():
    """The paper's run (20 s, initial angular velocity (0.1, 0.05, 0) rad/s): the multimodal tank on
    12 modes (third-order system) against the 8 x 8 x 8 finite elements, probe B's peak and rms over
    the run within 2 % (they are -0.3 % and +1.4 % apart). The 8 x 8 x 8 mesh is within 0.4 % (peak)
    and 0.8 % (rms) of the 20 x 20 x 20 one; the modes along x that 12 modes lack ((7, 0) to (11, 0):
    B is on the node of (5, 0), so 25 modes add none that reach it) would move the multimodal peak by
    -0.8 % and its rms by -1.2 % (measured with the two-dimensional tank, which holds them). Against
    the finest mesh with those modes' share the difference is -1.5 % and -0.6 %: within 2 % either
    way (docs/guide/nonlinear-sloshing.md, "The paper example")."""
    fem = _probe_b(SCENE.replace("mesh = [5, 5, 5]", "mesh = [8, 8, 8]"))
    mm = _probe_b(SCENE.replace('mesh = [5, 5, 5]\nwalls = "rigid"',
                                'model = "multimodal"\nflow = "3d"\nmodes = 12\nexpansion = "third-order"'))
    rel = np.array(mm) / np.array(fem) - 1
    assert np.all(np.abs(rel) < 0.02), rel


@pytest.mark.slow      # three scenes' programs (the 16 x 16 x 16 tank's and two multimodal): about 40 s
def test_paper_example_linear_limit_multimodal_is_the_finite_elements():
    """The linear limit (the paper's initial angular velocity times 0.01, 5 s): both tanks are linear
    potential flow and roll does not reach B at first order, so the two-dimensional tank on 12 modes
    (the modes along x up to (11, 0)) is probe B's linear response; against 16 x 16 x 16 finite
    elements (0.7 % and 0.4 % from 28 x 28 x 28 over these 5 s) its peak and rms agree within 1 %.
    On 6 modes ((1, 0) to (5, 0); B is on the node of (5, 0)) the series lacks (7, 0) to (11, 0)
    and reads more than 1 % high: the truncation that a `flow = "3d"` tank on up to 50 modes keeps."""
    text = SCENE.replace("duration = 20.0", "duration = 5.0").replace(
        "angular_velocity = [0.1, 0.05, 0.0]", "angular_velocity = [0.001, 0.0005, 0.0]")
    fem = np.array(_probe_b(text.replace("mesh = [5, 5, 5]", "mesh = [16, 16, 16]")))
    mm = {n: np.array(_probe_b(text.replace('mesh = [5, 5, 5]\nwalls = "rigid"',
                                            f'model = "multimodal"\nmodes = {n}\nexpansion = "third-order"')))
          for n in (6, 12)}
    assert np.all(np.abs(mm[12] / fem - 1) < 0.01), mm[12] / fem - 1
    assert np.all(mm[6] / fem - 1 > 0.01), mm[6] / fem - 1
