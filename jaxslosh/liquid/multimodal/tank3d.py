"""The multimodal liquid in three dimensions: a box tank's waves across its whole base (square or
rectangular, swirl included) and an upright circular cylinder's, after the same Bateman-Luke
variational principle and general (Lukovsky-type) modal system as the two-dimensional tank
(liquid/multimodal/term.py; Faltinsen, Rognebakke & Timokha 2003, J. Fluid Mech. 487, square base;
Faltinsen, Lukovsky & Timokha 2016, J. Fluid Mech. 804, upright circular cylinder; Faltinsen & Timokha,
Sloshing, 2009, chapters 7 to 9).

Tank-local coordinates: (x, y) on the base (from the inner min corner), z above the bottom, the free
surface

    H(x, y, t) = h + sum_n beta_n(t) f_n(x, y)

with f_n the base's natural modes (liquid/multimodal/modes.py), and the potential of the liquid's
velocity relative to the tank

    phi = sum_n R_n(t) f_n(x, y) cosh(k_n z) / cosh(k_n h).

The kinematic condition projected on each mode, dA_n/dt = sum_k A_nk R_k + sum_l Bw_nl omega_l
(A_n the integral of phi_n over the liquid, A_nk of grad phi_n . grad phi_k, Bw_nl the flux of the
vortical flows below), gives R; the kinetic energy is then exactly quadratic in the body's velocities
and beta_dot, and the modal system is its Lagrangian's with no ordering of the amplitudes. Every
integral is evaluated at every beta by quadrature over the instantaneous liquid: Gauss over the base
times Gauss through the depth (column height H).

A particle's velocity is V_b + omega x r + grad phi + sum_l omega_l w_l: w_l the flow relative to the
tank that a unit rotation rate about axis l adds so that the absolute motion stays irrotational
(Kelvin; the Stokes-Joukowski potential of the closed tank less the rigid rotation). The liquid's
momentum relative to the tank is the rate of its first moment (Reynolds), exact in beta, as in the
two-dimensional tank. The equations are Kirchhoff's, as there (`rows`).
"""
from __future__ import annotations

import functools
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .columns import column_values
from .modes import DiskBase, RectangleBase

#: Gauss points through the depth
NZ = 12


class Integrals3(NamedTuple):
    """The liquid's geometric integrals at one beta (per unit density), tank-local r from the corner."""
    An: jax.Array      # (N,) integral of phi_n
    Jn: jax.Array      # (N, N) dA_n / dbeta_j
    Ank: jax.Array     # (N, N) integral of grad phi_n . grad phi_k
    grad: jax.Array    # (N, 3) integral of grad phi_n
    rxg: jax.Array     # (N, 3) integral of r x grad phi_n
    Bw: jax.Array      # (N, 3) integral of grad phi_n . w_l
    W: jax.Array       # (3, 3) integral of w_l . w_m
    wint: jax.Array    # (3, 3) integral of w_l (rows l)
    rxw: jax.Array     # (3, 3) integral of r x w_l (rows l)
    vol: jax.Array     # integral of 1
    m1: jax.Array      # (3,) integral of r
    m2: jax.Array      # (3, 3) integral of r r^T
    dm1: jax.Array     # (3, N) d(integral of r) / dbeta


class ModalTank3D(eqx.Module):
    """One tank's liquid on N modes of its base (module docstring): a box or an upright cylinder."""
    size: jax.Array       # (2,) the base's extents (L, B; a cylinder's diameter twice), m
    h: jax.Array          # fill depth, m
    D: jax.Array          # tank height, m (the vortical flows' closed tank)
    rho: jax.Array        # liquid density, kg/m^3
    origin: jax.Array     # (3,) the tank's inner min corner in the vessel frame
    k: jax.Array          # (N,) wavenumbers
    xq: jax.Array         # (Q,) base quadrature points
    yq: jax.Array
    wq: jax.Array         # (Q,) their weights
    F: jax.Array          # (Q, N) the modes at the points
    Fx: jax.Array         # (Q, N) their x and y derivatives
    Fy: jax.Array
    norms: jax.Array      # (N,) integral of f_n^2 over the base
    sq: jax.Array         # (NZ,) points on [0, 1] through the depth
    ws: jax.Array         # (NZ,) their weights
    vq: tuple             # the vortical flows' factors at the points' columns (base.vortical_columns)
    base: object = eqx.field(static=True)    # RectangleBase | DiskBase (liquid/multimodal/modes.py)
    modes: tuple = eqx.field(static=True)    # box (i, j); cylinder (m, s, cos 0 | sin 1)

    @property
    def n(self) -> int:
        return int(self.k.shape[0])

    @property
    def mass(self):
        return self.rho * self.h * jnp.sum(self.wq)

    def omega_linear(self, g):
        """(N,) the linear natural frequencies sqrt(g k tanh(k h)), rad/s."""
        return jnp.sqrt(g * self.k * jnp.tanh(self.k * self.h))

    def modal_mass(self):
        """(N,) rho |f_n|^2 / (k tanh kh): each modal row's mass at rest (kg per m of beta)."""
        return self.rho * self.norms / (self.k * jnp.tanh(self.k * self.h))

    def surface_rows(self, x, y) -> np.ndarray:
        """(P, N): the free-surface elevation at tank-local points per unit beta (numpy, build time)."""
        return self.base.values(self.modes, x, y)[0]

    def vortical(self, x, y, z):
        return self.base.vortical(self.D, x, y, z)

    # ------------------------------------------------------------------ integrals
    def integrals(self, beta) -> Integrals3:
        """The integrals at beta: the columns' sums (`_columns`, their derivatives in beta column by
        column: liquid/multimodal/columns.py), scaled by the modes' cosh(k h); the moments of the
        liquid's volume, simple sums over the base."""
        k, w, F = self.k, self.wq, self.F
        H = self.h + F @ beta                                              # (Q,)
        geo = (k, w, F, self.Fx, self.Fy, self.xq, self.yq, self.sq, self.ws, self.vq, self.D)
        a, *sums = column_values(_column_fn(self.base), 0, H, geo)
        An, Ank, grad, rxg, Bw, W, wint, rxw = (jnp.sum(c, axis=0) for c in sums)
        ch = jnp.cosh(k * self.h)
        Jn = jnp.einsum("qn,qj->nj", a, F) / ch[:, None]
        x, y = self.xq, self.yq
        m1 = jnp.array([w @ (x * H), w @ (y * H), w @ (0.5 * H ** 2)])
        hh = 0.5 * H ** 2
        m2 = jnp.array([[w @ (x * x * H), w @ (x * y * H), w @ (x * hh)],
                        [w @ (x * y * H), w @ (y * y * H), w @ (y * hh)],
                        [w @ (x * hh), w @ (y * hh), w @ (H ** 3 / 3.0)]])
        dm1 = jnp.stack([(w * x) @ F, (w * y) @ F, (w * H) @ F])
        return Integrals3(An / ch, Jn, Ank / jnp.outer(ch, ch), grad / ch[:, None], rxg / ch[:, None],
                          Bw / ch[:, None], W, wint, rxw, w @ H, m1, m2, dm1)

    def moments(self, I: Integrals3):
        """(first moment S (3,), second moment J = sum m x x^T (3, 3)) of the liquid in the vessel frame."""
        o, m1 = self.origin, I.m1
        J = I.m2 + jnp.outer(o, m1) + jnp.outer(m1, o) + I.vol * jnp.outer(o, o)
        return self.rho * (m1 + I.vol * o), self.rho * J

    def rates(self, I: Integrals3, beta_dot, omega=np.zeros(3)):
        """The potential's amplitudes R from the projected kinematic condition. (The default is a
        NumPy constant: a jnp one compiled two programs at every import of the package.)"""
        return jnp.linalg.solve(I.Ank, I.Jn @ beta_dot - I.Bw @ omega)

    def mass_matrix(self, beta):
        """(6 + N, 6 + N): the kinetic energy is exactly 1/2 v^T M(beta) v in v = (V_b, omega, beta_dot)."""
        I = self.integrals(beta)
        S, J = self.moments(I)
        rho, o = self.rho, self.origin
        m = rho * I.vol
        P = rho * I.dm1                                              # relative momentum per beta_dot
        Hn = (I.rxg + jnp.cross(o, I.grad)).T                        # (3, N) integral of r x grad phi_n
        Hw = (I.rxw + jnp.cross(o, I.wint)).T                        # (3, 3) integral of r x w_l
        AiJ = jnp.linalg.solve(I.Ank, I.Jn)
        AiB = jnp.linalg.solve(I.Ank, I.Bw)
        Cw = Hw - Hn @ AiB
        Iw = jnp.trace(J) * jnp.eye(3) - J + rho * (Cw + Cw.T + I.W - I.Bw.T @ AiB)
        Hb = rho * Hn @ AiJ
        Mbb = rho * I.Jn.T @ AiJ
        Sx = jnp.array([[0.0, -S[2], S[1]], [S[2], 0.0, -S[0]], [-S[1], S[0], 0.0]])
        top = jnp.concatenate([m * jnp.eye(3), -Sx, P], axis=1)
        mid = jnp.concatenate([Sx, 0.5 * (Iw + Iw.T), Hb], axis=1)
        bot = jnp.concatenate([P.T, Hb.T, 0.5 * (Mbb + Mbb.T)], axis=1)
        return jnp.concatenate([top, mid, bot], axis=0)

    def kinetic(self, Vb, omega, beta, beta_dot):
        """The liquid's kinetic energy (J) for the body-frame velocity V_b of the vessel's origin and omega."""
        v = jnp.concatenate([Vb, omega, beta_dot])
        return 0.5 * v @ (self.mass_matrix(beta) @ v)

    def first_moment(self, beta):
        return self.moments(self.integrals(beta))[0]

    def rest_moment(self):
        return self.first_moment(jnp.zeros(self.n))

    def potential(self, beta, g_b):
        """The gravity potential of the liquid's displacement from rest: -g_b . (S(beta) - S0)."""
        return -g_b @ (self.first_moment(beta) - self.rest_moment())

    def rows(self, Vb, omega, beta, beta_dot, Vb_dot, alpha, beta_dd, g_b):
        """Kirchhoff's equations (liquid/multimodal/term.py): (translation rows (body), rotation rows (body),
        modal rows), from the momenta p = M(beta) v and their rates M v_dot + (dM/dt) v."""
        v = jnp.concatenate([Vb, omega, beta_dot])
        M, dM = jax.jvp(self.mass_matrix, (beta,), (beta_dot,))
        p = M @ v
        dp = M @ jnp.concatenate([Vb_dot, alpha, beta_dd]) + dM @ v
        dT = jax.grad(lambda be: 0.5 * v @ (self.mass_matrix(be) @ v))(beta)
        I = self.integrals(beta)
        dS = self.moments(I)[0] - self.rest_moment()
        P_lin, Hm = p[:3], p[3:6]
        f = dp[:3] + jnp.cross(omega, P_lin)
        m = dp[3:6] + jnp.cross(omega, Hm) + jnp.cross(Vb, P_lin) - jnp.cross(dS, g_b)
        return f, m, dp[6:] - dT - g_b @ (self.rho * I.dm1)           # dV/dbeta = -g_b . dS/dbeta


def _columns(base, H, geo):
    """What each column of the liquid holds (the column axis first; ModalTank3D.integrals sums them): the
    integrals of the potential's modes phi_n = f_n cosh(k_n z) (cosh(k_n h) left out: the caller
    scales), their gradients and the vortical flows w_l over the column of height H_q, by Gauss
    through the depth. `a` gives J_nj = sum_q a_qn F_qj (kept by column)."""
    k, w, F, Fx, Fy, x, y, sq, ws, vq, D = geo
    a = w[:, None] * F * jnp.cosh(H[:, None] * k)
    An = w[:, None] * F * jnp.sinh(H[:, None] * k) / k
    u = H[:, None] * sq[None, :]                                       # (Q, S)
    wu = w[:, None] * H[:, None] * ws[None, :]
    C = jnp.cosh(u[..., None] * k)                                     # (Q, S, N)
    S = jnp.sinh(u[..., None] * k)
    g = jnp.stack([Fx[:, None, :] * C, Fy[:, None, :] * C, k * F[:, None, :] * S], axis=-1)
    r = jnp.stack([jnp.broadcast_to(x[:, None], u.shape), jnp.broadcast_to(y[:, None], u.shape), u], -1)
    wl = base.vortical_at(vq, D, u)                                    # (3, Q, S, 3)
    return (a, An, jnp.einsum("qs,qsnc,qsmc->qnm", wu, g, g), jnp.einsum("qs,qsnc->qnc", wu, g),
            jnp.einsum("qs,qsnc->qnc", wu, jnp.cross(r[:, :, None, :], g)),
            jnp.einsum("qs,qsnc,lqsc->qnl", wu, g, wl), jnp.einsum("qs,lqsc,mqsc->qlm", wu, wl, wl),
            jnp.einsum("qs,lqsc->qlc", wu, wl), jnp.einsum("qs,lqsc->qlc", wu, jnp.cross(r[None], wl)))


@functools.lru_cache(maxsize=None)
def _column_fn(base):
    """`_columns` of one base (one function per base: the derivative rule's static argument)."""
    return functools.partial(_columns, base)


def _tank(base, h, D, rho, origin, modes) -> ModalTank3D:
    x, y, w = base.quadrature(modes)
    F, Fx, Fy = base.values(modes, x, y)
    sg, sw = np.polynomial.legendre.leggauss(NZ)
    f = lambda a: jnp.asarray(a, dtype=float)  # noqa: E731
    return ModalTank3D(size=f(base.size), h=f(h), D=f(D), rho=f(rho), origin=f(origin),
                       k=f(base.wavenumbers(modes)), xq=f(x), yq=f(y), wq=f(w), F=f(F), Fx=f(Fx), Fy=f(Fy),
                       norms=f(w @ F ** 2), sq=f(0.5 * (sg + 1.0)), ws=f(0.5 * sw),
                       vq=base.vortical_columns(f(D), f(x)[:, None], f(y)[:, None]), base=base, modes=tuple(modes))


def box_tank3d(L, B, h, rho, origin, n_modes: int = 0, D=None, modes=None) -> ModalTank3D:
    """A box tank's liquid on its base's lowest n_modes modes (whole degenerate groups), or on the
    given (i, j) modes."""
    return base_tank3d(RectangleBase(float(L), float(B)), h, rho, origin, n_modes, D, modes)


def cylinder_tank(R, h, rho, origin, n_modes: int = 0, D=None, modes=None) -> ModalTank3D:
    """An upright circular cylinder's liquid (radius R; origin: the min corner of its bounding box) on
    its lowest n_modes modes (whole cos/sin pairs), or on the given (m, s, c) modes."""
    return base_tank3d(DiskBase(float(R)), h, rho, origin, n_modes, D, modes)


def base_tank3d(base, h, rho, origin, n_modes: int = 0, D=None, modes=None) -> ModalTank3D:
    """The liquid of a tank standing on `base` (RectangleBase, DiskBase) on its lowest n_modes modes
    (whole degenerate groups), or on the given modes."""
    modes = base.lowest(n_modes) if modes is None else tuple(tuple(m) for m in modes)
    return _tank(base, h, 2.0 * h if D is None else D, rho, origin, modes)
