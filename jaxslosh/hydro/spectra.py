"""Incident waves: regular waves, JONSWAP and Pierson-Moskowitz seas (long-crested or spread), and their Froude-Krylov forces on a box hull.

Conventions (linear Airy waves, the frame of the scene: inertial, Z up, the vessel's COG at the
origin at rest, its body axes along the inertial axes at t = 0):

- `heading` beta is the direction the waves travel to, counted from +X towards +Y (radians), as in
  Capytaine and WAMIT: 0 following seas, pi head seas, pi/2 beam seas travelling to port.
- A component of amplitude a, frequency w and phase eps has the elevation
  eta(x, y, t) = a cos(w t + eps - k (x cos beta + y sin beta)), so eta = a cos(w t + eps) at the
  origin; w^2 = g k tanh(k h) (deep water when no depth is given: w^2 = g k).
- A force (or moment) per unit wave amplitude is a complex number X_j (an excitation RAO):
  F_j(t) = a |X_j| cos(w t + eps + arg X_j). Capytaine's X (time factor e^{-i w t}) is the complex
  conjugate of ours.

Everything here is host-side NumPy run once per build; the traced sum of the components is
`physics.seakeeping.Excitation`.
"""
from __future__ import annotations

import functools
import math
from typing import NamedTuple, Optional

import numpy as np


def wavenumber(omega, g=9.81, depth: Optional[float] = None):
    """k from w^2 = g k tanh(k h) (Newton, to round-off); deep water w^2 / g without a depth."""
    w = np.asarray(omega, dtype=float)
    k = w * w / g
    if depth is None:
        return k
    k = np.maximum(k, w / np.sqrt(g * depth))        # the shallow-water root bounds k from below
    for _ in range(60):
        t = np.tanh(k * depth)
        f = g * k * t - w * w
        df = g * t + g * k * depth * (1.0 - t * t)
        step = f / df
        k = k - step
        if np.all(np.abs(step) <= 1e-15 * np.maximum(k, 1e-300)):
            break
    return k


def jonswap(omega, hs: float, tp: float, gamma: float = 3.3):
    """JONSWAP spectral density S(w) (m^2 s / rad), one-sided in w, peak at wp = 2 pi / tp:
    the shape of DNV-RP-C205 (sigma = 0.07 below the peak, 0.09 above), normalised numerically so
    that its integral over (0, inf) is exactly Hs^2 / 16 (instead of the approximate 1 - 0.287 ln gamma)."""
    wp = 2.0 * np.pi / tp
    return (hs * hs / 16.0) * _jonswap_shape(np.asarray(omega, dtype=float), wp, gamma) / _jonswap_norm(wp, gamma)


def pierson_moskowitz(omega, hs: float, tp: float):
    """Pierson-Moskowitz spectral density S(w) (m^2 s / rad), one-sided, peak at wp = 2 pi / tp
    (the fully developed sea, JONSWAP with gamma = 1): (5/16) Hs^2 wp^4 w^-5 exp(-5/4 (wp/w)^4),
    whose integral over (0, inf) is exactly Hs^2 / 16."""
    wp = 2.0 * np.pi / tp
    w = np.maximum(np.asarray(omega, dtype=float), 1e-12)
    return (5.0 / 16.0) * hs * hs * wp ** 4 * w ** -5 * np.exp(-1.25 * (wp / w) ** 4)


def spectrum(waves, omega):
    """The spectral density of an irregular `[waves]` table at frequencies omega (its kind's:
    scene/seas.py)."""
    return waves.spectrum(omega)


def spreading_density(theta, s: float):
    """The cos-2s directional spreading D(theta) = C(s) cos^(2s)(theta / 2) over theta in [-pi, pi]
    (theta from the mean heading), C(s) = Gamma(s + 1) / (2 sqrt(pi) Gamma(s + 1/2)): integral 1."""
    c = math.exp(math.lgamma(s + 1.0) - math.lgamma(s + 0.5)) / (2.0 * math.sqrt(math.pi))
    return c * np.abs(np.cos(0.5 * np.asarray(theta, dtype=float))) ** (2.0 * s)


def spreading(s: float, n: int):
    """(theta, weight): n headings relative to the mean, the midpoints of equal bins over [-pi, pi)
    (an odd n puts one on the mean heading), and their share of the sea's energy, D(theta) dtheta
    normalised to sum to 1 (so the discretised sea keeps its Hs). s = 0 or n = 1: long-crested."""
    if s <= 0 or n <= 1:
        return np.zeros(1), np.ones(1)
    theta = -np.pi + (np.arange(n) + 0.5) * (2.0 * np.pi / n)
    wgt = spreading_density(theta, s) * (2.0 * np.pi / n)
    return theta, wgt / wgt.sum()


def _jonswap_shape(w, wp, gamma):
    w = np.maximum(np.asarray(w, dtype=float), 1e-12)
    sigma = np.where(w <= wp, 0.07, 0.09)
    r = np.exp(-0.5 * ((w - wp) / (sigma * wp)) ** 2)
    return w ** -5 * np.exp(-1.25 * (wp / w) ** 4) * gamma ** r


def _jonswap_norm(wp, gamma):
    """The integral of the JONSWAP shape over (0, inf), kept per (wp, gamma): a campaign draws many
    seas (headings, seeds) of each sea state, and the 400,001-point sum took longer than the rest of
    drawing one."""
    return _jonswap_norm_kept(float(wp), float(gamma))


@functools.lru_cache(maxsize=256)
def _jonswap_norm_kept(wp, gamma):
    # the density is below 1e-30 of its peak under 0.25 wp; above 50 wp its w^-5 tail holds < 1e-9
    w = np.linspace(0.25 * wp, 50.0 * wp, 400001)
    s = _jonswap_shape(w, wp, gamma)
    tail = _jonswap_shape(w[-1], wp, gamma) * w[-1] / 4.0      # integral of w^-5 beyond the grid
    return np.trapezoid(s, w) + tail if hasattr(np, "trapezoid") else np.trapz(s, w) + tail


class Components(NamedTuple):
    """A sea as a sum of regular components (host arrays): eta(0, 0, t) = sum a cos(w t + eps)."""
    omega: np.ndarray      # (N,) rad/s
    amplitude: np.ndarray  # (N,) m, for the scene's wave height (regular: amplitude; JONSWAP: Hs)
    phase: np.ndarray      # (N,) rad
    heading: float         # rad, the mean heading
    headings: Optional[np.ndarray] = None   # (N,) rad, each component's heading (a spread sea); None: `heading`

    def each_heading(self) -> np.ndarray:
        return np.full(self.omega.shape, self.heading) if self.headings is None else self.headings


def components(waves) -> Components:
    """The components of a scene's `[waves]` table (scene/seas.py: a regular wave is one, an
    irregular sea's are `drawn_components`)."""
    return waves.wave_components()


def drawn_components(waves) -> Components:
    """The components of an irregular sea.

    JONSWAP or Pierson-Moskowitz: `components` frequencies, one drawn uniformly in each of equal
    bins over `frequency_range` (so the record does not repeat after 2 pi / dw), amplitudes
    sqrt(2 S(w_i) dw), phases uniform in [0, 2 pi); both drawn from numpy's default_rng(seed), so
    that a sea's components depend on its own table only. A spread sea (`spreading` s > 0) has
    each frequency at `directions` headings (`spreading`), amplitudes sqrt(2 S dw D_j dtheta) and a
    phase of its own per (frequency, heading), drawn after the long-crested ones (a long-crested
    sea of the same seed keeps its phases)."""
    lo, hi = waves.omega_range
    n = int(waves.components)
    rng = np.random.default_rng(int(waves.seed))
    dw = (hi - lo) / n
    w = lo + (np.arange(n) + rng.uniform(size=n)) * dw
    eps = rng.uniform(0.0, 2.0 * np.pi, size=n)
    a = np.sqrt(2.0 * waves.spectrum(w) * dw)
    s = float(getattr(waves, "spreading", 0.0))
    if s <= 0:
        return Components(w, a, eps, float(waves.heading))
    theta, wgt = spreading(s, int(waves.directions))
    m = theta.size
    eps = rng.uniform(0.0, 2.0 * np.pi, size=(n, m))
    return Components(np.repeat(w, m), (a[:, None] * np.sqrt(wgt)[None, :]).ravel(), eps.ravel(),
                      float(waves.heading), np.tile(waves.heading + theta, n))


def elevation(waves, t, point=(0.0, 0.0), g: float = 9.81):
    """The incident wave elevation eta(x, y, t) (m) of a scene's `[waves]` table at times t
    (NumPy; the ramp included), at a horizontal point of the inertial frame (default the origin)."""
    c = components(waves)
    t = np.asarray(t, dtype=float)
    k = wavenumber(c.omega, g, waves.depth)
    b = c.each_heading()
    x = point[0] * np.cos(b) + point[1] * np.sin(b)
    eta = (c.amplitude[None, :] * np.cos(np.outer(t, c.omega) + c.phase[None, :] - (k * x)[None, :])).sum(axis=1)
    return eta.reshape(t.shape) * ramp_factor(t, waves.ramp)


def ramp_factor(t, ramp: float):
    if ramp <= 0:
        return np.ones_like(np.asarray(t, dtype=float))
    t = np.asarray(t, dtype=float)
    return np.where(t < ramp, 0.5 * (1.0 - np.cos(np.pi * np.clip(t, 0.0, ramp) / ramp)), 1.0)
