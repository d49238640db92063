"""The multimodal liquid: nonlinear sloshing of a box tank's liquid in two-dimensional flow along the
tank's length (x), after the Bateman-Luke variational principle with the free surface and the
velocity potential both expanded in the tank's natural modes (Miles 1976, J. Fluid Mech. 75;
Faltinsen, Rognebakke, Lukovsky & Timokha 2000, J. Fluid Mech. 407, section 2, the general modal
system; Faltinsen & Timokha, Sloshing, 2009, chapter 7).

Tank-local coordinates: x in [0, L] along the length, u in [0, H(x)] above the bottom, the free
surface

    H(x, t) = h + zeta(x, t),   zeta = sum_i beta_i(t) cos(k_i x),   k_i = i pi / L,  i = 1..N

(each cosine has zero mean: the volume is conserved exactly), and the potential of the liquid's
velocity relative to the tank  phi = sum_n R_n(t) phi_n,  phi_n = cos(k_n x) cosh(k_n u) / cosh(k_n h)
(the natural modes: phi_n has no normal flux through the walls and the bottom). The kinematic free
surface condition, projected on each phi_n, is Faltinsen et al.'s  dA_n/dt = sum_k A_nk R_k  with
A_n = integral of phi_n over the liquid and A_nk = integral of grad phi_n . grad phi_k; so
R = A_nk^-1 (dA_n / d beta) beta_dot, and the liquid's kinetic energy is a function of beta,
beta_dot and the tank's velocities. The modal system used here is that Lagrangian's, the general
(Lukovsky-type) system truncated at N modes with no ordering of the amplitudes: it holds the
third-order (Moiseev-type) system of Faltinsen et al. 2000 and goes beyond it. The integrals are
evaluated exactly in beta at every step: in closed form through the depth, by Gauss quadrature along
the tank (`ModalTank.integrals`).

The tank moves with the vessel: a particle's velocity is V_b + omega x r + grad phi + q w (body
frame), with q = omega_y the pitch rate and w the vortical flow relative to the tank that keeps the
liquid's absolute motion irrotational (Kelvin; `ModalTank.vortical`, the Stokes-Joukowski potential
of the tank's section less its rigid rotation), as the finite-element liquid's rotation penalty keeps
it. Across the tank (roll, yaw) the liquid turns with the tank.

The equations are Kirchhoff's for the body's velocities (V_b = A^T V0, omega), modal coordinates inside:

    d/dt dT/dV_b + omega x dT/dV_b                           = F_b   (translation rows, then A F_b)
    d/dt dT/domega + omega x dT/domega + V_b x dT/dV_b       = M_b   (rotation rows)
    d/dt dT/dbeta_dot - dT/dbeta + dV/dbeta                  = 0     (modal rows)

with V = -g_b . (S(beta) - S0) (the frozen liquid's weight and its moment are the vessel's: the
same convention as the finite-element liquid). Past the method's range (crests higher than the N
modes resolve) the modal rows take the steep-wave damping of multimodal_steep.py, zero within it. The force and moment on the tank follow from the
liquid's momentum: they are the rigid rows.
"""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...staging import evaluated
from .columns import spd_inverse
from .modes import odd_powers

#: quadrature points along the tank (Gauss-Legendre; at least, and 8 per mode: the integrands hold
#: cos(k_2N x) exp(k_2N zeta)) and through the depth (the reference quadrature over the liquid)
NX, NZ = 48, 20
#: terms of the vortical flow's series (`ModalTank.vortical`)
SJ_TERMS = 40


def _vortical_tables(L, D, xq):
    """(Te, Tf), each (NX, SJ_TERMS, 5): the vortical series' coefficients at the quadrature points,
    multiplying exp(-kappa_m (D - H)) and exp(-kappa_m H) in chi, w_x, w_z - 2 xi, G_x and the
    depth primitive of sinh (`ModalTank._vortical_surface`; `vortical` sums the same series)."""
    a, d = 0.5 * L, 0.5 * D
    m = jnp.arange(SJ_TERMS)
    kap = (2 * m + 1) * jnp.pi / (2 * a)
    c = -2.0 * (2.0 / a) * (-1.0) ** m / kap ** 2 / (1.0 + jnp.exp(-2.0 * kap * d))
    xi = xq[:, None] - a
    Cm, Sm = jnp.cos(kap * xi), jnp.sin(kap * xi)
    sh = jnp.stack([Sm * c / kap, Cm * c, jnp.zeros_like(Cm), jnp.zeros_like(Cm), Cm * c / kap ** 2], -1)
    chh = jnp.stack([jnp.zeros_like(Cm), jnp.zeros_like(Cm), Sm * c, Cm * c / kap, jnp.zeros_like(Cm)], -1)
    # sinh = (e - f) / den, cosh = (e + f) / den, with e = exp(-kappa (d - eta)), f = exp(-kappa (d + eta))
    return sh + chh, chh - sh


class Integrals(NamedTuple):
    """The liquid's geometric integrals at one beta (per unit breadth and density where not said)."""
    An: jax.Array      # (N,) integral of phi_n
    Jn: jax.Array      # (N, N) dA_n / dbeta_j
    Ank: jax.Array     # (N, N) integral of grad phi_n . grad phi_k
    grad: jax.Array    # (N, 2) integral of grad phi_n (x, u components)
    Zux: jax.Array     # (N,) integral of u dphi_n/dx
    Xuz: jax.Array     # (N,) integral of x dphi_n/du
    area: jax.Array    # integral of 1
    mx: jax.Array      # integral of x
    mz: jax.Array      # integral of u
    mxx: jax.Array
    mzz: jax.Array
    mxz: jax.Array
    dmx: jax.Array     # (N,) d(integral of x) / dbeta
    dmz: jax.Array     # (N,) d(integral of u) / dbeta
    Bw: jax.Array      # (N,) integral of grad phi_n . w (w: the rotation's vortical flow, `vortical`)
    W: jax.Array       # integral of |w|^2
    wint: jax.Array    # (2,) integral of w
    Zwx: jax.Array     # integral of u w_x
    Xwz: jax.Array     # integral of x w_z


class ModalTank(eqx.Module):
    """One tank's liquid in two-dimensional flow along its length, on N modes (module docstring)."""
    L: jax.Array          # tank length (x), m
    b: jax.Array          # tank breadth (y), m
    h: jax.Array          # fill depth, m
    D: jax.Array          # tank height, m (the vortical flow's section)
    rho: jax.Array        # liquid density, kg/m^3
    origin: jax.Array     # (3,) the tank's inner min corner in the vessel frame
    k: jax.Array          # (N,) k_n = n pi / L
    xq: jax.Array         # (NX,) quadrature points on [0, L]
    wq: jax.Array         # (NX,) their weights
    cx: jax.Array         # (NX, N) cos(k_n x_q), sin(k_n x_q): the tables of the integrals
    sx: jax.Array
    cj: jax.Array         # (NX, 2N + 1) cos(j pi x_q / L)
    vtab: tuple           # (NX, SJ_TERMS, 5) twice: the vortical series' tables (`_vortical_tables`)
    vort0: tuple          # the vortical integrals (Bw, W, wint, Zwx, Xwz) at rest less their surface terms
    S0: jax.Array         # (3,) the first moment at rest (vessel frame)

    @property
    def n(self) -> int:
        return int(self.k.shape[0])

    @property
    def mass(self):
        return self.rho * self.b * self.L * self.h

    def zeta(self, beta, x):
        """The free-surface elevation above the fill depth at tank-local x (any shape)."""
        x = jnp.asarray(x)
        return jnp.cos(x[..., None] * self.k) @ beta

    def omega_linear(self, g):
        """(N,) the linear natural frequencies sqrt(g k tanh(k h)), rad/s."""
        return jnp.sqrt(g * self.k * jnp.tanh(self.k * self.h))

    def modal_mass(self):
        """(N,) rho b (L/2) / (k tanh kh): each modal row's mass at rest (kg per m of beta)."""
        return self.rho * self.b * 0.5 * self.L / (self.k * jnp.tanh(self.k * self.h))

    # ------------------------------------------------------------------ integrals
    def integrals(self, beta) -> Integrals:
        """The integrals at beta, exact through the depth: the potential's in closed form (products of
        cosh(k_n u) make sinh(k_j H) / k_j with k_j = j pi / L, j = |n - m| or n + m), the vortical
        flow's from their values at rest (`vort0`) plus the flux through the free surface (Green: the
        integrands are divergences of fields with no flux through the walls), all along x by Gauss
        quadrature over the instantaneous surface H(x) = h + zeta(x).

        Written for the step's cost: one exponential per point and wavenumber k_j (sinh and cosh of
        k_n H are those of k_j H for j = n), A_nk from the (2N + 1)^2 moments of sinh(k_a H) cos(k_b x)
        (one matrix product), and the vortical flow's terms as powers (`_vortical_surface`)."""
        k, x, w, ch = self.k, self.xq, self.wq, jnp.cosh(self.k * self.h)
        n, cx, sx = self.n, self.cx, self.sx
        H = self.h + cx @ beta                                             # (NX,)
        Hp = -(sx * k) @ beta                                               # dH/dx
        # sinh(k_j H) / k_j (H for j = 0) and cosh(k_j H), j = 0..2N, from one exponential each
        kj = jnp.arange(2 * n + 1) * jnp.pi / self.L
        E = jnp.exp(H[:, None] * kj)
        Ei = 1.0 / E
        Sh, Chj = 0.5 * (E - Ei), 0.5 * (E + Ei)
        Sj = jnp.concatenate([H[:, None], Sh[:, 1:] / kj[1:]], axis=1)
        shH, chH = Sh[:, 1:n + 1], Chj[:, 1:n + 1]
        An = w @ (cx * shH) / (k * ch)
        phis = cx * chH / ch                                                # phi_n at the surface
        Jn = (phis * w[:, None]).T @ cx
        i = np.arange(1, n + 1)
        P, M = i[:, None] + i[None, :], np.abs(i[:, None] - i[None, :])
        T = (Sj * w[:, None]).T @ self.cj                                   # (2N + 1)^2: sinh(k_a H) / k_a, cos(k_b x)
        Ank = 0.5 * jnp.outer(k / ch, k / ch) * (T[P, M] - T[M, P])
        grad = jnp.stack([-(w @ (sx * shH)) / ch, (w @ (cx * (chH - 1.0))) / ch], axis=-1)
        Zux = -(w @ (sx * (H[:, None] * shH - (chH - 1.0) / k))) / ch
        Xuz = ((w * x) @ (cx * (chH - 1.0))) / ch
        chi, flux, Gx, Gz, Gux = self._vortical_surface(H, Hp)
        xi = x - 0.5 * self.L
        Bw0, W0, wint0, Zwx0, Xwz0 = self.vort0
        vort = (Bw0 + (w * flux) @ phis, W0 + w @ (chi * flux + 2.0 * xi * Gz), wint0 + jnp.stack([w @ Gx, w @ Gz]),
                Zwx0 + w @ Gux, Xwz0 + (w * x) @ Gz)
        return Integrals(An, Jn, Ank, grad, Zux, Xuz, w @ H, w @ (x * H), w @ (0.5 * H ** 2), w @ (x * x * H),
                         w @ (H ** 3 / 3.0), w @ (x * 0.5 * H ** 2),
                         (w * x) @ cx, (w * H) @ cx, *vort)

    def _vortical_surface(self, H, Hp):
        """At the quadrature points' surface (x_q, H_q), slope Hp: chi, the flux w . (-H', 1) of the
        vortical flow (`vortical`), and the depth primitives of w_x, w_z and u w_x (their values at
        u = H; the vortical integrals' differences from rest are sums of these).

        The series' exponentials exp(-kappa_m (D - H)) and exp(-kappa_m H), kappa_m = (2m + 1) kappa_0,
        are the odd powers of their m = 0 terms (by doubling: a few products, no exponential per
        term); the sums are then two products with the tables `vtab` (the series' coefficients times
        sin or cos (kappa_m xi_q), formed once)."""
        kap0 = jnp.pi / self.L
        e = odd_powers(jnp.exp(-kap0 * (self.D - H)), SJ_TERMS)             # (NX, SJ_TERMS)
        f = odd_powers(jnp.exp(-kap0 * H), SJ_TERMS)
        Te, Tf = self.vtab
        s = jnp.einsum("qm,qmk->qk", e, Te) + jnp.einsum("qm,qmk->qk", f, Tf)  # (NX, 5)
        chi, wx, wz0, Gx, Gux0 = s[:, 0], s[:, 1], s[:, 2], s[:, 3], s[:, 4]
        wz = 2.0 * (self.xq - 0.5 * self.L) + wz0
        return chi, wz - Hp * wx, Gx, 2.0 * (self.xq - 0.5 * self.L) * H + chi, H * Gx - Gux0

    def integrals_quadrature(self, beta) -> Integrals:
        """The same integrals by Gauss quadrature over the liquid (NZ points through the depth): the
        reference of `integrals`, and its vortical values at rest."""
        k, x, w = self.k, self.xq, self.wq
        H = self.h + jnp.cos(x[:, None] * k) @ beta                       # (NX,)
        ch = jnp.cosh(k * self.h)
        cx, sx = jnp.cos(x[:, None] * k), jnp.sin(x[:, None] * k)         # (NX, N)
        An = jnp.einsum("q,qn->n", w, cx * jnp.sinh(H[:, None] * k) / (k * ch))
        phis = cx * jnp.cosh(H[:, None] * k) / ch                          # (NX, N)
        Jn = jnp.einsum("q,qn,qj->nj", w, phis, cx)
        sg, sw = np.polynomial.legendre.leggauss(NZ)
        u = H[:, None] * (0.5 * (sg[None, :] + 1.0))                      # (NX, NZ)
        wu = w[:, None] * H[:, None] * (0.5 * sw[None, :])
        C = jnp.cosh(u[..., None] * k) / ch                               # (NX, NZ, N)
        S = jnp.sinh(u[..., None] * k) / ch
        gx = -k * sx[:, None, :] * C                                        # dphi/dx
        gz = k * cx[:, None, :] * S                                         # dphi/du
        Ank = jnp.einsum("qs,qsn,qsm->nm", wu, gx, gx) + jnp.einsum("qs,qsn,qsm->nm", wu, gz, gz)
        grad = jnp.stack([jnp.einsum("qs,qsn->n", wu, gx), jnp.einsum("qs,qsn->n", wu, gz)], axis=-1)
        Zux = jnp.einsum("qs,qs,qsn->n", wu, u, gx)
        Xuz = jnp.einsum("qs,q,qsn->n", wu, x, gz)
        wx, wz = self.vortical(jnp.broadcast_to(x[:, None], u.shape), u)
        Bw = jnp.einsum("qs,qsn->n", wu, gx * wx[..., None] + gz * wz[..., None])
        vort = (Bw, jnp.sum(wu * (wx ** 2 + wz ** 2)), jnp.array([jnp.sum(wu * wx), jnp.sum(wu * wz)]),
                jnp.sum(wu * u * wx), jnp.sum(wu * x[:, None] * wz))
        return Integrals(An, Jn, Ank, grad, Zux, Xuz, w @ H, w @ (x * H), w @ (0.5 * H ** 2), w @ (x * x * H),
                         w @ (H ** 3 / 3.0), w @ (x * 0.5 * H ** 2),
                         (w * x) @ cx, (w * H) @ cx, *vort)

    def vortical(self, x, u):
        """w (x and u components) at tank-local points: the flow relative to the tank that a unit pitch
        rate (about y) adds so that the liquid's absolute motion stays irrotational (Kelvin): curl w =
        -2 e_y, no flux through the walls, the bottom and the roof. With xi, eta from the centre of the
        L x D section, w = grad(chi) + (0, 2 xi), chi = sum_m c_m sin(k_m xi) sinh(k_m eta) /
        (k_m cosh(k_m D / 2)), k_m = (2m + 1) pi / L, c_m the sine series of -2 xi (the
        Stokes-Joukowski potential of the rectangle less the rigid rotation)."""
        a, d = 0.5 * self.L, 0.5 * self.D
        xi, eta = x - a, u - d
        m = jnp.arange(SJ_TERMS)
        k = (2 * m + 1) * jnp.pi / (2 * a)
        c = -2.0 * (2.0 / a) * (-1.0) ** m / k ** 2
        # sinh(k eta) / cosh(k d) and cosh(k eta) / cosh(k d) without overflow (|eta| <= d)
        e = jnp.exp(-k * (d - eta[..., None]))
        f = jnp.exp(-k * (d + eta[..., None]))
        den = 1.0 + jnp.exp(-2.0 * k * d)
        sh, ch = (e - f) / den, (e + f) / den
        wx = jnp.sum(c * jnp.cos(k * xi[..., None]) * sh, axis=-1)
        wz = 2.0 * xi + jnp.sum(c * jnp.sin(k * xi[..., None]) * ch, axis=-1)
        return wx, wz

    def moments(self, I: Integrals):
        """(first moment S (3,), second moment J = sum m x x^T (3, 3)) of the liquid in the vessel frame."""
        rb, o, bb = self.rho * self.b, self.origin, self.b
        yc = o[1] + 0.5 * bb
        Sl = rb * jnp.array([I.mx, 0.5 * bb * I.area, I.mz])            # tank-local, from the corner
        yy = self.rho * (bb ** 3 / 3.0) * I.area
        xy = self.rho * 0.5 * bb ** 2 * I.mx
        yz = self.rho * 0.5 * bb ** 2 * I.mz
        Jl = jnp.array([[rb * I.mxx, xy, rb * I.mxz], [xy, yy, yz], [rb * I.mxz, yz, rb * I.mzz]])
        m = rb * I.area
        J = Jl + jnp.outer(o, Sl) + jnp.outer(Sl, o) + m * jnp.outer(o, o)
        del yc
        return Sl + m * o, J

    def rates(self, I: Integrals, beta_dot):
        """The potential's amplitudes R from the projected kinematic condition dA_n/dt = A_nk R_k."""
        return jnp.linalg.solve(I.Ank, I.Jn @ beta_dot)

    def coupling(self, I: Integrals, AJ=None):
        """(3, N), (3, N): the liquid's linear and angular momentum (body frame, about the vessel's
        origin) per unit beta_dot, of the flow relative to the tank. The linear one is the mass
        centre's rate dS/dt, which the true flow's momentum equals (Reynolds): unlike the truncated
        potential's integral of grad phi it is an exact time derivative, so that a tank in uniform
        motion sloshes as one at rest (Galilean invariance). The angular one is the potential's
        integral of r x grad phi, r = origin + (x, y, u), uniform in y."""
        rb, o = self.rho * self.b, self.origin
        yc = o[1] + 0.5 * self.b
        P = rb * jnp.stack([I.dmx, jnp.zeros_like(I.dmx), I.dmz])
        gx, gz = I.grad[:, 0], I.grad[:, 1]
        Hn = rb * jnp.stack([yc * gz, I.Zux + o[2] * gx - I.Xuz - o[0] * gz, -yc * gx])
        return P, Hn @ (jnp.linalg.solve(I.Ank, I.Jn) if AJ is None else AJ)

    def pitch_block(self, I: Integrals, gw=None):
        """The vortical flow's share of the kinetic energy, in omega: with R = A^-1 (J beta_dot - q Bw)
        (the kinematic condition with w's flux through the surface) the cross terms in q beta_dot
        cancel, leaving the (3, 3) block rho b (e_y c^T + c e_y^T + (W - Bw A^-1 Bw) e_y e_y^T),
        c = integral of r x w less the potential's share integral of r x grad phi A^-1 Bw."""
        rb, o = self.rho * self.b, self.origin
        yc = o[1] + 0.5 * self.b
        gx, gz = I.grad[:, 0], I.grad[:, 1]
        Hn = jnp.stack([yc * gz, I.Zux + o[2] * gx - I.Xuz - o[0] * gz, -yc * gx])
        Hw = jnp.array([yc * I.wint[1], I.Zwx + o[2] * I.wint[0] - I.Xwz - o[0] * I.wint[1], -yc * I.wint[0]])
        gw = jnp.linalg.solve(I.Ank, I.Bw) if gw is None else gw
        c = Hw - Hn @ gw
        ey = jnp.array([0.0, 1.0, 0.0])
        return rb * (jnp.outer(ey, c) + jnp.outer(c, ey) + (I.W - I.Bw @ gw) * jnp.outer(ey, ey))

    def mass_matrix(self, beta):
        """(6 + N, 6 + N): the kinetic energy is exactly 1/2 v^T M(beta) v in v = (V_b, omega, beta_dot)."""
        return self._mass(beta)[0]

    def _mass(self, beta):
        """(M(beta), (P, S(beta) - S0)): the mass matrix, the linear momentum per beta_dot, the first
        moment's displacement from rest (one evaluation of the integrals and one solve with A_nk)."""
        I = self.integrals(beta)
        S, J = self.moments(I)
        G = spd_inverse(I.Ank) @ jnp.concatenate([I.Jn, I.Bw[:, None]], axis=1)
        AJ, gw = G[:, :-1], G[:, -1]
        P, Hb = self.coupling(I, AJ)
        m = self.rho * self.b * I.area
        Sx = jnp.array([[0.0, -S[2], S[1]], [S[2], 0.0, -S[0]], [-S[1], S[0], 0.0]])
        Iw = jnp.trace(J) * jnp.eye(3) - J + self.pitch_block(I, gw)
        Mbb = self.rho * self.b * I.Jn.T @ AJ
        top = jnp.concatenate([m * jnp.eye(3), -Sx, P], axis=1)
        mid = jnp.concatenate([Sx, Iw, Hb], axis=1)
        bot = jnp.concatenate([P.T, Hb.T, 0.5 * (Mbb + Mbb.T)], axis=1)
        return jnp.concatenate([top, mid, bot], axis=0), (P, S - self.S0)

    def kinetic(self, Vb, omega, beta, beta_dot):
        """The liquid's kinetic energy (J) for the body-frame velocity V_b of the vessel's origin and omega."""
        v = jnp.concatenate([Vb, omega, beta_dot])
        return 0.5 * v @ (self.mass_matrix(beta) @ v)

    def first_moment(self, beta):
        """S(beta) (vessel frame): the liquid's first moment, from the surface alone (the potential
        energy of every saved frame reads it; the other integrals are not needed)."""
        w, x = self.wq, self.xq
        H = self.h + self.cx @ beta
        rb, o = self.rho * self.b, self.origin
        area = w @ H
        return rb * jnp.array([w @ (x * H), 0.5 * self.b * area, w @ (0.5 * H ** 2)]) + rb * area * o

    def rest_moment(self):
        return self.S0

    def potential(self, beta, g_b):
        """The gravity potential of the liquid's displacement from rest: -g_b . (S(beta) - S0)."""
        return -g_b @ (self.first_moment(beta) - self.S0)

    def rows(self, Vb, omega, beta, beta_dot, Vb_dot, alpha, beta_dd, g_b):
        """Kirchhoff's equations (module docstring): (translation rows (body), rotation rows (body),
        modal rows), from the momenta p = M(beta) v and their rates M v_dot + (dM/dt) v."""
        v = jnp.concatenate([Vb, omega, beta_dot])
        # M's rate along beta_dot by one forward pass and dT/dbeta by one reverse pass (not the N
        # derivatives dM/dbeta_j: the rows need only these two contractions of them)
        (M, (P, dS)), (Md, _) = jax.jvp(self._mass, (beta,), (beta_dot,))
        Mdv = Md @ v
        dT = jax.grad(lambda be: 0.5 * v @ (self._mass(be)[0] @ v))(beta)
        p = M @ v
        dp = M @ jnp.concatenate([Vb_dot, alpha, beta_dd]) + Mdv
        P_lin, H = p[:3], p[3:6]
        f = dp[:3] + jnp.cross(omega, P_lin)
        m = dp[3:6] + jnp.cross(omega, H) + jnp.cross(Vb, P_lin) - jnp.cross(dS, g_b)
        return f, m, dp[6:] - dT - g_b @ P          # dV/dbeta = -g_b . dS/dbeta


def modal_tank(L, b, h, rho, origin, n_modes: int, D=None) -> ModalTank:
    """The tank, with its rest values (the vortical integrals less their surface terms, the first
    moment) formed once here by quadrature over the liquid at rest (`integrals_quadrature`).

    The build is one compiled program per mode count (`_build`, staging.py `evaluated`), where op by
    op its tables and quadrature compiled some 150 tiny XLA programs. Built from concrete values it
    is evaluated now, even inside an outer trace; traced values (a fill depth under differentiation)
    stage it into the caller's program."""
    return _modal_tank(*(_value(a) for a in (L, b, h, rho, origin)), n_modes, None if D is None else _value(D))


def _value(a):
    """An argument of the compiled build: a JAX array (a tracer among them) as it is, anything else as
    a float64 NumPy array (an argument of the program, not a constant compiled into it)."""
    return a if isinstance(a, jax.Array) else np.asarray(a, dtype=float)


def _build(L, b, h, rho, origin, n_modes: int, D) -> ModalTank:
    """`modal_tank`'s program (staging.py `evaluated`: one per mode count)."""
    nx = max(NX, 8 * n_modes)
    xg, wg = np.polynomial.legendre.leggauss(nx)
    L = jnp.asarray(L, dtype=float)
    D = 2.0 * jnp.asarray(h, dtype=float) if D is None else jnp.asarray(D, dtype=float)
    z = jnp.zeros(n_modes)
    x = 0.5 * L * (jnp.asarray(xg) + 1.0)
    k = jnp.arange(1, n_modes + 1) * jnp.pi / L
    t = ModalTank(L=L, b=jnp.asarray(b, dtype=float), h=jnp.asarray(h, dtype=float), D=D,
                  rho=jnp.asarray(rho, dtype=float), origin=jnp.asarray(origin, dtype=float),
                  k=k, xq=x, wq=0.5 * L * jnp.asarray(wg), cx=jnp.cos(x[:, None] * k), sx=jnp.sin(x[:, None] * k),
                  cj=jnp.cos(x[:, None] * jnp.arange(2 * n_modes + 1) * jnp.pi / L),
                  vtab=_vortical_tables(L, D, x),
                  vort0=(z, jnp.zeros(()), jnp.zeros(2), jnp.zeros(()), jnp.zeros(())), S0=jnp.zeros(3))
    I = t.integrals_quadrature(z)
    w, H = t.wq, jnp.full(nx, t.h)
    chi, flux, Gx, Gz, Gux = t._vortical_surface(H, jnp.zeros(nx))
    phis = jnp.cos(x[:, None] * t.k)
    vort0 = (I.Bw - (w * flux) @ phis, I.W - w @ (chi * flux + (x - 0.5 * L) * 2.0 * Gz),
             I.wint - jnp.stack([w @ Gx, w @ Gz]), I.Zwx - w @ Gux, I.Xwz - (w * x) @ Gz)
    return eqx.tree_at(lambda m: (m.vort0, m.S0), t, (vort0, t.moments(I)[0]))


_modal_tank = evaluated(_build, static_argnums=5)
