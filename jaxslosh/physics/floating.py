"""A floating rigid body: the one family of the vessel (system.System) and each `[[bodies]]` body
(bodies.Floating), docs/design.md "Floating bodies".

A floating body is a frame at its COG with six rigid unknowns (translations inertial, rotations on
the group, in body axes) and, where it carries tanks, the deformable unknowns of their liquid. Its
rows, energies and mass scales are the sums of its terms' (the same term classes for every body:
vessel.py `RigidBody`, the restoring `AbstractRestoring` or the hull's pressure and `Weight`,
seakeeping.py's damping and wave excitation, its liquid and the terms on it), each evaluated with
the body's own kinematics (`frame_kin`: its rotation A(q) and gravity in its axes). A final body says
which terms it has, in the order their rows are summed (`frame_terms`: the sum's order is the
residual's rounding); the sums are this class's, the same for the vessel and every body.
"""
from __future__ import annotations

import abc
from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp

from .kinematics import rotation_matrix, tv3
from .terms import Config, Kin


def gravity_in(A, gravity):
    """Gravity (0, 0, -g) in the axes of a body whose rotation matrix is A."""
    return tv3(A, jnp.array([0.0, 0.0, -gravity]))


def frame_kin(c: Config, V0, omega, d_dot, a6, d_acc, t, gravity, attitude: Optional[jax.Array] = None) -> Kin:
    """A body's Kin at configuration c: its rotation A(c.q), and gravity in its axes (in those of
    `attitude` instead where given: gravity frozen at the start, AbstractFloating.gravity_attitude)."""
    A = rotation_matrix(c.q)
    return Kin(c, V0, omega, d_dot, a6, d_acc, jnp.asarray(t), jnp.zeros((0,)), A,
               gravity_in(A if attitude is None else attitude, gravity))


class AbstractFloating(eqx.Module):
    """A floating rigid body (the vessel, or one of the `[[bodies]]`): the sums of its terms'
    rows, energies and mass scales, and the gravity in its axes. Each final body gives its terms
    (`frame_terms`), its attitude at the start (`start_attitude`) and whether its gravity turns with
    it (`gravity_turning`: off, the liquid it carries sees gravity frozen at the start, eq. 32
    without its turning; the scene's `[effects] gravity_turning` for every body alike: a static
    field of each final, not declared here, since a field declared on the abstract class would
    come before the finals' fields without defaults)."""

    @abc.abstractmethod
    def start_attitude(self) -> jax.Array:
        """(4,) its attitude at t = 0 (Euler parameters)."""

    def gravity_attitude(self) -> Optional[jax.Array]:
        """None where its gravity turns with it; else its rotation at the start, where gravity
        stays in its axes (`frame_kin`'s `attitude`)."""
        return None if self.gravity_turning else rotation_matrix(self.start_attitude())

    @abc.abstractmethod
    def frame_terms(self) -> tuple:
        """Its terms, in the order their rows are summed: the rigid ones, its liquid, the terms on
        its liquid."""

    def frame_rows(self, k: Kin, z: Optional[tuple] = None):
        """(rigid rows (6,), deformable rows or None, rows on the bodies' frames or None): the sum of
        its terms' rows at k, each with its own integrator states `z` (in frame_terms' order; None:
        those of t = 0)."""
        terms = self.frame_terms()
        rigid, d, frames = None, None, None
        for term, zi in zip(terms, tuple(t.state_init() for t in terms) if z is None else z, strict=True):
            with jax.named_scope(type(term).__name__):
                r = term.rows(k._replace(z=zi))
            rigid = r.rigid if rigid is None else rigid + r.rigid
            if r.d is not None:
                d = r.d if d is None else d + r.d
            if r.frames is not None:
                frames = r.frames if frames is None else frames + r.frames
        return rigid, d, frames

    def frame_kinetic(self, k: Kin):
        return sum((term.kinetic(k) for term in self.frame_terms()), jnp.zeros(()))

    def frame_potential(self, k: Kin):
        return sum((term.potential(k) for term in self.frame_terms()), jnp.zeros(()))

    def frame_mass_scale(self):
        """(6,) its terms' characteristic masses of the rigid unknowns (kg, kg m^2)."""
        return sum((term.mass_scale() for term in self.frame_terms()), jnp.zeros(6))
