"""The multimodal tank against a laboratory experiment: Faltinsen, Rognebakke, Lukovsky & Timokha
(2000, J. Fluid Mech. 407), figure 7 (benchmarks/data/faltinsen2000_fig7.csv, scenes/sloshing_experiment.toml):
the wave elevation 0.05 m from the wall of a 1.73 m tank filled to 0.6 m, moved in surge by
x = 0.032 cos(2 pi t / 1.3) m from rest.

Linear theory here is the closed form of the tank's standing waves forced from rest (independent of
the finite elements); the fully nonlinear potential flow is the high-order spectral solution of
tests/hos_sloshing.py (independent of the multimodal liquid). What the measurement supports: linear
theory is off by more than 15 % rms of the measured maximum and makes crests and troughs equal, where
the measured crests rise about 1.5 times as high as the troughs fall; the multimodal tank reproduces
that asymmetry. It does not reproduce the measured heights within 10 % at the forcing as documented
(benchmarks/validation/sloshing_experiments.py), and neither does the fully nonlinear potential flow, which the
multimodal tank follows: already in the first half-period, where the motion is still linear, the
documented forcing gives a trough 30 % deeper than the measured one.

The rig's start-up is not published. Identified on the first half-period alone (t < 0.8 s, least
squares of linear theory), a start with a delay reproduces that half-period but puts the later beats
out of phase; the later record is in phase with a clean harmonic start from rest, whose one unknown is
then the amplitude. With it, linear theory is itself within 15 % rms, and no amplitude brings the
multimodal tank within 10 % of the scored record: the issue's target is not reachable with this
record (benchmarks/validation/sloshing_experiments.py prints the numbers)."""
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

import jaxslosh as js
from hos_sloshing import hos_tank
from record_components import components, fitted_components
from scipy.optimize import minimize
from scipy.signal import fftconvolve

ROOT = Path(__file__).resolve().parents[2]
L, H, G, A, W, X = 1.73, 0.6, 9.81, 0.032, 2 * np.pi / 1.3, 0.05
EARLY = 0.8                 # the first half-period (the first trough, linear): the fit window
#: the batch of clean harmonic starts run with the multimodal tank: the documented amplitude and three
#: around the one that the first trough gives (24.5 mm)
AMPLITUDES = (0.032, 0.0235, 0.0245, 0.0255)


def _measured():
    text = (ROOT / "benchmarks" / "data" / "faltinsen2000_fig7.csv").read_text()
    rows = [line.split(",") for line in text.splitlines() if line.strip() and not line.startswith("#")]
    assert rows[0] == ["t", "elevation"]
    d = np.array(rows[1:], dtype=float)
    return d[:, 0], d[:, 1]


def _linear(t, n=60):
    """Linear theory from rest: each standing wave cos(k_n x) of the tank, forced by the surge
    acceleration -A w^2 cos(w t), is beta_n = F_n (cos w t - cos w_n t) / (w_n^2 - w^2)."""
    k = np.arange(1, n + 1) * np.pi / L
    wn = np.sqrt(G * k * np.tanh(k * H))
    c = ((-1.0) ** np.arange(1, n + 1) - 1.0) / k ** 2      # integral of x cos(k x) over the length
    mn = 0.5 * L / (k * np.tanh(k * H))                      # the mode's mass per unit rho b
    F = c * A * W ** 2 / mn
    t = np.asarray(t)[:, None]
    return np.sum(F / (wn ** 2 - W ** 2) * (np.cos(W * t) - np.cos(wn * t)) * np.cos(k * X), axis=1)


@lru_cache(maxsize=None)
def _multimodal_first_beat():
    """The scene's multimodal tank over the first beat (to 3.6 s): (t, elevation at the probe)."""
    text = (ROOT / "scenes" / "sloshing_experiment.toml").read_text().replace("duration = 10.0", "duration = 3.6")
    r = js.simulate(js.load_scene(text))
    assert r.status == "ok"
    return np.asarray(r.time), np.asarray(r.probes["wall"].displacement)[:, 2]


def _multimodal_runs():
    """The scene's multimodal tank over the record (10 s) at each of AMPLITUDES, one batch:
    (t, elevations at the probe, one row per amplitude)."""
    scene = js.load_scene(ROOT / "scenes" / "sloshing_experiment.toml")
    result, status = js.simulate_batch(scene, {"vessel.forced.amplitude": np.array(AMPLITUDES)})
    assert list(status) == ["ok"] * len(AMPLITUDES)
    t = np.asarray(result.time)
    t = t[0] if t.ndim == 2 else t
    return t, np.asarray(result.probes["wall"].displacement)[..., 2]


def _linear_response(acceleration, t):
    """Linear theory for any surge acceleration a (sampled on the even grid t from 0, the liquid at rest
    at t = 0): beta_n'' + w_n^2 beta_n = -F_n a / (A W^2) by convolution with sin(w_n t) / w_n, with
    _linear's modes."""
    n = np.arange(1, 61)
    k = n * np.pi / L
    wn = np.sqrt(G * k * np.tanh(k * H))
    gain = ((-1.0) ** n - 1.0) / k ** 2 / (0.5 * L / (k * np.tanh(k * H)))
    dt = t[1] - t[0]
    # the trapezoidal rule (the end at t carries sin 0 = 0, the one at 0 half its weight)
    beta = np.array([(fftconvolve(acceleration, np.sin(w * t))[:t.size] - 0.5 * acceleration[0] * np.sin(w * t)) / w
                     for w in wn]) * dt
    return np.cos(k * X) @ (-gain[:, None] * beta)


def _scored_rms(t, z, tm, zm):
    """rms difference from the measurement over the scored window (t >= EARLY) over the measured maximum."""
    late = tm >= EARLY
    return np.sqrt(np.mean((np.interp(tm[late], t, z) - zm[late]) ** 2)) / zm.max()


def test_linear_theory_misses_the_measured_elevation():
    """Over the whole record (0.1 to 9.9 s): more than 15 % rms of the measured maximum, its
    troughs more than 1.4 times as deep as the measured ones."""
    tm, zm = _measured()
    zl = _linear(tm)
    assert np.sqrt(np.mean((zl - zm) ** 2)) > 0.15 * zm.max()
    t = np.linspace(tm[0], tm[-1], 4001)
    assert -_linear(t).min() > 1.4 * -zm.min()


def test_multimodal_tank_has_the_measured_crest_to_trough_ratio():
    """The first beat (to 3.6 s: the largest measured crest at 2.57 s and the deepest trough at
    3.27 s): the measured crest is 1.54 times the trough; the multimodal tank's within 15 % of that,
    linear theory's (about 1.06) more than 25 % off. Crest and trough at the measured times (0.05 s)."""
    tm, zm = _measured()
    first = tm <= 3.6
    tm, zm = tm[first], zm[first]
    t, z = _multimodal_first_beat()
    measured = zm.max() / -zm.min()
    multimodal = z.max() / -z.min()
    zl = _linear(t)
    linear = zl.max() / -zl.min()
    assert abs(multimodal / measured - 1) < 0.15, (multimodal, measured)
    assert abs(linear / measured - 1) > 0.25, (linear, measured)
    assert abs(t[np.argmax(z)] - tm[np.argmax(zm)]) < 0.05
    assert abs(t[np.argmin(z)] - tm[np.argmin(zm)]) < 0.05


def test_multimodal_tank_is_the_fully_nonlinear_potential_flow():
    """The scene's forcing over the first beat: the multimodal tank (8 modes) within 10 mm (5 % of its
    0.2 m crest) of the independent high-order spectral solution (16 modes, fourth order). Both
    overshoot the measured crest by more than 30 %: the overshoot is not the multimodal model's."""
    t, z = _multimodal_first_beat()
    th, zh = hos_tank(L, H, G, lambda s: -A * W ** 2 * np.cos(W * s), 3.6, 0.01, X)
    assert np.max(np.abs(np.interp(t, th, zh) - z)) < 0.010
    zm = _measured()[1]
    assert z.max() > 1.3 * zm.max() and zh.max() > 1.3 * zm.max()


def test_documented_forcing_misses_the_linear_first_half_period():
    """The first trough (before 0.8 s, 0.04 m: still linear): the multimodal tank's within 2 % of
    linear theory's, and both more than 25 % deeper than the measured one (so no model of the liquid
    mends it: the tank's motion at the start differs from the documented one)."""
    tm, zm = _measured()
    t, z = _multimodal_first_beat()
    early = t < 0.8
    multimodal, linear, measured = z[early].min(), _linear(t[early]).min(), zm[tm < 0.8].min()
    assert abs(multimodal / linear - 1) < 0.02, (multimodal, linear)
    assert multimodal < 1.25 * measured and linear < 1.25 * measured, (multimodal, linear, measured)


def test_linear_response_is_the_closed_form():
    """The convolution of _linear_response against _linear's closed form, the documented start: within
    0.05 mm over 10 s (so the identifications below use linear theory itself)."""
    t = np.arange(0.0, 10.0, 0.002)
    z = _linear_response(-A * W ** 2 * np.cos(W * t), t)
    assert np.max(np.abs(z - _linear(t))) < 5e-5


def test_a_start_identified_on_the_first_half_period_puts_the_beats_out_of_phase():
    """An amplitude and a delay (the tank at rest until the delay), least squares of linear theory over the
    first half-period: it reproduces that half-period within 3 % rms of the measured maximum (the
    documented start: 12 %), but over the rest of the record linear theory is then off by more than
    20 % (the documented start: 17 %); the measured beats are in phase with a start at t = 0."""
    tm, zm = _measured()
    t = np.arange(0.0, 10.0, 0.004)
    early = tm < EARLY

    def response(p):
        return _linear_response(np.where(t >= p[1], -p[0] * W ** 2 * np.cos(W * (t - p[1])), 0.0), t)

    def misfit(p):
        return np.sqrt(np.mean((np.interp(tm[early], t, response(p)) - zm[early]) ** 2)) / zm.max()
    fit = minimize(misfit, [0.025, 0.05], method="Nelder-Mead")
    assert fit.fun < 0.03 and misfit([A, 0.0]) > 0.10, (fit.x, fit.fun)
    assert 0.05 < fit.x[1] < 0.15, fit.x
    assert _scored_rms(t, response(fit.x), tm, zm) > 0.20
    assert 0.15 < _scored_rms(t, response([A, 0.0]), tm, zm) < 0.20


def test_with_the_amplitude_identified_linear_theory_is_within_15_percent():
    """The clean start from rest at the amplitude that makes the first trough the measured one (24.5 mm):
    linear theory is within 15 % rms of the measured maximum over the scored record (0.8 to 9.9 s), so
    the target's premise (linear theory off by more than 15 %) holds only at the documented forcing."""
    tm, zm = _measured()
    t = np.arange(0.0, 10.0, 0.002)
    zl = _linear(t)
    amplitude = A * zm[tm < EARLY].min() / zl[t < EARLY].min()
    assert abs(amplitude - 0.0245) < 0.0005, amplitude
    assert _scored_rms(t, amplitude / A * zl, tm, zm) < 0.15
    assert _scored_rms(t, zl, tm, zm) > 0.15


def test_the_measured_free_wave_is_not_the_one_a_harmonic_start_gives():
    """The scored record (0.8 to 9.9 s) as the forced wave, the free first mode and their products
    (tests/record_components.py): any harmonic start from rest, whatever its amplitude, sets the free
    wave 1.2 times the forced one in linear theory (and, within 3 %, in the multimodal tank and the
    fully nonlinear potential flow: the benchmark's table); the measured free wave is 0.87 of the
    measured forced one, and falls by a tenth from the window's first half to its second (damping
    ratio about 0.007), where linear theory's stays within 1 %. Both frequencies are measured within
    0.5 % of the forcing's and linear theory's first mode's, so the time axis of the digitised
    record is not what differs: the tank's motion at the start is."""
    tm, zm = _measured()
    t = np.arange(0.0, 10.0, 0.002)
    k = np.pi / L
    w0 = [W, np.sqrt(G * k * np.tanh(k * H))]
    w, measured, _ = fitted_components(tm, zm, EARLY, tm[-1], w0)
    assert np.all(np.abs(w / w0 - 1) < 0.005), w
    zl = _linear(t)
    w_lin, linear, _ = fitted_components(t, zl, EARLY, tm[-1], w0)
    assert linear[1] / linear[0] > 1.15 and measured[1] / measured[0] < 0.95, (linear[:2], measured[:2])
    half = 0.5 * (EARLY + tm[-1])
    decay = [components(tm, zm, EARLY, half, w)[1][1], components(tm, zm, half, tm[-1], w)[1][1]]
    assert decay[1] < 0.95 * decay[0], decay
    kept = [components(t, zl, EARLY, half, w_lin)[1][1], components(t, zl, half, tm[-1], w_lin)[1][1]]
    assert abs(kept[1] / kept[0] - 1) < 0.01, kept


@pytest.mark.slow
def test_no_clean_start_brings_the_multimodal_tank_within_10_percent():
    """The multimodal tank over the scored record (0.8 to 9.9 s): 18 % rms of the measured maximum at the
    documented 32 mm, 11 % at the 24.5 mm of the first trough, and more than 10 % at 23.5 and 25.5 mm
    on either side (the rms is least near 24.5 mm: the floor of a clean harmonic start, chosen even on
    the scored window itself, is above the target)."""
    tm, zm = _measured()
    t, z = _multimodal_runs()
    rms = [_scored_rms(t, zi, tm, zm) for zi in z]
    assert rms[0] > 0.15, rms
    assert rms[2] < 0.12 and min(rms[1:]) > 0.10, rms
    assert rms[2] <= min(rms[1], rms[3]), rms
