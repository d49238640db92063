"""Batches carry the Newton preconditioner from step to step (formed anew every few steps, since a
vmapped run cannot form it on its own test). Near resonance a multimodal tank's Jacobian moves fast
(its high modes' integrals go as exp(k_n zeta)): a preconditioner formed three steps before contracts
the residual by only about half per iteration, and a step ran out of iterations at 1.2 to 1.8 times
the tolerance where a fresh preconditioner converges in three. Such a step is now redone with a fresh
one (solve/integrator._step_or_redo); a step that fails with a fresh one still fails, with its step."""
import re

import numpy as np
import pytest

import jaxslosh as js

TANK = """
[environment]
gravity = 9.81
[simulation]
duration = {duration}
dt = {dt}
scheme = "newmark"
tolerance = 1e-10
max_iterations = {iters}
[vessel]
mass = 1.0e3
inertia = [1.0e3, 1.0e3, 1.0e3]
[vessel.forced]
dof = "surge"
amplitude = {A}
frequency = 4.0421
ramp = {ramp}
[[tanks]]
name = "tank"
origin = [-0.865, -0.1, -0.5]
size = [1.73, 0.2, 1.4]
fill_depth = 0.865
model = "multimodal"
modes = 2
[[probes]]
name = "wall"
tank = "tank"
point = [0.0, 0.1, 0.865]
"""
G = 9.81


def test_a_step_the_carried_preconditioner_cannot_finish_is_redone_fresh():
    # the forcing at the first mode's frequency (4.0421 rad/s at h = 0.865 m) and 2.4 % above it;
    # 6 iterations: what a fresh preconditioner needs (3 to 5) and fewer than a stale one here (a
    # run without the redo stopped at step 24 and 27 with scaled residuals 1.1e-10 and 1.35e-10)
    scene = js.load_scene(TANK.format(duration=2.0, dt=0.05, iters=6, A=0.05, ramp=0.5))
    ratios = np.array([1.0, 0.976])
    res, status = js.simulate_batch(scene, {"environment.gravity": G / ratios ** 2})
    assert status == ["ok", "ok"], status
    it = np.asarray(res.solver.iterations)
    assert it.max() > 6          # some step was redone (both attempts' iterations are counted)
    z = np.asarray(res.probes["wall"].displacement)[..., 2]
    assert np.abs(z).max() > 0.05             # large, near resonance
    # each run is the single run's (which forms its preconditioner again when convergence slows)
    one = js.simulate(scene, params={"environment.gravity": G / ratios[1] ** 2})
    np.testing.assert_allclose(z[1], np.asarray(one.probes["wall"].displacement)[:, 2], rtol=0, atol=1e-9)


# slow: the default suite sees a batch case fail with its step in tests/campaign/test_campaign.py's
# failing campaign (Hs 1000 m)
@pytest.mark.slow
def test_a_divergent_step_still_fails_with_its_step():
    # a time step of a third of the sloshing period at 0.3 m of surge: Newton diverges with a fresh
    # preconditioner too, and the run reports the step where it stopped
    scene = js.load_scene(TANK.format(duration=2.0, dt=0.2, iters=25, A=0.3, ramp=0.2))
    _, status = js.simulate_batch(scene, {"environment.gravity": np.array([G])})
    m = re.match(r"step (\d+) \(t = ([\d.]+) s\): Newton did not converge in \d+ iterations \(scaled residual "
                 r"([\d.e+-]+), tolerance 1e-10\)", status[0])
    assert m, status
    assert 1 <= int(m[1]) <= 10 and abs(float(m[2]) - 0.2 * int(m[1])) < 1e-9
    assert float(m[3]) > 1e-3        # far from converged: not a stall near the tolerance
