"""Hull hydrodynamics: added mass, radiation damping with the memory of the Cummins equation, wave
excitation from tables, and Capytaine (an optional extra) to compute them.

The rigid rows of the residual (model.System.residual) gain, for small motions xi about the
initial equilibrium (translations of the COG, rotations about it):

    A_inf xi_ddot + mu(t) + B_v xi_dot - F_exc(t),     mu(t) = int_0^t K(t - s) xi_dot(s) ds   (Cummins 1962)

with A_inf the added mass at infinite frequency, K the retardation functions, B_v an optional linear
(viscous) damping and F_exc the first-order wave excitation (waves.py). Coefficients are about the
COG, in the axes of the residual's rows (translations inertial, rotations body: equal at small
motions). In the frequency domain this is the classical

    [-w^2 (M + A(w)) + i w (B(w) + B_v) + C] xi = F_exc,   A(w) = A_inf - int K sin / w,  B(w) = int K cos,

which the tests check against the time-domain run.

The memory (hydro/radiation.py fits it) is a set of complex poles p_k, each with a state
w_k' = p_k w_k + xi_dot_j; the states are the RadiationMemory term's integrator states and a step advances them exactly
for a velocity linear over the step, so the memory force is linear in the step's unknown new velocity.
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .about import About
from .terms import AbstractTerm, Kin, Rows


class Memory(eqx.Module):
    """The fitted radiation memory: complex poles (real, imaginary parts), their input dof (a one-hot
    (M, n) selection) and output coefficients c (n, M); n = 6 for the vessel, 6 per body for the
    coupled radiation of several (physics/bodies.py)."""
    p_re: jax.Array
    p_im: jax.Array
    select: jax.Array     # (M, n)
    c_re: jax.Array       # (n, M)
    c_im: jax.Array

    def init(self):
        return jnp.zeros((self.p_re.shape[0], 2))

    def coefficients(self, h):
        """exp(p h), g0, g1 of w_{n+1} = exp(p h) w_n + g0 u_n + g1 u_{n+1} (u linear over the step):
        g1 = ((exp(p h) - 1) / (p h) - 1) / p, g0 = (exp(p h) - 1) / p - g1. As (re, im) pairs."""
        p = self.p_re + 1j * self.p_im
        ph = p * h
        E = jnp.exp(ph)
        em1 = jnp.expm1(ph)
        small = jnp.abs(ph) < 1e-4
        phs = jnp.where(small, 1.0, ph)
        ratio = jnp.where(small, 1.0 + ph / 2.0 + ph * ph / 6.0, em1 / phs)   # (e^{ph} - 1) / (ph)
        g1 = jnp.where(small, h * (0.5 + ph / 6.0 + ph * ph / 24.0), (ratio - 1.0) / jnp.where(small, 1.0, p))
        g0 = h * ratio - g1
        split = lambda z: (jnp.real(z), jnp.imag(z))  # noqa: E731
        return split(E), split(g0), split(g1)

    def advance(self, z, v_old, v_new, coef):
        """The states at t_{n+1} from those at t_n and the rigid velocities (6,) at both ends."""
        (Er, Ei), (g0r, g0i), (g1r, g1i) = coef
        n = self.select.shape[1]          # the vessel's 6, or the rigid dofs of several bodies
        u0, u1 = self.select @ v_old[:n], self.select @ v_new[:n]
        wr, wi = z[:, 0], z[:, 1]
        nr = Er * wr - Ei * wi + g0r * u0 + g1r * u1
        ni = Er * wi + Ei * wr + g0i * u0 + g1i * u1
        return jnp.stack([nr, ni], axis=1)

    def force(self, z):
        """mu = sum_k Re(c_k w_k) (6,)."""
        return self.c_re @ z[:, 0] - self.c_im @ z[:, 1]


class Excitation(eqx.Module):
    """First-order wave forces as a known function of time: F_j(t) = r(t) height sum_i
    amp_ji cos(w_i t + phase_ji), rows in the residual's frame (translations inertial, rotations
    body; equal at small motions about the initial attitude). `height` is the scene's amplitude
    (regular) or Hs (JONSWAP): the forces are linear in it, so it may be a traced parameter.

    The sum is evaluated as amp cos(phase) . cos(w t) - amp sin(phase) . sin(w t), the two
    (6, N) products formed once where the excitation is made: the force is evaluated in every
    Newton iteration, and N cosines and N sines there cost a third of a cosine per row and
    component (6 N)."""
    omega: jax.Array      # (N,)
    amp: jax.Array        # (6, N) per unit `height`
    phase: jax.Array      # (6, N)
    height: jax.Array     # ()
    in_phase: jax.Array   # (6, N) amp cos(phase)
    quadrature: jax.Array  # (6, N) amp sin(phase)
    ramp: float = eqx.field(static=True, default=0.0)

    def __init__(self, omega, amp, phase, height, ramp: float = 0.0):
        self.omega, self.amp, self.phase, self.height, self.ramp = omega, amp, phase, height, ramp
        self.in_phase = amp * jnp.cos(phase)
        self.quadrature = amp * jnp.sin(phase)

    def force(self, t):
        wt = self.omega * t
        F = self.height * (self.in_phase @ jnp.cos(wt) - self.quadrature @ jnp.sin(wt))
        if self.ramp > 0:
            F = F * jnp.where(t < self.ramp, 0.5 * (1.0 - jnp.cos(jnp.pi * jnp.clip(t, 0.0, self.ramp) / self.ramp)), 1.0)
        return F


class WaveExcitation(AbstractTerm):
    """First-order wave forces on the rigid rows: a known function of time."""
    excitation: Excitation
    about: About = eqx.field(static=True, default=About())     # the sea and the forces' source

    def rows(self, k: Kin) -> Rows:
        return Rows(-self.excitation.force(k.t))

    def describe(self) -> tuple:
        return self.about.lines

    def at_time(self, t) -> "KnownForce":
        # N cosines and N sines and two (6, N) products per evaluation, the same in every Newton
        # iteration of a step: formed once (the paper ship's 200 components were a third of its step)
        return KnownForce(self.excitation.force(t), self.about)


class KnownForce(AbstractTerm):
    """A force on the rigid rows known for the step being solved: a WaveExcitation at the step's
    time (WaveExcitation.at_time). Its rows are that term's, the same numbers."""
    force: jax.Array      # (6,)
    about: About = eqx.field(static=True, default=About())

    def rows(self, k: Kin) -> Rows:
        return Rows(-self.force)

    def describe(self) -> tuple:
        return self.about.lines


class AddedMass(AbstractTerm):
    """The radiation added mass at infinite frequency, A_inf (6, 6) about the COG: it moves with the hull."""
    matrix: jax.Array
    about: About = eqx.field(static=True, default=About())     # where the coefficients come from

    def rows(self, k: Kin) -> Rows:
        return Rows(self.matrix @ k.a6)

    def describe(self) -> tuple:
        return self.about.lines

    def kinetic(self, k: Kin):
        v6 = k.v6
        return 0.5 * v6 @ (self.matrix @ v6)

    def mass_scale(self):
        return jnp.diag(self.matrix)


class LinearDamping(AbstractTerm):
    """Linear (viscous) damping B_v (6, 6) added to the radiation: bilge keels, viscous roll damping."""
    matrix: jax.Array
    about: About = eqx.field(static=True, default=About())

    def rows(self, k: Kin) -> Rows:
        return Rows(self.matrix @ k.v6)

    def describe(self) -> tuple:
        return self.about.lines


class RadiationMemory(AbstractTerm):
    """The memory force mu(t) of the Cummins equation on the rigid rows, from the memory's states:
    integrator states of this term (terms.AbstractTerm's hooks), advanced by every step."""
    memory: Memory
    about: About = eqx.field(static=True, default=About())     # where the fit comes from

    def rows(self, k: Kin) -> Rows:
        return Rows(self.memory.force(k.z))

    def describe(self) -> tuple:
        return self.about.lines

    def state_init(self):
        return self.memory.init()

    def state_coefficients(self, h):
        return self.memory.coefficients(h)

    def state_advance(self, z, v_old, v_new, coef):
        return self.memory.advance(z, v_old, v_new, coef)
