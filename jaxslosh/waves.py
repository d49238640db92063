"""Incident waves: regular waves and JONSWAP seas, and their Froude-Krylov forces on a box hull.

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

Everything here is host-side NumPy run once per build; the only traced code is `Excitation.force`,
a sum of cosines over the precomputed components inside the jitted step.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")


# --------------------------------------------------------------------------------------------
# Wave kinematics and spectra (host)


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


def _jonswap_shape(w, wp, gamma):
    w = np.maximum(np.asarray(w, dtype=float), 1e-12)
    sigma = np.where(w <= wp, 0.07, 0.09)
    r = np.exp(-0.5 * ((w - wp) / (sigma * wp)) ** 2)
    return w ** -5 * np.exp(-1.25 * (wp / w) ** 4) * gamma ** r


def _jonswap_norm(wp, gamma):
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
    heading: float         # rad


def components(waves) -> Components:
    """The components of a scene's `[waves]` table (scene_types.Waves).

    JONSWAP: `components` frequencies, one drawn uniformly in each of equal bins over
    `frequency_range` (so the record does not repeat after 2 pi / dw), amplitudes
    sqrt(2 S(w_i) dw), phases uniform in [0, 2 pi); both drawn from numpy's default_rng(seed)."""
    if waves.type == "regular":
        return Components(np.array([waves.omega]), np.array([waves.amplitude]), np.array([waves.phase]),
                          float(waves.heading))
    lo, hi = waves.omega_range
    n = int(waves.components)
    rng = np.random.default_rng(int(waves.seed))
    dw = (hi - lo) / n
    w = lo + (np.arange(n) + rng.uniform(size=n)) * dw
    eps = rng.uniform(0.0, 2.0 * np.pi, size=n)
    a = np.sqrt(2.0 * jonswap(w, waves.hs, waves.tp, waves.gamma) * dw)
    return Components(w, a, eps, float(waves.heading))


def elevation(waves, t, point=(0.0, 0.0), g: float = 9.81):
    """The incident wave elevation eta(x, y, t) (m) of a scene's `[waves]` table at times t
    (NumPy; the ramp included), at a horizontal point of the inertial frame (default the origin)."""
    c = components(waves)
    t = np.asarray(t, dtype=float)
    k = wavenumber(c.omega, g, waves.depth)
    x = point[0] * np.cos(c.heading) + point[1] * np.sin(c.heading)
    eta = (c.amplitude[None, :] * np.cos(np.outer(t, c.omega) + c.phase[None, :] - k[None, :] * x)).sum(axis=1)
    return eta.reshape(t.shape) * ramp_factor(t, waves.ramp)


def ramp_factor(t, ramp: float):
    if ramp <= 0:
        return np.ones_like(np.asarray(t, dtype=float))
    t = np.asarray(t, dtype=float)
    return np.where(t < ramp, 0.5 * (1.0 - np.cos(np.pi * np.clip(t, 0.0, ramp) / ramp)), 1.0)


# --------------------------------------------------------------------------------------------
# Froude-Krylov forces on a box hull (host, closed form)


def _e0(kappa, c):
    """int_{-c}^{c} exp(-i kappa s) ds (real)."""
    u = kappa * c
    return 2.0 * c * np.sinc(u / np.pi)


def _e1(kappa, c):
    """int_{-c}^{c} s exp(-i kappa s) ds = -2 i (sin(u) - u cos(u)) / kappa^2, u = kappa c (imaginary);
    by its series -2i c^3 kappa (1/3 - u^2/30 + u^4/840) for small u."""
    u = kappa * c
    small = np.abs(u) < 1e-2
    us = np.where(small, 1.0, u)
    ks = np.where(small, 1.0, kappa)
    exact = (np.sin(us) - us * np.cos(us)) / (ks * ks)
    series = c * c * c * kappa * (1.0 / 3.0 - u * u / 30.0 + u ** 4 / 840.0)
    return -2j * np.where(small, series, exact)


def _vertical(k, draft, z_wl, depth):
    """f(z') = cosh(k (z' + h)) / cosh(k h) (exp(k z') in deep water) of the depth below the surface
    z' = z - z_wl: returns f at the keel, Z0 = int f dz and Z1 = int z f dz over the draft (body z).
    Written with decaying exponentials only, so that deep water (h = inf) and k h > 700 are exact."""
    T = draft
    h = np.inf if depth is None else float(depth)
    D = 1.0 + np.exp(-2.0 * k * h)
    far = np.exp(-k * (2.0 * h - T))
    c_T = (np.exp(-k * T) + far) / D            # cosh(k (h - T)) / cosh(k h)
    s_T = (np.exp(-k * T) - far) / D            # sinh(k (h - T)) / cosh(k h)
    th = np.tanh(k * h)
    Z0 = (th - s_T) / k
    Zp = -1.0 / k ** 2 + T * s_T / k + c_T / k ** 2   # int z' f dz' over [-T, 0]
    return c_T, Z0, Zp + z_wl * Z0


def froude_krylov_box(omega, heading, length, beam, draft, kg, rho=1025.0, g=9.81, depth=None):
    """Froude-Krylov force and moment per unit wave amplitude on a box hull, X (N, 6) complex:
    X = -int p n dS over the five wetted faces (n outward), moments about the COG, for the incident
    pressure p = rho g f(z') exp(-i k (x cos beta + y sin beta)) of a wave eta = cos(w t) at the origin.

    The box spans x in [-L/2, L/2], y in [-B/2, B/2], and from the keel z = -kg up to the waterline
    z = draft - kg in the vessel frame (COG at the origin, centred in plan). In long waves the roll
    moment tends to rho g V GM_T k sin(beta) (the wave slope times the restoring), which a test checks."""
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    k = wavenumber(w, g, depth)
    kx, ky = k * np.cos(heading), k * np.sin(heading)
    cL, cB = 0.5 * length, 0.5 * beam
    Ex0, Ex1, Ey0, Ey1 = _e0(kx, cL), _e1(kx, cL), _e0(ky, cB), _e1(ky, cB)
    fb, Z0, Z1 = _vertical(k, draft, draft - kg, depth)
    exp_, exm = np.exp(-1j * kx * cL), np.exp(1j * kx * cL)     # exp(-i kx x) at x = +L/2, -L/2
    eyp, eym = np.exp(-1j * ky * cB), np.exp(1j * ky * cB)
    X = np.zeros((w.size, 6), dtype=complex)
    # bottom, n = -e_z, r x n = (-y, x, 0)
    X[:, 2] += fb * Ex0 * Ey0
    X[:, 3] += fb * Ex0 * Ey1
    X[:, 4] -= fb * Ex1 * Ey0
    # sides y = +-B/2, n = +-e_y, r x n = +-(-z, 0, x)
    X[:, 1] += -(eyp - eym) * Ex0 * Z0
    X[:, 3] += (eyp - eym) * Ex0 * Z1
    X[:, 5] += -(eyp - eym) * Ex1 * Z0
    # ends x = +-L/2, n = +-e_x, r x n = +-(0, z, -y)
    X[:, 0] += -(exp_ - exm) * Ey0 * Z0
    X[:, 4] += -(exp_ - exm) * Ey0 * Z1
    X[:, 5] += (exp_ - exm) * Ey1 * Z0
    return rho * g * X


def box_hydrostatics(length, beam, draft, kg):
    """Closed forms for a box: displaced volume, waterplane area, GM_T = KB + BM_T - KG and
    GM_L = KB + BM_L - KG (BM_T = B^2 / (12 T), BM_L = L^2 / (12 T))."""
    V = length * beam * draft
    kb = 0.5 * draft
    return {"waterplane_area": length * beam, "displaced_volume": V,
            "gm_t": kb + beam ** 2 / (12.0 * draft) - kg, "gm_l": kb + length ** 2 / (12.0 * draft) - kg}


# --------------------------------------------------------------------------------------------
# The traced part: excitation inside the step


class Excitation(eqx.Module):
    """First-order wave forces as a known function of time: F_j(t) = r(t) height sum_i
    amp_ji cos(w_i t + phase_ji), rows in the residual's frame (translations inertial, rotations
    body; equal at small motions about the initial attitude). `height` is the scene's amplitude
    (regular) or Hs (JONSWAP): the forces are linear in it, so it may be a traced parameter."""
    omega: jax.Array      # (N,)
    amp: jax.Array        # (6, N) per unit `height`
    phase: jax.Array      # (6, N)
    height: jax.Array     # ()
    ramp: float = eqx.field(static=True, default=0.0)

    def force(self, t):
        F = self.height * jnp.sum(self.amp * jnp.cos(self.omega[None, :] * t + self.phase), axis=1)
        if self.ramp > 0:
            F = F * jnp.where(t < self.ramp, 0.5 * (1.0 - jnp.cos(jnp.pi * jnp.clip(t, 0.0, self.ramp) / self.ramp)), 1.0)
        return F


def make_excitation(waves, X, height) -> Excitation:
    """From the components of `waves` and X (N, 6): the force of each component per unit `height`."""
    c = components(waves)
    h0 = waves.amplitude if waves.type == "regular" else waves.hs
    a = c.amplitude / h0
    amp = (np.abs(X) * a[:, None]).T
    phase = (np.angle(X) + c.phase[:, None]).T
    return Excitation(jnp.asarray(c.omega), jnp.asarray(amp), jnp.asarray(phase), jnp.asarray(height, dtype=float),
                      ramp=float(waves.ramp))


__all__ = ["DOFS", "Components", "Excitation", "box_hydrostatics", "components", "elevation", "froude_krylov_box",
           "jonswap", "make_excitation", "ramp_factor", "wavenumber"]
