"""The natural sloshing modes of a box tank's rectangular base and an upright circular cylinder's disk,
the quadrature of those bases, and the vortical flows that keep a rotating tank's liquid irrotational:
the pieces of the three-dimensional multimodal liquid (liquid/multimodal/tank3d.py).

A base's surface modes f_n(x, y) are the Neumann eigenfunctions of its Laplacian with zero mean (the
volume is conserved exactly), in tank-local coordinates from the inner min corner:

* box L x B: f = cos(i pi x / L) cos(j pi y / B), k = pi sqrt((i / L)^2 + (j / B)^2), (i, j) != (0, 0);
* cylinder of radius R (centre (R, R)): f = J_m(k r) / J_m(k R) (cos m theta | sin m theta), k R the
  n-th zero of J_m' (unit elevation at the wall).

A tank keeps its N lowest modes, completed to whole degenerate groups (the (1, 0), (0, 1) pair of a
square base, the cos and sin pair of a cylinder's m >= 1 modes): the swirling waves need both.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import jax.numpy as jnp
import numpy as np
from jax.scipy.special import i0e, i1e
from scipy import special

from ...staging import evaluated

#: terms of the vortical flows' series
SJ_TERMS = 24
#: relative tolerance of two modes' wavenumbers that makes them one degenerate group
DEGENERATE = 1e-9


def _lowest(cands, n):
    """The n lowest of (k, mode) candidates in order, completed to a whole degenerate group."""
    cands = sorted(cands, key=lambda c: c[0])
    out = cands[:n]
    while len(out) < len(cands) and abs(cands[len(out)][0] - out[-1][0]) <= DEGENERATE * out[-1][0]:
        out.append(cands[len(out)])
    return tuple(c[1] for c in out)


def box_modes(L: float, B: float, n: int) -> tuple:
    """The lowest n modes (i, j) of an L x B base (whole degenerate groups)."""
    top = n + 2
    cands = [(np.pi * np.hypot(i / L, j / B), -i, (i, j)) for i in range(top) for j in range(top) if i + j > 0]
    cands = sorted(cands)
    return _lowest([(c[0], c[2]) for c in cands], n)


def cylinder_modes(R: float, n: int) -> tuple:
    """The lowest n modes (m, s, c) of a disk of radius R: order m, the s-th zero of J_m', c = 0 for
    cos m theta, 1 for sin m theta (whole cos/sin pairs)."""
    top = n + 2
    cands = []
    for m in range(top):
        for s, z in enumerate(special.jnp_zeros(m, top), start=1):
            cands.append((z / R, (m, s, 0)))
            if m > 0:
                cands.append((z / R, (m, s, 1)))
    cands.sort(key=lambda c: (c[0], c[1][2]))
    return _lowest(cands, n)


@dataclass(frozen=True)
class RectangleBase:
    """The L x B base of a box tank: modes (i, j), f = cos(i pi x / L) cos(j pi y / B)."""
    L: float
    B: float
    name: ClassVar[str] = "box"

    @property
    def size(self) -> tuple:
        return (self.L, self.B)

    def lowest(self, n: int) -> tuple:
        return box_modes(self.L, self.B, n)

    def wavenumbers(self, modes) -> np.ndarray:
        return np.array([np.pi * np.hypot(i / self.L, j / self.B) for i, j in modes])

    def values(self, modes, x, y):
        """(f, df/dx, df/dy), each (P, N), of the base's modes at tank-local points x, y (P,)."""
        x, y = np.asarray(x, float).ravel(), np.asarray(y, float).ravel()
        i = np.array([m[0] for m in modes]) * np.pi / self.L
        j = np.array([m[1] for m in modes]) * np.pi / self.B
        cx, sx = np.cos(np.outer(x, i)), np.sin(np.outer(x, i))
        cy, sy = np.cos(np.outer(y, j)), np.sin(np.outer(y, j))
        return cx * cy, -i * sx * cy, -j * cx * sy

    def quadrature(self, modes):
        """(x, y, w): Gauss-Legendre in x and y."""
        top = max(max(i for i, _ in modes), max(j for _, j in modes))
        n = max(12, 4 * top + 4)
        g, gw = np.polynomial.legendre.leggauss(n)
        xs, xw = 0.5 * self.L * (g + 1.0), 0.5 * self.L * gw
        ys, yw = 0.5 * self.B * (g + 1.0), 0.5 * self.B * gw
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        return X.ravel(), Y.ravel(), np.outer(xw, yw).ravel()

    def vortical(self, D, x, y, z):
        return box_vortical(self.L, self.B, D, x, y, z)

    def vortical_columns(self, D, x, y):
        """What `vortical_at` needs of the points (x, y) (formed once at a tank's quadrature points)."""
        return (jnp.asarray(x, dtype=float), jnp.asarray(y, dtype=float))

    def vortical_at(self, columns, D, z):
        """The vortical flows at heights z over the points of `vortical_columns`."""
        return box_vortical(self.L, self.B, D, *columns, z)

    def rim(self, n: int):
        """(x, y): n points round the walls, the corners among them."""
        L, B = self.L, self.B
        q = n // 4
        s = np.arange(q) / q
        x = np.concatenate([L * s, np.full(q, L), L * (1 - s), np.zeros(n - 3 * q)])
        y = np.concatenate([np.zeros(q), B * s, np.full(q, B), B * (1 - np.arange(n - 3 * q) / (n - 3 * q))])
        return x, y


@dataclass(frozen=True)
class DiskBase:
    """The disk of radius R (centre (R, R)) of an upright cylinder: modes (m, s, c),
    f = J_m(k r) / J_m(k R) (cos m theta | sin m theta)."""
    R: float
    name: ClassVar[str] = "cylinder"

    @property
    def size(self) -> tuple:
        return (2.0 * self.R, 2.0 * self.R)

    def lowest(self, n: int) -> tuple:
        return cylinder_modes(self.R, n)

    def wavenumbers(self, modes) -> np.ndarray:
        return np.array([special.jnp_zeros(m, s)[-1] / self.R for m, s, _ in modes])

    def values(self, modes, x, y):
        """(f, df/dx, df/dy), each (P, N), of the base's modes at tank-local points x, y (P,)."""
        x, y = np.asarray(x, float).ravel(), np.asarray(y, float).ravel()
        k = self.wavenumbers(modes)
        R = self.R
        xc, yc = x - R, y - R
        r, th = np.hypot(xc, yc), np.arctan2(yc, xc)
        m = np.array([md[0] for md in modes])
        sin_form = np.array([md[2] == 1 for md in modes])
        kr = np.outer(r, k)
        norm = special.jv(m, k * R)
        Jm, dJ = special.jv(m, kr) / norm, k * special.jvp(m, kr) / norm
        ang = np.where(sin_form, np.sin(np.outer(th, m)), np.cos(np.outer(th, m)))
        dang = m * np.where(sin_form, np.cos(np.outer(th, m)), -np.sin(np.outer(th, m)))
        # J_m(k r) / r is finite at the centre (zero unless m = 1, where the mode's gradient is k / 2 / norm)
        Jr = np.where(kr > 1e-12, special.jv(m, kr) / np.maximum(r, 1e-300)[:, None],
                      np.where(m == 1, 0.5 * k, 0.0)) / norm
        f, fr, ft = Jm * ang, dJ * ang, Jr * dang            # ft: (1 / r) df / dtheta
        c, s = np.cos(th)[:, None], np.sin(th)[:, None]
        return f, fr * c - ft * s, fr * s + ft * c

    def quadrature(self, modes):
        """(x, y, w): Gauss-Jacobi in r (the weight r of the disk's area exact: Gauss for the
        polynomials in r that r dr integrates), the trapezoidal rule in theta (exact for trigonometric
        polynomials). The counts give the box's accuracy (`RectangleBase.quadrature`) on as many
        modes, measured against 40 x 96 points at random surfaces of 3 and 10 cm in a 1.2 m tank with
        0.6 m of liquid (docs/benchmarks.md, "The multimodal upright cylinder"): the mass matrix's
        modal block within 4e-8 on 7 modes (the box's 1.5e-7), 2e-6 on 16 (the box's 4e-6). Fewer
        points around lose it (20 points on 7 modes: 5e-7), more along the radius gain nothing there."""
        R = self.R
        mmax = max(m for m, _, _ in modes)
        smax = max(s for _, s, _ in modes)
        g, gw = special.roots_jacobi(max(8, 2 * (mmax + smax)), 0.0, 1.0)     # weight (1 + g) on [-1, 1]
        r, rw = 0.5 * R * (g + 1.0), (0.5 * R) ** 2 * gw
        nt = max(24, 8 * mmax)
        th = 2.0 * np.pi * np.arange(nt) / nt
        Rr, T = np.meshgrid(r, th, indexing="ij")
        return ((R + Rr * np.cos(T)).ravel(), (R + Rr * np.sin(T)).ravel(),
                np.outer(rw, np.full(nt, 2 * np.pi / nt)).ravel())

    def vortical(self, D, x, y, z):
        return cylinder_vortical(self.R, D, x, y, z)

    def vortical_columns(self, D, x, y):
        """The flows' radial factors at the points (x, y) (`cylinder_columns`: Bessel functions, formed
        once at a tank's quadrature points, never in a step; one compiled program, staging.py
        `evaluated`, where op by op they compiled some 30)."""
        return _columns_program(self.R, D, x, y)

    def vortical_at(self, columns, D, z):
        """The vortical flows at heights z over the points of `vortical_columns`."""
        return cylinder_flow(columns, D, z)

    def rim(self, n: int):
        """(x, y): n points round the wall."""
        th = 2.0 * np.pi * np.arange(n) / n
        return self.R + self.R * np.cos(th), self.R + self.R * np.sin(th)


# ---------------------------------------------------------------------------------- vortical flows
def odd_powers(a, m: int):
    """(..., m): a, a^3, ..., a^(2m - 1), by doubling: a few products in place of m exponentials or
    sines (exp((2k + 1) x) and exp(i (2k + 1) x) from exp(x), exp(i x)); relative error a few m eps."""
    p, r = a[..., None], a * a
    while p.shape[-1] < m:
        p = jnp.concatenate([p, p * r[..., None]], axis=-1)
        r = r * r
    return p[..., :m]


def _section(length, depth, xi, eta):
    """The vortical flow (w1, w2) of a unit rotation of a length x depth rectangle about its normal,
    at (xi, eta) from its centre: curl w = -2, no flux through its sides; with w = grad chi + (0, 2 xi),
    chi = sum_m c_m sin(k_m xi) sinh(k_m eta) / (k_m cosh(k_m d)), k_m = (2m + 1) pi / length, c_m the
    sine series of -2 xi (the Stokes-Joukowski potential less the rigid rotation). The series' terms
    are odd powers of their first (`odd_powers`)."""
    a, d = 0.5 * length, 0.5 * depth
    m = jnp.arange(SJ_TERMS)
    k0 = jnp.pi / (2 * a)
    k = (2 * m + 1) * k0
    c = -2.0 * (2.0 / a) * (-1.0) ** m / k ** 2 / (1.0 + jnp.exp(-2.0 * k * d))
    eta, xi = jnp.asarray(eta), jnp.asarray(xi)
    e = odd_powers(jnp.exp(-k0 * (d - eta)), SJ_TERMS)            # exp(-k (d -+ eta)): no overflow, |eta| <= d
    f = odd_powers(jnp.exp(-k0 * (d + eta)), SJ_TERMS)
    z = odd_powers(jnp.exp(1j * k0 * xi), SJ_TERMS)               # cos(k xi) + i sin(k xi)
    sh, ch = e - f, e + f
    return jnp.sum(c * z.real * sh, axis=-1), 2.0 * xi + jnp.sum(c * z.imag * ch, axis=-1)


def box_vortical(L, B, D, x, y, z):
    """(3, ..., 3): the flow relative to an L x B x D box that a unit rotation rate about x, y, z (rows)
    adds so that the liquid's absolute motion stays irrotational (each the two-dimensional flow of the
    section across that axis: the rigid rotation's flux through the walls of the box is planar)."""
    x, y, z = jnp.broadcast_arrays(jnp.asarray(x), jnp.asarray(y), jnp.asarray(z))
    zero = jnp.zeros_like(x)
    a1, a2 = _section(B, D, y - 0.5 * B, z - 0.5 * D)             # about x: (y, z) components, reversed
    b1, b2 = _section(L, D, x - 0.5 * L, z - 0.5 * D)             # about y: (x, z) components
    c1, c2 = _section(L, B, x - 0.5 * L, y - 0.5 * B)             # about z: (x, y) components, reversed
    return jnp.stack([jnp.stack([zero, -a1, -a2], -1), jnp.stack([b1, zero, b2], -1),
                      jnp.stack([-c1, -c2, zero], -1)])


def cylinder_vortical(R, D, x, y, z):
    """(3, ..., 3): the vortical flows of an upright closed cylinder (radius R, height D; rows: rotation
    about x, y, z). About its axis the liquid stays at rest: w = -e_z x r. About x, w = (0, 2 eta, 0) +
    grad(sin theta G), about y w = (-2 eta, 0, 0) - grad(cos theta G), G = sum_m c_m I_1(mu_m r)
    sin(mu_m eta), mu_m = (2m + 1) pi / D, c_m mu_m I_1'(mu_m R) the sine series of -2 eta (no flux
    through the wall; eta from mid-height)."""
    x, y, z = jnp.broadcast_arrays(jnp.asarray(x), jnp.asarray(y), jnp.asarray(z))
    return cylinder_flow(cylinder_columns(R, D, x, y), D, z)


def cylinder_columns(R, D, x, y):
    """What the cylinder's vortical flows (`cylinder_vortical`) hold at points (x, y) of its base that
    does not depend on the height: the series' radial factors (Bessel functions of mu_m r, (..., SJ_TERMS)
    each) and the point's place. A tank forms them once at its quadrature points' columns (build time):
    the flows at the liquid's depth points are then a sine series in eta alone."""
    x, y = jnp.broadcast_arrays(jnp.asarray(x, dtype=float), jnp.asarray(y, dtype=float))
    xc, yc = x - R, y - R
    r = jnp.hypot(xc, yc)
    rs = jnp.where(r > 0, r, 1.0)
    c, s = jnp.where(r > 0, xc / rs, 1.0), jnp.where(r > 0, yc / rs, 0.0)
    m = jnp.arange(SJ_TERMS)
    mu = (2 * m + 1) * jnp.pi / D
    b = -4.0 * (-1.0) ** m / (0.5 * D * mu ** 2)

    def i1pe(v):                       # exp(-v) I_1'(v)
        return i0e(v) - i1e(v) / v
    scale = jnp.exp(mu * (r[..., None] - R)) / i1pe(mu * R)
    mr = mu * r[..., None]
    mrs = jnp.where(mr > 0, mr, 1.0)
    I1r = jnp.where(mr > 0, i1e(mrs) / mrs, 0.5) * scale      # I_1(mu r) / (mu r), scaled
    return (xc, yc, c, s, b * jnp.where(mr > 0, i1pe(mrs), 0.5) * scale, b * I1r, b * I1r * mr)


_columns_program = evaluated(cylinder_columns)


def _odd_series(B, alpha, sign):
    """Clenshaw's recurrence for sum_m B_m t_m, t_m = sin or cos of (2m + 1) theta (t_(m+1) = alpha
    t_m - t_(m-1), alpha = 2 cos 2 theta): b_m = B_m + alpha b_(m+1) - b_(m+2), the sum sin(theta)
    (b_0 + b_1) for the sines (sign +1), cos(theta) (b_0 - b_1) for the cosines (sign -1); returned
    without that factor. B (..., M) broadcast against alpha's shape; elementwise steps, one fused
    loop for XLA."""
    b1 = b2 = jnp.zeros_like(alpha)
    for m in range(B.shape[-1] - 1, 0, -1):        # the series' terms (SJ_TERMS), not elements
        b1, b2 = B[..., m] + alpha * b1 - b2, b1
    return B[..., 0] + alpha * b1 - b2 + sign * b1


def cylinder_flow(columns, D, z):
    """`cylinder_vortical` at heights z of the columns (`cylinder_columns`, broadcast against z): the
    series in eta, sums of B_m sin(mu_m eta) or B_m cos(mu_m eta) with mu_m = (2m + 1) pi / D, by
    Clenshaw's recurrence (`_odd_series`: two sines per point, no sine per term)."""
    xc, yc, c, s, Br, Bq, Be = columns
    eta = jnp.asarray(z) - 0.5 * D
    th = (jnp.pi / D) * eta
    sin1, cos1 = jnp.sin(th), jnp.cos(th)
    alpha = 2.0 * (cos1 * cos1 - sin1 * sin1)                  # 2 cos(2 theta)
    Gr = sin1 * _odd_series(Br, alpha, +1.0)                   # dG / dr
    G_r = sin1 * _odd_series(Bq, alpha, +1.0)                  # G / r
    Ge = cos1 * _odd_series(Be, alpha, -1.0)                   # dG / deta
    xc, yc, c, s = jnp.broadcast_arrays(xc, yc, c, s, eta)[:4]
    zero = jnp.zeros_like(Gr)
    wx = jnp.stack([(Gr - G_r) * s * c, 2.0 * eta + Gr * s * s + G_r * c * c, s * Ge], -1)
    wy = jnp.stack([-2.0 * eta - Gr * c * c - G_r * s * s, -(Gr - G_r) * c * s, -c * Ge], -1)
    wz = jnp.stack([yc, -xc, zero], -1)
    return jnp.stack([wx, wy, wz])


def modal_modes(t) -> tuple:
    """The modes a multimodal tank runs on: cos(i pi x / L), i = 1..N, along a two-dimensional box
    ((i, 0) each); the base's lowest, completed to whole degenerate groups, in three dimensions
    (this module's bases, as build3d.py builds them)."""
    if t.flow != "3d":
        return tuple((i, 0) for i in range(1, t.modes + 1))
    return t.geometry.modal_base(RectangleBase, DiskBase).lowest(t.modes)
