"""An independent fully nonlinear potential-flow reference for two-dimensional sloshing in a
rectangular tank moved along its length: the high-order spectral (HOS) method of Dommermuth & Yue
(1987, J. Fluid Mech. 184) and West et al. (1987, J. Geophys. Res. 92), in the tank's frame.

It shares nothing with jaxslosh's multimodal liquid but the physics: the unknowns are the surface
elevation eta(x, t) and the velocity potential on the surface psi(x, t) on a grid (Zakharov's form)

    eta_t = -eta_x psi_x + (1 + eta_x^2) W
    psi_t = -g eta - x a(t) - psi_x^2 / 2 + (1 + eta_x^2) W^2 / 2

with a(t) the tank's acceleration along x and W the vertical velocity at the surface, found by the
HOS perturbation series of order M: the potential is a sum of cos(k_n x) cosh(k_n (z + h)) /
cosh(k_n h), k_n = n pi / L (no flux through the walls and the bottom), each order's boundary value
on z = 0 from Taylor series of the lower orders about z = 0. Cosine transforms on a grid padded for
the products, a sharp low-pass filter on the carried modes, classical Runge-Kutta in time."""
from __future__ import annotations

import math

import numpy as np
from scipy.fft import dct, idct, idst


def hos_tank(L, h, g, acceleration, t_end, dt, x_probe, modes=16, order=4, pad=4):
    """(t, elevation at x_probe) of the liquid of depth h in a tank of length L, at rest at t = 0,
    whose walls move along x with the acceleration `acceleration(t)` (m/s^2)."""
    nq = pad * modes + 1                                     # DCT-I nodes, walls included
    x = np.linspace(0.0, L, nq)
    k = np.arange(nq) * np.pi / L
    th = np.tanh(k * h)
    carried = np.exp(-36.0 * (np.arange(nq) / modes) ** 36) * (np.arange(nq) < modes)

    def coef(f):          # grid values -> cosine coefficients (c_0 / 2 + sum c_n cos(k_n x))
        return dct(f, type=1) / (nq - 1)

    def grid(c):
        return idct(c * (nq - 1), type=1)

    def dz(c, j):         # j-th z-derivative at z = 0 of the potential whose z = 0 values are c
        return c * k ** j * (th if j % 2 else 1.0)

    def dx(c):            # x-derivative on the grid (a sine series: zero at the walls)
        out = np.zeros(nq)
        out[1:-1] = idst(-(c * k)[1:-1] * (nq - 1), type=1)
        return out

    def vertical_velocity(eta, psi):
        orders = [coef(psi) * carried]
        for m in range(2, order + 1):
            f = -sum(eta ** j / math.factorial(j) * grid(dz(orders[m - 1 - j], j)) for j in range(1, m))
            orders.append(coef(f) * carried)
        return sum(eta ** j / math.factorial(j) * grid(dz(orders[m - 1], j + 1))
                   for m in range(1, order + 1) for j in range(order - m + 1))

    def rates(t, eta, psi):
        ex, px = dx(coef(eta) * carried), dx(coef(psi) * carried)
        W = vertical_velocity(eta, psi)
        deta = -ex * px + (1.0 + ex ** 2) * W
        dpsi = -g * eta - x * acceleration(t) - 0.5 * px ** 2 + 0.5 * (1.0 + ex ** 2) * W ** 2
        return np.stack([grid(coef(deta) * carried), grid(coef(dpsi) * carried)])

    probe = np.cos(k * x_probe) * np.where(np.arange(nq) == 0, 0.5, 1.0)
    y = np.zeros((2, nq))
    steps = int(round(t_end / dt))
    out = np.zeros(steps + 1)
    for i in range(steps):
        t = i * dt
        k1 = rates(t, *y)
        k2 = rates(t + 0.5 * dt, *(y + 0.5 * dt * k1))
        k3 = rates(t + 0.5 * dt, *(y + 0.5 * dt * k2))
        k4 = rates(t + dt, *(y + dt * k3))
        y = y + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        out[i + 1] = probe @ (coef(y[0]) * carried)
    return np.arange(steps + 1) * dt, out
