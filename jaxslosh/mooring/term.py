"""The mooring lines' term of the residual: each line's quasi-static catenary (catenary.py) pulls its
fairlead, a force and a moment on the vessel (docs/guide/moorings.md).

Positions are taken in the frame whose origin is the vessel's COG at rest, axes inertial (the frame
of the vessel's position X0): the fairlead is at X0 + A r, the anchor at (x, y, z - cog_height) of
the scene. The line's force is a function of the fairlead's position only (quasi-static), so the
term's rows are too: Newton's tangent, HHT, `rao` and `modes --coupled` take the lines' stiffness
from JAX's derivative of these rows, which runs through the catenary's implicit-function
derivative, not its iterations.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..physics.about import About
from ..physics.kinematics import rotation_matrix
from ..physics.terms import AbstractTerm, Kin, Rows
from .catenary import lines_inverse, profile, solve_lines

#: m^2: keeps the horizontal direction defined (and differentiable) with the fairlead right above its anchor
_XF_EPS2 = 1e-12


class LineState(NamedTuple):
    """Each line's solution at one pose ((n,) arrays; `force` (n, 3) on the fairlead, inertial)."""
    horizontal: jax.Array
    vertical: jax.Array
    anchor_horizontal: jax.Array
    anchor_vertical: jax.Array
    seabed_length: jax.Array
    force: jax.Array
    fairlead: jax.Array          # (n, 3) the fairleads' positions, COG-at-rest frame

    @property
    def fairlead_tension(self):
        return jnp.hypot(self.horizontal, self.vertical)

    @property
    def anchor_tension(self):
        return jnp.hypot(self.anchor_horizontal, self.anchor_vertical)


class MooringLines(AbstractTerm):
    """Quasi-static catenary lines on the vessel. `carried` (3,) is a constant force added to the
    lines': with linear hydrostatics (springs about the rest position) the buoyancy carries the
    lines' vertical pull at rest, as the displacement of a moored platform does, so the rest position
    stays the equilibrium in heave (docs/guide/moorings.md); zero with the hull's own hydrostatics."""
    fairlead: jax.Array       # (n, 3) body frame, from the COG
    anchor: jax.Array         # (n, 3) COG-at-rest frame
    length: jax.Array         # (n,)
    weight: jax.Array
    ea: jax.Array
    friction: jax.Array
    anchor_height: jax.Array
    carried: jax.Array        # (3,)
    names: tuple = eqx.field(static=True, default=())
    about: About = eqx.field(static=True, default=About())

    def spans(self, X0, A):
        """(the fairleads (n, 3), their offsets from the anchors (n, 3), XF (n,), ZF (n,))."""
        p = X0[None, :] + self.fairlead @ A.T
        d = p - self.anchor
        return p, d, jnp.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2 + _XF_EPS2), d[:, 2]

    def solve(self, X0, A, guess=None, inverse=None):
        """(n, 2) the lines' (H, V) at the pose (`guess`: a nearby solution, `inverse` the inverse
        of the residual's Jacobian there, catenary.solve_lines)."""
        _, _, XF, ZF = self.spans(X0, A)
        return solve_lines(XF, ZF, *self._values(), guess, inverse)

    def _values(self):
        return self.length, self.weight, self.ea, self.friction, self.anchor_height

    def state(self, X0, A, guess=None, inverse=None) -> LineState:
        p, d, XF, ZF = self.spans(X0, A)
        H, V = solve_lines(XF, ZF, *self._values(), guess, inverse).T
        _, _, LB, HA, VA = jax.vmap(profile)(H, V, self.length, self.weight, self.ea, self.friction, self.anchor_height)
        force = jnp.stack([-H * d[:, 0] / XF, -H * d[:, 1] / XF, -V], axis=1)
        return LineState(H, V, HA, VA, LB, force, p)

    def force_moment(self, X0, A, guess=None, inverse=None):
        """The lines' total force and moment about the COG, both inertial (the carried force left out)."""
        s = self.state(X0, A, guess, inverse)
        arm = s.fairlead - X0[None, :]
        return s.force.sum(axis=0), jnp.cross(arm, s.force).sum(axis=0)

    # ------------------------------------------------------------ integrator states: a warm start
    # Every residual evaluation of a step solves every line. Started cold (the inextensible estimate,
    # then a bracketed Newton of some ten iterations) three lines added a third to the paper
    # example's step. The term's states carry each line's (H, V) at the end of the last step and
    # the inverse of its residual's Jacobian there (refreshed once a step, `state_settle`): chord
    # steps from there converge to round-off in two or three evaluations of the profile. The states
    # only start the iterations: the rows are the converged solution whatever they hold (cold where
    # a caller gives none), and no derivative goes through them.
    def _settled(self, X0, A, guess=None, inverse=None):
        X0, A = jax.lax.stop_gradient((X0, A))
        x = self.solve(X0, A, guess, inverse)
        _, _, XF, ZF = self.spans(X0, A)
        inv = lines_inverse(XF, ZF, *self._values(), x)
        return jax.lax.stop_gradient(jnp.concatenate([x, inv.reshape(-1, 4)], axis=1).reshape(-1))

    def state_init(self):
        return self._settled(jnp.zeros(3), jnp.eye(3))

    def state_settle(self, z, c):
        z = z.reshape(-1, 6)
        return self._settled(c.X0, rotation_matrix(c.q), z[:, :2], z[:, 2:].reshape(-1, 2, 2))

    def rows(self, k: Kin) -> Rows:
        z = k.z.reshape(-1, 6)
        guess, inverse = (z[:, :2], z[:, 2:].reshape(-1, 2, 2)) if k.z.shape[0] else (None, None)
        F, M = self.force_moment(k.c.X0, k.A, guess, inverse)
        return Rows(-jnp.concatenate([F + self.carried, k.A.T @ M]))

    def describe(self) -> tuple:
        return self.about.lines


def build_mooring(scene, balanced: bool, outline: bool = False, params: Optional[dict] = None) -> MooringLines:
    """The term of the scene's `[[mooring]]` lines; `balanced`: the vessel's hydrostatics are linear
    springs about the rest position (then the buoyancy carries the lines' vertical pull at rest);
    `params`: canonical keys `mooring.<name>.<key>` that replace the scene's values (tracers too)."""
    lines = [m for m in scene.mooring if m.model == "catenary"]
    cog = scene.vessel.cog_height
    P = (params or {}).get
    col = lambda key: jnp.stack([jnp.asarray(P(f"mooring.{m.name}.{key}", getattr(m, key)), dtype=float)  # noqa: E731
                                 for m in lines])
    anchor = np.array([m.anchor for m in lines], dtype=float) - np.array([0.0, 0.0, cog])
    carried_words = (" (the buoyancy carries their vertical pull at rest: linear hydrostatics)" if balanced else "")
    about = About(("mooring", f"{len(lines)} quasi-static elastic catenary line(s) "
                              f"{', '.join(repr(m.name) for m in lines)}, depth {scene.environment.depth:g} m"
                              + carried_words))
    term = MooringLines(fairlead=jnp.asarray([m.fairlead for m in lines], dtype=float), anchor=jnp.asarray(anchor),
                        length=col("length"), weight=col("weight"), ea=col("ea"), friction=col("seabed_friction"),
                        anchor_height=col("anchor_height"), carried=jnp.zeros(3), names=tuple(m.name for m in lines),
                        about=about)
    if balanced and not outline:
        F, _ = term.force_moment(jnp.zeros(3), jnp.eye(3))
        term = eqx.tree_at(lambda t: t.carried, term, jnp.array([0.0, 0.0, -F[2]]))
    return term


def mooring_term(system) -> Optional[MooringLines]:
    """The system's mooring term, or None."""
    return next((t for t in system.terms if isinstance(t, MooringLines)), None)


@eqx.filter_jit
def _tensions(term: MooringLines, X0, q):
    def one(x, qq):
        s = term.state(x, rotation_matrix(qq))
        return s.fairlead_tension, s.anchor_tension
    return jax.vmap(one)(X0, q)


def mooring_datasets(system, X0, q) -> dict:
    """The result file's `/mooring/<line>/fairlead_tension` and `/anchor_tension` (N) of frames
    whose vessel positions X0 (..., 3) and attitudes q (..., 4) are given (the lines are
    quasi-static: their tensions are functions of the pose)."""
    term = mooring_term(system)
    return {} if term is None else line_datasets(term, X0, q)


def line_datasets(term: MooringLines, X0, q) -> dict:
    """mooring_datasets of one term."""
    lead = X0.shape[:-1]
    tf, ta = _tensions(term, jnp.reshape(X0, (-1, 3)), jnp.reshape(q, (-1, 4)))
    d = {}
    for i, name in enumerate(term.names):
        d[f"mooring/{name}/fairlead_tension"] = jnp.reshape(tf[:, i], lead)
        d[f"mooring/{name}/anchor_tension"] = jnp.reshape(ta[:, i], lead)
    return d
