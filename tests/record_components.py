"""A sloshing record's components (no jaxslosh imports): the elevation at a probe of a tank forced
harmonically from rest, over a window, as a mean plus six sinusoids. The forced wave (the forcing's
frequency) and the free first mode (its natural frequency) are the linear response; twice each, their
sum and their difference are the second-order products. Both frequencies are fitted by nonlinear least
squares (the amplitudes, linear in the basis, by linear least squares at each trial), or given.

A harmonic start from rest sets the free wave against the forced one; the liquid's nonlinearity shows
in the frequencies and the products. The benchmark (benchmarks/validation/sloshing_experiments.py) and the
experiment's tests use it on the measured record and the models' alike."""
from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

#: the six components' names, in the order of the amplitudes returned
COMPONENTS = ("forced", "free", "2 forced", "2 free", "sum", "difference")


def components(t, z, t0, t1, w):
    """((forced, free) frequencies, the six amplitudes in COMPONENTS' order, rms of the rest) of the
    record z(t) over t0 <= t <= t1, at the two given frequencies w (fitted_components fits them)."""
    sel = (t >= t0) & (t <= t1)
    B = _basis(t[sel], w)
    c = np.linalg.lstsq(B, z[sel], rcond=None)[0]
    return np.asarray(w, dtype=float), np.hypot(c[1::2], c[2::2]), np.sqrt(np.mean((B @ c - z[sel]) ** 2))


def fitted_components(t, z, t0, t1, w0):
    """components() with both frequencies fitted by least squares, starting from w0."""
    sel = (t >= t0) & (t <= t1)
    ts, zs = t[sel], z[sel]

    def residual(w):
        B = _basis(ts, w)
        return B @ np.linalg.lstsq(B, zs, rcond=None)[0] - zs
    return components(t, z, t0, t1, least_squares(residual, w0).x)


def _basis(t, w):
    freqs = (w[0], w[1], 2 * w[0], 2 * w[1], w[0] + w[1], abs(w[0] - w[1]))
    return np.column_stack([np.ones_like(t)] + [f(v * t) for v in freqs for f in (np.cos, np.sin)])
