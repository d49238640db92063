"""Linear damping of the liquid's sloshing modes (`[tanks.damping]`): the modal damping matrix

    C = M Phi diag(2 zeta_i omega_i) Phi^T M

of the tanks' mass-normalised sloshing modes Phi (K Phi = M Phi Omega^2, Phi^T M Phi = I), so that
each mode alone decays as a damped oscillator of ratio zeta_i and the rigid motion of the tank, which
no sloshing mode holds, is not damped. Its force acts against the liquid's velocity relative to the
tank (d_dot, tank frame): an inviscid liquid has no other dissipation, and a viscous one loses its
energy in the boundary layers on the walls it slides along (liquid/damping.py).

The term is held as B = M Phi (nf, k) and c = 2 zeta omega (k,): C has rank k, so a row costs two
thin products and the constant liquid block of the Newton matrix takes it by a low-rank update of
its inverse (`update_inverse`, LowRankUpdate) instead of a new factorization. With a modal liquid B is the basis's
coordinates of its sloshing modes and C = B diag(c) B^T is diagonal on them.
"""
from __future__ import annotations

from typing import Any, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp

from ..physics.about import About
from ..fem.linalg import solve
from ..physics.terms import AbstractTerm, Kin, Rows


class TankDamping(NamedTuple):
    """One tank's damped modes: their frequencies (rad/s) and ratios (the ratio part may be traced)."""
    name: str
    omega: Any
    zeta: Any


class ModalDamping(AbstractTerm):
    """C d_dot on the deformable block's rows; no energy of its own (it only removes energy)."""
    B: jax.Array     # (nf, k) M Phi: the sloshing modes' mass-weighted shapes on the unknowns
    c: jax.Array     # (k,) 2 zeta_i omega_i, 1/s (zeta traceable: `tanks.<name>.damping.ratio`)
    about: About = eqx.field(static=True, default=About())     # the damped tanks and their ratios

    def rows(self, k: Kin) -> Rows:
        return Rows(jnp.zeros(6), self.B @ (self.c * (self.B.T @ k.d_dot)))

    def describe(self) -> tuple:
        return self.about.lines
    def update_inverse(self, inv, c_v):
        """The step block's inverse with c_v C added, by a low-rank update of `inv`. Formed from
        stop_gradient values: it only preconditions the iterations, whose solutions do not depend on it."""
        B, c = jax.lax.stop_gradient((self.B, self.c))
        W = inv @ B
        D = c_v * c
        G = B.T @ W
        S = solve(jnp.eye(c.shape[0]) + D[:, None] * G, jnp.diag(D))      # (I + D G)^-1 D = D (I + G D)^-1
        return LowRankUpdate(inv, W, S)


class LowRankUpdate(eqx.Module):
    """The inverse of A + U D U^T from A's: the step block with the liquid's modal damping, whose
    C = B diag(c) B^T has the rank of its few sloshing modes. By the Sherman-Morrison-Woodbury
    formula, in the form that allows zero entries of D (undamped modes):

        (A + U D U^T)^-1 = A^-1 - W D (I + G D)^-1 W^T,   W = A^-1 U,  G = U^T W

    W is formed once per run (k solves with the constant block's inverse, dense or sparse); a solve
    is A's and two thin products. D follows a traced damping ratio (a k x k solve per run)."""
    base: Any              # A^-1: a matrix, or an object with `@` (the sparse paths)
    W: jax.Array           # (nf, k)
    S: jax.Array           # (k, k) D (I + G D)^-1

    @property
    def shape(self):
        return self.base.shape

    def __matmul__(self, x):
        return self.base @ x - self.W @ (self.S @ (self.W.T @ x))
