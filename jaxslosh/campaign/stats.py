"""Response statistics of one case: per channel (roll, pitch, heave, probe.<name> vertical
displacement, mooring.<name> fairlead tension, <body>.roll/pitch/heave, connection.<name> force) over the saved frames from t = waves.ramp on; the
Rayleigh exceedance and the operability of a scatter (host NumPy / SciPy)."""
from __future__ import annotations

import math

import numpy as np

STATISTICS = ("std", "significant", "max", "mpm", "tz")
#: a channel whose standard deviation is below this (m or rad, plus 1e-12 of its largest value) has
#: no response: what varies is round-off (the roll of a symmetric ship in head seas), and its
#: zero crossings would give a period tz of nothing; its tz and mpm are NaN
RESPONSE_FLOOR = 1e-9


def channels(result, run=None) -> dict:
    """{channel: (frames,) series} of a result (`run`: the index along a batch's leading axis)."""
    pick = (lambda x: np.asarray(x)) if run is None else (lambda x: np.asarray(x)[run])
    rpy = pick(result.vessel.roll_pitch_yaw)
    out = {"roll": rpy[:, 0], "pitch": rpy[:, 1], "heave": pick(result.vessel.position)[:, 2]}
    for name, p in result.probes.items():
        out[f"probe.{name}"] = pick(p.displacement)[:, 2]
    for name, line in (result.mooring or {}).items():
        out[f"mooring.{name}"] = pick(line.fairlead_tension)
    for name, body in (getattr(result, "bodies", None) or {}).items():   # position: its offset from rest
        b = pick(body.roll_pitch_yaw)
        out.update({f"{name}.roll": b[:, 0], f"{name}.pitch": b[:, 1], f"{name}.heave": pick(body.position)[:, 2]})
    for name, c in (getattr(result, "connections", None) or {}).items():
        out[f"connection.{name}"] = pick(c.force)
    return out


def segment_length(n_frames: int) -> int:
    """Welch's segment: a quarter of the record (7 half-overlapping segments), the same for every
    case of a campaign (equal records), so that their spectra share one frequency grid."""
    return max(8, n_frames // 4)


def frequencies(n_frames: int, dt_frame: float) -> np.ndarray:
    """The response spectra's frequencies (rad/s) for records of `n_frames` frames `dt_frame` apart."""
    return 2.0 * np.pi * np.fft.rfftfreq(segment_length(n_frames), dt_frame)


def welch(y, dt: float, nperseg: int) -> np.ndarray:
    """The one-sided power spectral density (per Hz) of y sampled every dt by Welch's method, as
    SciPy's `signal.welch(y, fs=1 / dt, nperseg=nperseg, detrend="constant")` computes it: segments
    of nperseg samples overlapping by half, each less its mean and windowed by the periodic Hann
    window, their periodograms averaged. Written out here (the frequencies are
    `frequencies(n, dt)`'s): importing scipy.signal, which imports scipy.stats, took a second of
    every campaign process's start, a worker's too (docs/benchmarks.md, campaigns)."""
    y = np.asarray(y, dtype=float)
    nperseg = min(int(nperseg), y.size)
    step = nperseg - nperseg // 2
    starts = np.arange((y.size - nperseg // 2) // step) * step
    seg = y[starts[:, None] + np.arange(nperseg)]
    win = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(nperseg) / nperseg)
    X = np.fft.rfft((seg - seg.mean(axis=1, keepdims=True)) * win, axis=1)
    p = (X.real ** 2 + X.imag ** 2).mean(axis=0) * (dt / float(np.sum(win * win)))
    p[1:nperseg - nperseg // 2] *= 2.0          # one-sided: every bin but 0 (and nperseg / 2 when even) twice
    return p


def statistics(t, x) -> dict:
    """std, significant (4 std), max |x - mean|, most probable maximum over the record (Rayleigh:
    std sqrt(2 ln N), N = duration / tz), the mean zero-upcrossing period tz, and the one-sided
    spectral density in rad/s (Welch) of the record x(t), t equally spaced."""
    t, x = np.asarray(t, dtype=float), np.asarray(x, dtype=float)
    y = x - x.mean()
    std = float(y.std())
    silent = std <= RESPONSE_FLOOR + 1e-12 * float(np.abs(x).max())    # round-off about a constant
    duration = float(t[-1] - t[0]) + float(t[1] - t[0])
    # the mean period between the first and last upcrossings (interpolated between frames): a count
    # over the whole record would be off by the part-cycles at its ends
    k = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0)) if not silent else np.zeros(0, dtype=int)
    tc = t[k] + (t[k + 1] - t[k]) * (-y[k]) / (y[k + 1] - y[k])
    tz = float(tc[-1] - tc[0]) / (k.size - 1) if k.size >= 2 else math.nan
    n_cycles = duration / tz if k.size >= 2 else 0.0
    mpm = std * math.sqrt(2.0 * math.log(n_cycles)) if n_cycles > 1 else math.nan
    # Welch (averaged, windowed periodograms of overlapping segments) rather than one periodogram:
    # a single periodogram's scatter at each frequency does not fall as the record grows, the
    # average of segments' does, at the price of the segment's coarser resolution
    dt = float(t[1] - t[0])
    p = welch(y, dt, segment_length(y.size))
    return {"std": std, "significant": 4.0 * std, "max": float(np.abs(y).max()), "mpm": mpm, "tz": tz,
            "spectrum": p / (2.0 * np.pi)}


def case_statistics(t, series: dict, t0: float) -> dict:
    """{channel: statistics} of one case over its frames from t0 (waves.ramp) on."""
    t = np.asarray(t, dtype=float)
    keep = t >= t0 - 1e-9 * max(1.0, abs(t0))
    return {ch: statistics(t[keep], np.asarray(x)[keep]) for ch, x in series.items()}


def exceedance(std, tz, duration: float, limit: float):
    """The probability that a narrow-band Gaussian response of this std and zero-upcrossing period
    exceeds `limit` (in |x|, its peaks Rayleigh) at least once in `duration`:
    1 - exp(-N exp(-limit^2 / (2 std^2))), N = duration / tz."""
    std, tz = np.asarray(std, dtype=float), np.asarray(tz, dtype=float)
    n = np.where(np.isfinite(tz) & (tz > 0), duration / np.where(tz > 0, tz, 1.0), 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(std > 0, np.exp(-0.5 * (limit / np.where(std > 0, std, 1.0)) ** 2), 0.0)
    return 1.0 - np.exp(-n * q)


def operability(stats: dict, weight, ok, limits: dict, duration: float, failed=None) -> dict:
    """Per limited channel the scatter-weighted probability of exceeding its limit in `duration`
    (Rayleigh, from each case's std and tz), and the operability: the weighted share (%) of the
    cases whose every limited channel's largest |x - mean| stayed within its limit. The cases
    judged are those that finished (`ok`) and those that `failed`: a failed case is not operable
    and counts as exceeding every limit (a run that broke down is not one a ship rides out);
    cases still pending are left out, the weights of the judged renormalised. "failed": the share
    (%) of the judged weight that failed."""
    ok = np.asarray(ok, dtype=bool)
    bad = np.zeros_like(ok) if failed is None else np.asarray(failed, dtype=bool) & ~ok
    weight = np.asarray(weight, dtype=float)
    w = np.where(ok, weight, 0.0)
    w_bad = np.where(bad, weight, 0.0)
    total = w.sum() + w_bad.sum()
    out = {"exceedance": {ch: math.nan for ch in limits}, "operability": math.nan, "failed": math.nan}
    if total <= 0:
        return out
    within = np.ones(w.shape, dtype=bool)
    for ch, lim in limits.items():
        p = exceedance(stats[ch]["std"], stats[ch]["tz"], duration, lim)
        out["exceedance"][ch] = float((np.sum(w * np.nan_to_num(p)) + w_bad.sum()) / total)
        within &= np.asarray(stats[ch]["max"]) <= lim
    out["operability"] = float(100.0 * np.sum(w * within) / total)
    out["failed"] = float(100.0 * w_bad.sum() / total)
    return out
