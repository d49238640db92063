"""Linear damping of the liquid's sloshing modes (`[tanks.damping]`): the modal damping matrix

    C = M Phi diag(2 zeta_i omega_i) Phi^T M

of the tanks' mass-normalised sloshing modes Phi (K Phi = M Phi Omega^2, Phi^T M Phi = I), so that
each mode alone decays as a damped oscillator of ratio zeta_i and the rigid motion of the tank, which
no sloshing mode holds, is not damped. Its force acts against the liquid's velocity relative to the
tank (d_dot, tank frame): an inviscid liquid has no other dissipation, and a viscous one loses its
energy in the boundary layers on the walls it slides along (fem/damping.py).

The term is held as B = M Phi (nf, k) and c = 2 zeta omega (k,): C has rank k, so a row costs two
thin products and the constant liquid block of the Newton matrix takes it by a low-rank update of
its inverse (solve/linear.py) instead of a new factorization. With a modal liquid B is the basis's
coordinates of its sloshing modes and C = B diag(c) B^T is diagonal on them.
"""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .about import About
from .terms import AbstractTerm, Kin, Rows


class ModalDamping(AbstractTerm):
    """C d_dot on the deformable block's rows; no energy of its own (it only removes energy)."""
    B: jax.Array     # (nf, k) M Phi: the sloshing modes' mass-weighted shapes on the unknowns
    c: jax.Array     # (k,) 2 zeta_i omega_i, 1/s (zeta traceable: `tanks.<name>.damping.ratio`)
    about: About = eqx.field(static=True, default=About())     # the damped tanks and their ratios

    def rows(self, k: Kin) -> Rows:
        return Rows(jnp.zeros(6), self.B @ (self.c * (self.B.T @ k.d_dot)))

    def describe(self) -> tuple:
        return self.about.lines
