"""The harmonic forced motion's amplitude, frequency and phase as traced values: the prescribed
motion is a term of the model (physics/vessel.py `HarmonicMotion`) whose numbers are leaves, so
`params`, `jax.grad` and batches (`simulate_batch`, `jaxslosh sweep`) reach them as they reach
every other traceable key.

- jax.grad of a sloshing loss with respect to amplitude and phase against central differences;
- a batch over amplitude and phase equals the runs of the scene files with those values written in.
"""
import os

import jax
import jax.numpy as jnp
import numpy as np

import pytest

import jaxslosh as js
from jaxslosh.scene.keys import TRACEABLE, traceable_keys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
KEYS = ("vessel.forced.amplitude", "vessel.forced.phase")
P0 = np.array([0.02, 0.3])


def _text(amplitude=0.02, phase=0.3):
    """Surge near the first sloshing frequency of the paper tank on a 2 x 2 x 2 mesh, faded in over
    0.3 s, for 0.4 s. The sound speed is 50 m/s so that the Newton iterations reach 1e-13 (at
    1500 m/s round-off leaves ~1e-5 of noise in a difference quotient)."""
    t = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    t = t.replace("duration = 20.0", "duration = 0.4").replace("dt = 0.01", "dt = 0.02")
    t = t.replace("mesh = [5, 5, 5]", "mesh = [2, 2, 2]").replace("sound_speed = 1500.0", "sound_speed = 50.0")
    forced = f'[vessel.forced]\ndof = "surge"\namplitude = {amplitude!r}\nfrequency = 2.4\nramp = 0.3\nphase = {phase!r}\n'
    return t.replace("[vessel.hydrostatics]", forced + "\n[vessel.hydrostatics]")


def _loss(r):
    eta = r.probes["B"].displacement[:, 2] - r.probes["A"].displacement[:, 2]
    return 1e4 * jnp.sum(eta ** 2)


def test_the_harmonic_numbers_are_traceable_and_the_others_are_not():
    scene = js.load_scene(_text())
    assert set(KEYS) | {"vessel.forced.frequency"} <= set(traceable_keys(scene))
    assert "vessel.forced.ramp" not in TRACEABLE and "vessel.forced.rate" not in TRACEABLE


@pytest.mark.slow      # reverse mode through the whole run and its compilation: a long case
def test_gradient_wrt_forced_amplitude_and_phase_matches_central_differences():
    """Relative steps 1e-4 and 1e-5 agree with each other first; the gradient within 1e-7 of them."""
    scene = js.load_scene(_text())

    def loss(p):
        r = js.simulate(scene, params=dict(zip(KEYS, p)))
        return _loss(r), jnp.max(r.solver.residual)

    value_and_grad = jax.jit(jax.value_and_grad(loss, has_aux=True))

    def value(p):
        (v, residual), _ = value_and_grad(jnp.asarray(p))
        assert float(residual) <= 1e-11, residual
        return float(v)

    (v0, residual), g = value_and_grad(jnp.asarray(P0))
    g = np.asarray(g)
    assert float(residual) <= 1e-11
    assert np.all(np.abs(g * P0) > 1e-3 * float(v0)), g      # both move the loss
    for i, key in enumerate(KEYS):
        fds = []
        for rel in (1e-4, 1e-5):
            e = np.zeros(len(P0))
            e[i] = rel * P0[i]
            fds.append((value(P0 + e) - value(P0 - e)) / (2 * e[i]))
        assert abs(fds[0] - fds[1]) <= 1e-6 * abs(fds[1]), (key, fds, "central differences not converged")
        print(key, "gradient", g[i], "central difference", fds[1])
        assert abs(g[i] - fds[1]) <= 1e-7 * abs(fds[1]), (key, g[i], fds)


def test_a_batch_over_amplitude_and_phase_equals_the_scene_files_with_those_values():
    """One vmapped run of three (amplitude, phase) pairs against three runs of scene files with the
    values written in (a batch forms its preconditioner on its own schedule: the runs agree to the
    solver's tolerance, not bit for bit)."""
    amplitude, phase = np.array([0.01, 0.02, 0.03]), np.array([0.0, 0.3, -0.5])
    batch, status = js.simulate_batch(js.load_scene(_text()), {KEYS[0]: amplitude, KEYS[1]: phase})
    assert status == ["ok"] * 3
    for i, (a, ph) in enumerate(zip(amplitude, phase)):
        one = js.simulate(js.load_scene(_text(float(a), float(ph))))
        y, y_b = np.asarray(one.vessel.position)[:, 0], np.asarray(batch.vessel.position)[i, :, 0]
        assert np.abs(y_b - y).max() <= 1e-9 * a, np.abs(y_b - y).max()
        b, b_b = np.asarray(one.probes["B"].displacement), np.asarray(batch.probes["B"].displacement)[i]
        assert np.abs(b).max() > 1e-2 * a                                # the liquid moves
        assert np.abs(b_b - b).max() <= 1e-7 * np.abs(b).max(), np.abs(b_b - b).max()
