"""The mooring lines' term of the residual: each line's quasi-static catenary (catenary.py) pulls its
fairlead, a force and a moment on the vessel (docs/guide/moorings.md).

Positions are taken in the frame whose origin is the vessel's COG at rest, axes inertial (the frame
of the vessel's position X0): the fairlead is at X0 + A r, the anchor at (x, y, z - cog_height) of
the scene. The line's force is a function of the fairlead's position only (quasi-static), so the
term's rows are too: Newton's tangent, HHT, `rao` and `modes --coupled` take the lines' stiffness
from JAX's derivative of these rows, which runs through the catenary's implicit-function
derivative, not its iterations.

A line may hold a body of `[[bodies]]` instead of the vessel (its `ends` entry: the body's slot, as
a connection's ends, physics/bodies.py): its fairlead is then in that body's frame, from its COG,
and its force and moment go to that body's rows (`Rows.frames`). Where a body's hydrostatics are
linear springs about its rest pose its buoyancy carries its lines' vertical pull at rest
(`carried_bodies`), as the vessel's does with linear hydrostatics; a body on its own hull
(nonlinear hydrostatics) sinks under that pull, as the vessel on its hull does.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..physics.about import About, held_by
from ..physics.bodies import VESSEL, body_rest, end_index, frame_slots, weight_balanced
from ..physics.kinematics import quat_from_rpy, rotation_matrix
from ..physics.terms import AbstractTerm, Config, Kin, Rows
from .catenary import lines_inverse, lines_settle, lines_spans, profile, solve_lines

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
    fairlead: jax.Array       # (n, 3) its body's frame, from its COG
    anchor: jax.Array         # (n, 3) COG-at-rest frame
    length: jax.Array         # (n,)
    weight: jax.Array
    ea: jax.Array
    friction: jax.Array
    anchor_height: jax.Array
    carried: jax.Array        # (3,)
    names: tuple = eqx.field(static=True, default=())
    about: About = eqx.field(static=True, default=About())
    ends: tuple = eqx.field(static=True, default=())   # per line: VESSEL or a body's slot; () all on the vessel
    n_bodies: int = eqx.field(static=True, default=0)  # the scene's bodies (those without lines included)
    carried_bodies: Optional[jax.Array] = None   # (S, 3) on the bodies, as `carried` on the vessel
    rest_X: Optional[jax.Array] = None           # (n, 3) each line's body's COG at rest (lines on bodies only)
    rest_A: Optional[jax.Array] = None           # (n, 3, 3) its attitude at rest

    @property
    def on_bodies(self) -> bool:
        """Whether some line holds a body of [[bodies]] (then the poses are per line)."""
        return any(e != VESSEL for e in self.ends)

    def frames(self, c: Config, A):
        """(X (n, 3), A (n, 3, 3)): each line's body's COG and attitude at configuration c (A the
        vessel's); the bodies at rest where c has none."""
        if c.Xs is None:
            vessel = np.array([e == VESSEL for e in self.ends])
            return jnp.where(vessel[:, None], c.X0, self.rest_X), jnp.where(vessel[:, None, None], A, self.rest_A)
        idx = frame_slots(self.ends)
        As = jax.vmap(rotation_matrix)(c.qs)
        return jnp.concatenate([c.X0[None], c.Xs])[idx], jnp.concatenate([A[None], As])[idx]

    def spans(self, X0, A):
        """(the fairleads (n, 3), their offsets from the anchors (n, 3), XF (n,), ZF (n,)); X0 (3,)
        and A (3, 3) the vessel's pose, or (n, 3) and (n, 3, 3) each line's body's (`frames`)."""
        p = X0 + (jnp.einsum("nij,nj->ni", A, self.fairlead) if A.ndim == 3 else self.fairlead @ A.T)
        d = p - self.anchor
        return p, d, jnp.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2 + _XF_EPS2), d[:, 2]

    def solve(self, X0, A, guess=None, inverse=None):
        """(n, 2) the lines' (H, V) at the pose (`guess`: a nearby solution, `inverse` the inverse
        of the residual's Jacobian there, catenary.solve_lines)."""
        _, _, XF, ZF = self.spans(X0, A)
        return solve_lines(XF, ZF, *self._values(), guess, inverse)

    def _values(self):
        return self.length, self.weight, self.ea, self.friction, self.anchor_height

    def state(self, X0, A, guess=None, inverse=None, fallback=True, at=None) -> LineState:
        """The lines at the pose (`guess`, `inverse`, `fallback`, `at`: catenary.solve_lines)."""
        p, d, XF, ZF = self.spans(X0, A)
        H, V = solve_lines(XF, ZF, *self._values(), guess, inverse, fallback, at).T
        _, _, LB, HA, VA = jax.vmap(profile)(H, V, self.length, self.weight, self.ea, self.friction, self.anchor_height)
        force = jnp.stack([-H * d[:, 0] / XF, -H * d[:, 1] / XF, -V], axis=1)
        return LineState(H, V, HA, VA, LB, force, p)

    def force_moment(self, X0, A, guess=None, inverse=None, fallback=True, at=None):
        """The lines' total force and moment about the COG, both inertial (the carried force left out)."""
        s = self.state(X0, A, guess, inverse, fallback, at)
        arm = s.fairlead - X0
        return s.force.sum(axis=0), jnp.cross(arm, s.force).sum(axis=0)

    def frame_rows(self, X, A, guess=None, inverse=None, fallback=True, at=None):
        """(S + 1, 6) the lines' generalized forces (force inertial, moment in the body's frame) on
        the vessel (first) and on each body, carried forces included; X, A per line (`frames`)."""
        s = self.state(X, A, guess, inverse, fallback, at)
        moment = jnp.einsum("nji,nj->ni", A, jnp.cross(s.fairlead - X, s.force))
        slot = frame_slots(self.ends)
        per = jax.ops.segment_sum(jnp.concatenate([s.force, moment], axis=1), slot, num_segments=self.n_bodies + 1)
        carried = jnp.concatenate([self.carried[None], self.carried_bodies])
        return per.at[:, :3].add(carried)

    # ------------------------------------------------------------ integrator states: a warm start
    # Every residual evaluation of a step solves every line. Started cold (the inextensible estimate,
    # then a bracketed Newton of some ten iterations) three lines added a third to the paper
    # example's step. The term's states carry each line's (H, V) at the end of the last step, the
    # inverse of its residual's Jacobian there and the profile's spans there (the residual at the
    # start without evaluating the profile), refreshed once a step (`state_settle`): chord
    # steps from there converge to round-off in two or three evaluations of the profile. The rows
    # take those chord steps alone (no loop, no cold fallback: the residual is traced again in every
    # linearisation of the step, and a fallback's code in each copy made compiling a moored run five
    # times longer); a line they leave above catenary.CHORD_TOL gives NaN, which fails the step with
    # its number. A step's end refreshes the states from the same chord steps and one Newton step
    # (round-off where the step took them; no loop, `catenary.lines_settle`); the run's start solves
    # the lines cold at the initial pose (`start`, solve/integrator.initial_state). No derivative goes
    # through the states; without states (a caller's own evaluation) the lines are solved cold.
    def _settled(self, X0, A, guess=None, inverse=None, at=None):
        X0, A = jax.lax.stop_gradient((X0, A))
        _, _, XF, ZF = self.spans(X0, A)
        if guess is None:           # cold (the rest pose, a run's initial pose)
            x = solve_lines(XF, ZF, *self._values())
            inv, at = lines_inverse(XF, ZF, *self._values(), x), lines_spans(*self._values(), x)
        else:                       # a step's end: its chord steps and one Newton step, no loop
            x, inv, at = lines_settle(XF, ZF, *self._values(), guess, inverse, at)
        # per line: (H, V), the inverse Jacobian (4), the profile's spans at (H, V) (`_warm`)
        return jax.lax.stop_gradient(jnp.concatenate([x, inv.reshape(-1, 4), at], axis=1).reshape(-1))

    @staticmethod
    def _warm(z):
        """(guess, inverse, at) from the states z (`_settled`)."""
        z = z.reshape(-1, 8)
        return z[:, :2], z[:, 2:6].reshape(-1, 2, 2), z[:, 6:]

    def state_init(self):
        if self.on_bodies:
            return self._settled(self.rest_X, self.rest_A)
        return self._settled(jnp.zeros(3), jnp.eye(3))

    def state_settle(self, z, c, start=False):
        X, A = self.frames(c, rotation_matrix(c.q)) if self.on_bodies else (c.X0, rotation_matrix(c.q))
        if start:
            return self._settled(X, A)
        return self._settled(X, A, *self._warm(z))

    def rows(self, k: Kin) -> Rows:
        guess, inverse, at = self._warm(k.z) if k.z.shape[0] else (None, None, None)
        # with states (the step's evaluations): the chord steps alone, the full solve at the step's end
        if self.on_bodies:
            per = self.frame_rows(*self.frames(k.c, k.A), guess, inverse, False, at)
            return Rows(-per[0], frames=-per[1:].reshape(-1))
        F, M = self.force_moment(k.c.X0, k.A, guess, inverse, False, at)
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
    index = end_index(b.name for b in scene.bodies) | {scene.vessel.name: VESSEL}
    ends = tuple(index[m.body] for m in lines)
    about = _about(scene, lines, ends, balanced)
    on_bodies = any(e != VESSEL for e in ends)
    held = {}
    if on_bodies:
        slot = frame_slots(ends)
        rest = np.concatenate([np.zeros((1, 3))] + [body_rest(b, cog)[None] for b in scene.bodies])
        turn = jnp.stack([jnp.eye(3)] + [rotation_matrix(quat_from_rpy(jnp.array([0.0, 0.0, b.heading])))
                                          for b in scene.bodies])
        held = dict(ends=ends, n_bodies=len(scene.bodies), carried_bodies=jnp.zeros((len(scene.bodies), 3)),
                    rest_X=jnp.asarray(rest[slot]), rest_A=turn[slot])
        # the bodies whose buoyancy carries their lines' pull at rest: those whose weight it balances there
        # (linear springs, or buoyancy off); a body on its own hull sinks under it, as the vessel does
        springs = jnp.asarray([float(weight_balanced(scene, b)) for b in scene.bodies])
    term = MooringLines(fairlead=jnp.asarray([m.fairlead for m in lines], dtype=float), anchor=jnp.asarray(anchor),
                        length=col("length"), weight=col("weight"), ea=col("ea"), friction=col("seabed_friction"),
                        anchor_height=col("anchor_height"), carried=jnp.zeros(3), names=tuple(m.name for m in lines),
                        about=about, **held)
    if outline:
        return term
    if on_bodies or balanced:
        return _carry_rest(term, balanced, springs if on_bodies else None)
    return term


def _about(scene, lines, ends, balanced: bool) -> About:
    """`check`'s lines of the catenary lines: those on the vessel, then each body's under its name
    (physics/about.py held_by), each group saying whether its buoyancy carries their pull at rest."""
    def words(group, carried: bool, whose: str) -> str:
        return (f"{len(group)} quasi-static elastic catenary line(s) {', '.join(repr(m.name) for m in group)}, "
                f"depth {scene.environment.depth:g} m"
                + (f" ({whose} buoyancy carries their vertical pull at rest)" if carried else ""))
    out = []
    mine = [m for m, e in zip(lines, ends) if e == VESSEL]
    if mine:
        out.append(("mooring", words(mine, balanced, "the")))
    for s, b in enumerate(scene.bodies):
        group = [m for m, e in zip(lines, ends) if e == s]
        if group:
            out.append(("mooring", held_by(b.name, words(group, weight_balanced(scene, b), "its"))))
    return About(*out)


@eqx.filter_jit
def _carry_rest(term: MooringLines, balanced: bool, springs=None) -> MooringLines:
    """The term with the lines' vertical pull at rest carried by the buoyancy (`build_mooring`) of the
    vessel where `balanced` and of the bodies where `springs` (S,) is 1: one program, cached by the
    term's structure (run eagerly, the cold solve's loops were compiled anew for every build)."""
    if term.on_bodies:
        per = term.frame_rows(term.rest_X, term.rest_A)
        up = jnp.zeros_like(per[:, :3]).at[:, 2].set(-per[:, 2])
        return eqx.tree_at(lambda t: (t.carried, t.carried_bodies), term,
                           (up[0] if balanced else jnp.zeros(3), up[1:] * springs[:, None]))
    F, _ = term.force_moment(jnp.zeros(3), jnp.eye(3))
    return eqx.tree_at(lambda t: t.carried, term, jnp.array([0.0, 0.0, -F[2]]))


def mooring_term(system) -> Optional[MooringLines]:
    """The system's mooring term, or None."""
    return next((t for t in system.terms if isinstance(t, MooringLines)), None)


@eqx.filter_jit
def _tensions(term: MooringLines, X0, q, Xs=None, qs=None):
    def one(x, qq, xs=None, qss=None):
        A = rotation_matrix(qq)
        pose = term.frames(Config(x, qq, jnp.zeros(0), xs, qss), A) if term.on_bodies else (x, A)
        s = term.state(*pose)
        return s.fairlead_tension, s.anchor_tension
    return jax.vmap(one)(X0, q) if Xs is None else jax.vmap(one)(X0, q, Xs, qs)


def mooring_datasets(system, X0, q, Xs=None, qs=None) -> dict:
    """The result file's `/mooring/<line>/fairlead_tension` and `/anchor_tension` (N) of frames
    whose vessel positions X0 (..., 3) and attitudes q (..., 4) are given, and the bodies' Xs
    (..., S, 3) and qs (..., S, 4) where lines hold bodies (the lines are quasi-static: their
    tensions are functions of the poses)."""
    term = mooring_term(system)
    return {} if term is None else line_datasets(term, X0, q, Xs, qs)


def line_datasets(term: MooringLines, X0, q, Xs=None, qs=None) -> dict:
    """mooring_datasets of one term."""
    lead = X0.shape[:-1]
    bodies = () if Xs is None or not term.on_bodies else (jnp.reshape(Xs, (-1, *Xs.shape[-2:])),
                                                          jnp.reshape(qs, (-1, *qs.shape[-2:])))
    tf, ta = _tensions(term, jnp.reshape(X0, (-1, 3)), jnp.reshape(q, (-1, 4)), *bodies)
    d = {}
    for i, name in enumerate(term.names):
        d[f"mooring/{name}/fairlead_tension"] = jnp.reshape(tf[:, i], lead)
        d[f"mooring/{name}/anchor_tension"] = jnp.reshape(ta[:, i], lead)
    return d
