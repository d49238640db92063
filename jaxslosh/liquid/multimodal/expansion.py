"""The multimodal liquid's third-order system: the exact tank's kinetic energy truncated at fourth
order in the small quantities, its modal equations then complete to third order (the classical
asymptotic modal systems of Narimanov, Moiseev and Lukovsky; Faltinsen, Rognebakke, Lukovsky &
Timokha 2000, J. Fluid Mech. 407, section 3; Faltinsen & Timokha, Sloshing, 2009, chapters 7 and 8).

The exact tanks (liquid/multimodal/term.py, multimodal3d.py) write the liquid's kinetic energy as
T = 1/2 v^T M(beta) v in v = (V_b, omega, beta_dot) and its potential through the first moment
S(beta); M holds the Bateman-Luke integrals A_n, A_nk (inverted), the flux of the vortical flows and
the moments, evaluated exactly in beta by quadrature at every residual. Here M is replaced by its
Taylor polynomial of second degree about the level surface,

    M(beta) ~ M0 + sum_j M1_j beta_j + sum_jk M2_jk beta_j beta_k,

so that T keeps every term of up to fourth order in (beta, beta_dot, the tank's velocities) and the
Lagrange equations every term of up to third order: the system of Faltinsen et al. 2000's section 3
before its Moiseev ordering (every mode of one order: it keeps the terms that ordering drops).
S(beta) is quadratic in beta (the surface is linear in beta): its polynomial is exact. The
coefficients are the exact tank's derivatives at beta = 0 (nested forward differentiation, once per
run), so the polynomial is the exact system's expansion by construction. A residual is then a few
small tensor contractions in place of the quadrature: the step is several times cheaper, the
frequencies at small amplitude are the exact tank's (M0), and the Lagrangian form keeps a free
vessel's energy. It departs from the exact system at fourth order in the amplitudes: steep waves
(crests of a tenth of the tank's length and more) call for the exact integrals.
"""
from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp


def _coefficients(tank):
    """(M0, M1, M2, S0, S1, S2): the Taylor coefficients of M(beta) and S(beta) at beta = 0 (M2 and
    S2 half the Hessians, symmetric in their last two indices)."""
    z = jnp.zeros(tank.n)
    M = tank.mass_matrix
    M1 = jax.jacfwd(M)(z)
    S = tank.first_moment

    def hessian(f):
        # one mode's column of second derivatives at a time (lax.map): nested jacfwd would carry all
        # N^2 directions through the quadrature at once, whose memory grows as N^2 (a 30-mode
        # three-dimensional tank took 20 GB); by columns it grows as N, for the same arithmetic
        def column(e):
            return jax.jacfwd(lambda b: jax.jvp(f, (b,), (e,))[1])(z)
        return jnp.moveaxis(jax.lax.map(column, jnp.eye(tank.n)), 0, -2)
    M2 = 0.5 * hessian(M)
    S2 = 0.5 * hessian(S)
    sym = lambda a: 0.5 * (a + jnp.swapaxes(a, -1, -2))  # noqa: E731
    return M(z), M1, sym(M2), S(z), jax.jacfwd(S)(z), sym(S2)


# a concrete tank's coefficients: one program, run once, compiled without XLA's costly optimisations
# (it halves the compile); a traced tank's (traced `params`) are part of the caller's program
_compiled_coefficients = functools.partial(jax.jit, compiler_options={
    "xla_backend_optimization_level": 0, "xla_llvm_disable_expensive_passes": True})(_coefficients)


class ExpandedTank(eqx.Module):
    """A multimodal tank (2-D ModalTank or ModalTank3D) on its third-order system (module docstring):
    the same interface as the exact tank's in the liquid's residual."""
    exact: eqx.Module     # the exact tank: its linear data (wavenumbers, modal masses, probes' rows)
    M0: jax.Array         # (6 + N, 6 + N)
    M1: jax.Array         # (6 + N, 6 + N, N)
    M2: jax.Array         # (6 + N, 6 + N, N, N)
    S0: jax.Array         # (3,) the first moment at rest (vessel frame)
    S1: jax.Array         # (3, N)
    S2: jax.Array         # (3, N, N)

    @property
    def n(self) -> int:
        return self.exact.n

    @property
    def mass(self):
        return self.exact.mass

    def omega_linear(self, g):
        return self.exact.omega_linear(g)

    def modal_mass(self):
        return self.exact.modal_mass()

    def surface_rows(self, x, y):
        return self.exact.surface_rows(x, y)

    def integrals(self, beta):
        return self.exact.integrals(beta)

    def moments(self, I):
        return self.exact.moments(I)

    def mass_matrix(self, beta):
        return self.M0 + (self.M1 + self.M2 @ beta) @ beta

    def kinetic(self, Vb, omega, beta, beta_dot):
        v = jnp.concatenate([Vb, omega, beta_dot])
        return 0.5 * v @ (self.mass_matrix(beta) @ v)

    def first_moment(self, beta):
        return self.S0 + (self.S1 + self.S2 @ beta) @ beta

    def rest_moment(self):
        return self.S0

    def potential(self, beta, g_b):
        return -g_b @ (self.first_moment(beta) - self.S0)

    def rows(self, Vb, omega, beta, beta_dot, Vb_dot, alpha, beta_dd, g_b):
        """Kirchhoff's equations (liquid/multimodal/term.py) of the polynomial's kinetic energy: the
        momenta p = M v, their rates M v_dot + (dM/dt) v, dT/dbeta = 1/2 v^T dM/dbeta v, written out
        (dM/dbeta_j = M1_j + 2 M2_jk beta_k) in place of automatic derivatives."""
        v = jnp.concatenate([Vb, omega, beta_dot])
        M2b = self.M2 @ beta
        dM = self.M1 + 2.0 * M2b                                    # (6 + N, 6 + N, N) dM/dbeta
        M = self.M0 + (self.M1 + M2b) @ beta
        Mv = jnp.einsum("abj,b->aj", dM, v)                          # (dM/dbeta_j) v
        p = M @ v
        dp = M @ jnp.concatenate([Vb_dot, alpha, beta_dd]) + Mv @ beta_dot
        dT = 0.5 * v @ Mv
        dS = (self.S1 + self.S2 @ beta) @ beta
        P = self.S1 + 2.0 * self.S2 @ beta                           # dS/dbeta
        P_lin, H = p[:3], p[3:6]
        f = dp[:3] + jnp.cross(omega, P_lin)
        m = dp[3:6] + jnp.cross(omega, H) + jnp.cross(Vb, P_lin) - jnp.cross(dS, g_b)
        return f, m, dp[6:] - dT - g_b @ P           # dV/dbeta = -g_b . dS/dbeta


def third_order(tank) -> ExpandedTank:
    """The tank on its third-order system (module docstring)."""
    traced = any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(tank))
    return ExpandedTank(tank, *(_coefficients if traced else _compiled_coefficients)(tank))
