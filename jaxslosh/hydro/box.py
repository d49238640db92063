"""A box hull in closed form: its hydrostatics and the Froude-Krylov forces of linear waves on its
wetted faces (the conventions of `spectra.py`: forces per unit wave amplitude as complex numbers,
F_j(t) = a |X_j| cos(w t + eps + arg X_j))."""
from __future__ import annotations


import numpy as np

from .spectra import wavenumber


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
