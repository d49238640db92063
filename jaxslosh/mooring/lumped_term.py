"""A lumped-mass mooring line as a term of the vessel's residual (docs/guide/moorings-lumped.md).

The line's moving nodes and their velocities are the term's integrator states (terms.AbstractTerm's
hooks): every step advances them from t_n to t_{n+1} with the fairlead's positions and velocities
at both ends (`state_advance_config`: the vessel's configuration and velocities at t_n and at the
step's unknown t_{n+1}), sub-stepped inside the step (lumped.advance). The force on the vessel is
the line's load on the fairlead at t_{n+1} (the last segment's tension with the fairlead node's
half segment of weight and drag, lumped.fairlead_force), applied at the fairlead: translation
rows in the inertial frame, the moment p x (A^T F) about the COG in the body frame. Being a
function of the states at t_{n+1}, which follow the unknown configuration, it is implicit in the
step as the radiation memory is: the Newton iterations see the line's response to the vessel's
motion within the step.

Frames: `fairlead` is in the body frame from the COG; the line's anchor and seabed in the frame of
the vessel's COG position X0 (its origin the COG's rest position, z up): `lumped_line_term` shifts
the scene's anchor (x, y from the COG at rest, z from the still-water level) by the COG's height.

A line may hold a body of `[[bodies]]` instead of the vessel (`end`: the body's slot, as a
connection's ends, physics/bodies.py): its fairlead is then in that body's frame and moves with that
body's pose and velocities (the configuration's `Xs`, `qs` and the step's rigid velocities of every
frame: `Kin.vs` in the rows, the frames' velocities in the states' advance), and its force and
moment go to that body's rows (`Rows.frames`), as the catenary lines' do (mooring/term.py).
"""
from __future__ import annotations

import dataclasses
import math
from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..io.line_energy import LINE_ENERGY
from ..io.status import is_traced
from ..physics.about import held_by
from ..physics.bodies import VESSEL, bodies_term, body_rest, end_index, frame_slots, point_motion, weight_balanced
from ..physics.kinematics import quat_from_rpy, rotation_matrix
from ..physics.terms import AbstractTerm, Config, Kin, Rows
from . import lumped as lm
from ..scene.types import SceneError
from .lumped_keys import LUMPED_KEYS, LUMPED_TRACEABLE, read_lumped  # noqa: F401  (the loader's reader, JAX-free)


def _fairlead(p_b, c: Config, V0, omega):
    """The fairlead's inertial position and velocity for the vessel's point p_b."""
    return point_motion(p_b, (c.X0, rotation_matrix(c.q), V0, omega))


class LumpedLineTerm(AbstractTerm):
    """One lumped-mass line from a fixed anchor to a fairlead on the vessel. States: the moving
    nodes' positions and velocities, flattened ((N - 1) * 6,). `substeps` (static): the line's
    sub-steps per vessel step, from the step given at construction (a smaller step, such as a
    retried step's sub-steps, only makes them smaller)."""
    line: lm.LumpedLine
    fairlead: jax.Array      # (3,) body frame, from the COG
    nodes0: jax.Array        # (N - 1, 3) the static shape at the start
    # (3,) a constant force added to the line's: with linear hydrostatics (springs about the rest
    # position) the buoyancy carries the line's vertical pull at rest, as for the catenary lines
    carried: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(3))
    name: str = eqx.field(static=True, default="line")
    substeps: int = eqx.field(static=True, default=1)
    end: int = eqx.field(static=True, default=VESSEL)    # the body it holds: VESSEL or a body's slot
    holder: str = eqx.field(static=True, default="")     # that body's name ("" for the vessel): check's words

    # ------------------------------------------------------------ states
    def state_init(self):
        # the nodes, their velocities, the dissipated work and the fairlead's work (lm.LineState)
        return jnp.concatenate([self.nodes0.reshape(-1), jnp.zeros(self.nodes0.size + 2)])

    def split(self, z) -> lm.LineState:
        n = self.nodes0.size
        return lm.LineState(z[:n].reshape(-1, 3), z[n:2 * n].reshape(-1, 3), z[2 * n], z[2 * n + 1])

    def state_coefficients(self, h):
        return jnp.asarray(h)

    def state_advance(self, z, v_old, v_new, coef):
        raise TypeError("a lumped line's states follow the vessel's configuration: state_advance_config")

    def state_advance_config(self, z, c_old, v_old, c_new, v_new, coef):
        return self.advance_at(z, (c_old.X0, rotation_matrix(c_old.q), v_old[:3], v_old[3:6]),
                               (c_new.X0, rotation_matrix(c_new.q), v_new[:3], v_new[3:6]), coef)

    def advance_at(self, z, pose_old, pose_new, coef):
        """The states at t_{n+1}, its body at `pose_old` at t_n and `pose_new` at t_{n+1} (physics/bodies.py point_motion's poses)."""
        p0, u0 = point_motion(self.fairlead, pose_old)
        p1, u1 = point_motion(self.fairlead, pose_new)
        s = lm.advance(self.line, self.split(z), p0, u0, p1, u1, coef, self.substeps)
        return jnp.concatenate([s.r.reshape(-1), s.v.reshape(-1), jnp.stack([s.dissipated, s.work])])

    # ------------------------------------------------------------ forces
    def force(self, c: Config, V0, omega, z):
        """The line's force on the fairlead (3,), inertial, for the vessel at (c, V0, omega) and the
        line's states z."""
        return self.force_at((c.X0, rotation_matrix(c.q), V0, omega), z)

    def force_at(self, pose, z):
        """`force` with its body at `pose` (point_motion's)."""
        p, u = point_motion(self.fairlead, pose)
        s = self.split(z)
        return lm.fairlead_force(self.line, s.r, s.v, p, u)

    def rows_at(self, pose, z):
        """(6,) its rows on its body at `pose`: minus the force (inertial, the carried one added) and
        its moment about the COG in the body's frame."""
        F = self.force_at(pose, z)
        return -jnp.concatenate([F + self.carried, jnp.cross(self.fairlead, pose[1].T @ F)])

    def rows(self, k: Kin) -> Rows:
        return Rows(self.rows_at((k.c.X0, k.A, k.V0, k.omega), k.z))

    def tension(self, c: Config, V0, omega, z):
        """|force on the fairlead| (N)."""
        return jnp.linalg.norm(self.force(c, V0, omega, z))

    def nodes(self, c: Config, z):
        """Every node (N + 1, 3) in the X0 frame: anchor, moving nodes, fairlead (the result file's
        `/mooring/<line>/nodes`)."""
        return self.nodes_at(c.X0, rotation_matrix(c.q), z)

    def nodes_at(self, X, A, z):
        """`nodes` with its body's COG at X, its rotation A."""
        s = self.split(z)
        return jnp.concatenate([self.line.anchor[None], s.r, (X + A @ self.fairlead)[None]], axis=0)

    def describe(self) -> tuple:
        ln = self.line
        text = (f"lumped line {self.name}: {ln.segments} segments, {self.substeps} sub-steps "
                f"of the step (symplectic Euler, stable sub-step {ln.substep_max:.3g} s)")
        return (("mooring", held_by(self.holder, text) if self.holder else text),)


class LumpedLines(AbstractTerm):
    """Lumped lines of one shape (the same segments and sub-steps) as one term: each line's
    LumpedLineTerm equations mapped over the lines (jax.vmap) on their arrays stacked, so that the
    step's program holds one line's sub-steps whatever the number of lines (each line a term of
    its own repeated them per line in every copy of the residual: the FLNG scene's eight lines
    made two thirds of its program, docs/benchmarks.md). States: (lines, the line's states).
    Lines on bodies of [[bodies]] (`ends`, static: each line's VESSEL or body slot; `n_bodies` the
    scene's bodies) take their body's pose, gathered per line, and put their rows on its frame."""
    lines: tuple             # LumpedLineTerm, one per line, all of one shape (group_lines)
    ends: tuple = eqx.field(static=True, default=())    # per line: VESSEL or a body's slot; () all on the vessel
    n_bodies: int = eqx.field(static=True, default=0)

    @property
    def names(self) -> tuple:
        return tuple(t.name for t in self.lines)

    @property
    def on_bodies(self) -> bool:
        """Whether some line holds a body of [[bodies]] (then the poses are per line)."""
        return any(e != VESSEL for e in self.ends)

    def stacked(self) -> LumpedLineTerm:
        """The lines as one LumpedLineTerm whose arrays have a leading axis of lines."""
        plain = [dataclasses.replace(t, name="", end=VESSEL, holder="") for t in self.lines]
        return jax.tree_util.tree_map(lambda *x: jnp.stack(x), *plain)

    def poses(self, c: Config, v, A=None):
        """(pose, its vmap axis): the vessel's (X0, A, V0, omega) for every line (axis None) where all
        hold the vessel, else each line's body's, stacked (axis 0); `v` the rigid velocities of every
        frame (the vessel's six, then six per body), `A` the vessel's rotation where known."""
        A = rotation_matrix(c.q) if A is None else A
        vessel = (c.X0, A, v[:3], v[3:6])
        if not self.on_bodies:
            return vessel, None
        S = self.n_bodies
        if c.Xs is None or v.shape[0] < 6 + 6 * S:
            raise ValueError("lumped lines on bodies need the bodies' poses and velocities (the step's)")
        vs = v[6:6 + 6 * S].reshape(S, 6)
        idx = frame_slots(self.ends)
        every = (jnp.concatenate([c.X0[None], c.Xs]), jnp.concatenate([A[None], jax.vmap(rotation_matrix)(c.qs)]),
                 jnp.concatenate([v[None, :3], vs[:, :3]]), jnp.concatenate([v[None, 3:6], vs[:, 3:]]))
        return tuple(x[idx] for x in every), 0

    def state_init(self):
        return jnp.stack([t.state_init() for t in self.lines])

    def state_coefficients(self, h):
        return jnp.asarray(h)

    def state_advance(self, z, v_old, v_new, coef):
        raise TypeError("a lumped line's states follow the vessel's configuration: state_advance_config")

    def state_advance_config(self, z, c_old, v_old, c_new, v_new, coef):
        (p0, ax), (p1, _) = self.poses(c_old, v_old), self.poses(c_new, v_new)
        return jax.vmap(lambda t, zi, a, b: t.advance_at(zi, a, b, coef), in_axes=(0, 0, ax, ax))(
            self.stacked(), z, p0, p1)

    def rows(self, k: Kin) -> Rows:
        v = k.v6 if k.vs is None else jnp.concatenate([k.v6, k.vs])
        pose, ax = self.poses(k.c, v, k.A)
        rigid = jax.vmap(lambda t, zi, p: t.rows_at(p, zi), in_axes=(0, 0, ax))(self.stacked(), k.z, pose)
        if not self.on_bodies:
            return Rows(jnp.sum(rigid, axis=0))
        slot = frame_slots(self.ends)
        per = jax.ops.segment_sum(rigid, slot, num_segments=self.n_bodies + 1)
        return Rows(per[0], frames=per[1:].reshape(-1))

    def observe(self, z, c: Config, v) -> tuple:
        """(fairlead tensions (n,), anchor tensions (n,), nodes (n, N + 1, 3), energies {part: (n,)}) of
        the lines (the energies: lm.energies, the dissipated work and the fairlead's); `v` the rigid
        velocities of every frame (`poses`)."""
        def one(t, zi, pose):
            p, u = point_motion(t.fairlead, pose)
            s = t.split(zi)
            parts = dict(lm.energies(t.line, s.r, s.v, p), dissipated=s.dissipated, fairlead_work=s.work)
            return (jnp.linalg.norm(lm.fairlead_force(t.line, s.r, s.v, p, u)),
                    jnp.linalg.norm(lm.anchor_force(t.line, s.r, s.v, p, u)), t.nodes_at(pose[0], pose[1], zi),
                    {k: parts[k] for k in LINE_ENERGY})
        pose, ax = self.poses(c, v)
        return jax.vmap(one, in_axes=(0, 0, ax))(self.stacked(), z, pose)

    def describe(self) -> tuple:
        return sum((t.describe() for t in self.lines), ())


def group_lines(terms, n_bodies: int = 0) -> tuple:
    """The line terms as LumpedLines, one per shape (segments, sub-steps), in their first line's
    order; `n_bodies`: the scene's [[bodies]] (where lines hold some)."""
    groups: dict = {}
    for t in terms:
        groups.setdefault((t.line.segments, t.line.substep_max, t.substeps), []).append(t)
    return tuple(LumpedLines(tuple(g), tuple(t.end for t in g) if any(t.end != VESSEL for t in g) else (),
                             n_bodies) for g in groups.values())


@jax.jit
def _rest_shape(line, p_b, X0, q):
    """(nodes, converged, the line's force on the fairlead) of its static shape with the vessel at
    (X0, q): one program, compiled once for every line of the same segments (its steps run op by
    op took a compilation of each operation, a third of the FLNG scene's build)."""
    fair, _ = _fairlead(p_b, Config(X0, q, jnp.zeros(0)), jnp.zeros(3), jnp.zeros(3))
    nodes, ok = lm.static_shape(line, fair)
    return nodes, ok, lm.fairlead_force(line, nodes, jnp.zeros_like(nodes), fair, jnp.zeros(3))


def _traced_rest(line, p_b, X0, q):
    """_rest_shape for traced values (params, a sweep's runs): solved in the trace, differentiable
    (lm.static_shape_traced); a shape that did not converge gives NaN nodes, which the run's first
    step reports (a traced flag cannot raise here)."""
    fair, _ = _fairlead(p_b, Config(X0, q, jnp.zeros(0)), jnp.zeros(3), jnp.zeros(3))
    nodes, ok = lm.static_shape_traced(line, fair)
    nodes = jnp.where(ok, nodes, jnp.nan)
    return nodes, lm.fairlead_force(line, nodes, jnp.zeros_like(nodes), fair, jnp.zeros(3))


def _static(line, p_b, X0, q, name):
    """(nodes, the line's force on the fairlead) of the line's static shape with the vessel at (X0,
    q), solved in float64 whatever the caller's precision (a description, `jaxslosh check`, may
    build the model in float32, where the energy's round-off stops the solve short of its
    tolerance), in the caller's precision. Traced values: _traced_rest."""
    if is_traced((line, p_b, X0, q)):
        return _traced_rest(line, p_b, X0, q)
    with jax.enable_x64(True):
        f64 = lambda x: jnp.asarray(x, dtype=jnp.float64)  # noqa: E731
        nodes, ok, F = _rest_shape(jax.tree_util.tree_map(f64, line), f64(p_b), f64(X0), f64(q))
        nodes, ok, F = np.asarray(nodes), bool(ok), np.asarray(F)
    if not ok:
        raise ValueError(f"mooring.{name}: the line's static shape did not converge")
    return jnp.asarray(nodes, dtype=float), jnp.asarray(F, dtype=float)


def lumped_line_term(c0: Config, dt: float, *, name: str, fairlead, anchor, length, weight, ea,
                     depth: Optional[float] = None, cog_height: float = 0.0, gravity: float = 9.81,
                     water_density: float = 1025.0, current=(0.0, 0.0, 0.0), balanced: bool = False,
                     end: int = VESSEL, rest=None, holder: str = "", traced=None, **lumped) -> LumpedLineTerm:
    """The term of one `[[mooring]]` table with `model = "lumped"`: the scene's values (fairlead in
    the body frame from the COG; anchor x, y from the COG at rest and z from the still-water level;
    `depth` the water depth, None without a seabed; `cog_height` the COG's height above the
    still-water level at rest) and the lumped-only keys (LUMPED_KEYS), for the vessel starting at
    c0 (its lines start in their static shape there) and stepped at dt. `balanced`: the vessel's
    hydrostatics are linear springs about the rest position (X0 = 0, level), whose buoyancy then
    carries the line's vertical pull there (`carried`, as the catenary lines' term does). `end`: the
    body it holds (VESSEL, or a [[bodies]] body's slot: then c0 is that body's initial pose and
    `rest` = (X, q) its rest pose, where its springs are balanced; `holder` its name). Bad values raise ValueError
    naming the key (`mooring.<name>.<key>`). `traced`: {"length" | "weight" | "ea": value} that replace
    the scene's (tracers too: params, a sweep's runs); the sub-step stays the scene values' (static)."""
    unknown = set(lumped) - set(LUMPED_KEYS)
    if unknown:
        raise ValueError(f"mooring.{name}.{sorted(unknown)[0]}: not a key of a lumped line")
    kw = dict(LUMPED_KEYS, **lumped)
    checks = {"segments": kw["segments"] >= 2 and int(kw["segments"]) == kw["segments"],
              "diameter": kw["diameter"] > 0, "length": length > 0, "ea": ea > 0,
              "seabed_stiffness": kw["seabed_stiffness"] >= 0, "seabed_damping": kw["seabed_damping"] >= 0,
              "mass": kw["mass"] is None or kw["mass"] > 0,
              "cd": len(kw["cd"]) == 2 and min(kw["cd"]) >= 0, "ca": len(kw["ca"]) == 2 and min(kw["ca"]) >= 0}
    for key, ok in checks.items():
        if not ok:
            raise ValueError(f"mooring.{name}.{key}: out of range ({kw.get(key, locals().get(key))!r})")
    shift = jnp.array([0.0, 0.0, -cog_height])
    seabed = -math.inf if depth is None else -float(depth) - cog_height
    common = dict(segments=int(kw["segments"]), diameter=kw["diameter"], mass=kw["mass"], cd=tuple(kw["cd"]),
                  ca=tuple(kw["ca"]), internal_damping=kw["internal_damping"], seabed_z=seabed,
                  seabed_stiffness=kw["seabed_stiffness"], seabed_damping=kw["seabed_damping"],
                  rho=water_density, gravity=gravity, current=current)
    anchor = jnp.asarray(anchor, dtype=float) + shift
    line = lm.lumped_line(anchor, length, weight, ea, **common)
    if traced:        # the traced values, on the sub-step of the scene's (static)
        own = dict(length=length, weight=weight, ea=ea) | dict(traced)
        line = lm.lumped_line(anchor, own["length"], own["weight"], own["ea"], substep=line.substep_max, **common)
    p_b = jnp.asarray(fairlead, dtype=float)
    nodes0, F0 = _static(line, p_b, c0.X0, c0.q, name)
    carried = jnp.zeros(3)
    if balanced:       # the pull at the rest pose (the vessel's: X0 = 0, level), where the springs are balanced
        rest = (np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])) if rest is None else \
            tuple(np.asarray(x, dtype=float) for x in rest)
        # a body starting at rest: the same solve as its start's (half the lines' build)
        at_rest = all(np.array_equal(np.asarray(a, dtype=float), b) for a, b in zip((c0.X0, c0.q), rest))
        _, F = (None, F0) if at_rest else _static(line, p_b, *rest, name)
        carried = jnp.zeros(3).at[2].set(-F[2])
    return LumpedLineTerm(line, p_b, nodes0, carried, name, line.substeps(dt), end, holder)


# ---------------------------------------------------------------------------- the scene's tables
def build_lumped_lines(scene, balanced: bool, q0=None, params=None) -> tuple:
    """The terms of the scene's `[[mooring]]` lines with `model = "lumped"` (each line's lumped
    values in its `lumped` attribute, read_lumped's pairs; absent: the defaults), each in its static
    shape with the vessel at its initial position and attitude q0 (identity when None), or the body
    of [[bodies]] it holds at that body's initial pose, sub-stepped for the scene's dt. `balanced`:
    the vessel's hydrostatics are linear springs; a body's lines are carried where its own are.
    `params`: canonical keys `mooring.<name>.length | weight | ea` that replace the scene's values
    (tracers too; the loader's keys refuse the others on a lumped line: scene/keys.py)."""
    lines = [m for m in scene.mooring if getattr(m, "model", "catenary") == "lumped"]
    if not lines:
        return ()
    if getattr(scene.simulation, "energy_projection", False):
        raise SceneError("simulation.energy_projection", "cannot hold the energy with lumped mooring lines "
                                                         "(their drag and damping take energy out of the vessel)")
    env = scene.environment
    X0 = jnp.asarray(scene.vessel.initial.position, dtype=float)
    q = jnp.array([1.0, 0.0, 0.0, 0.0]) if q0 is None else jnp.asarray(q0, dtype=float)
    c0 = Config(X0, q, jnp.zeros(0))
    index = end_index(b.name for b in getattr(scene, "bodies", ())) | {getattr(scene.vessel, "name", "vessel"): VESSEL}
    terms = []
    for m in lines:
        end = index[getattr(m, "body", "vessel")]
        held = dict(balanced=balanced) if end == VESSEL else _body_pose(scene, end)
        start = held.pop("c0", c0)
        try:
            terms.append(lumped_line_term(
                start, scene.simulation.dt, name=m.name, fairlead=m.fairlead, anchor=m.anchor, length=m.length,
                weight=m.weight, ea=m.ea, depth=env.depth, cog_height=getattr(scene.vessel, "cog_height", 0.0),
                gravity=env.gravity, water_density=env.water_density, **held,
                traced={k: params[f"mooring.{m.name}.{k}"] for k in LUMPED_TRACEABLE
                        if f"mooring.{m.name}.{k}" in (params or {})},
                **dict(getattr(m, "lumped", ()))))
        except ValueError as e:
            raise SceneError(f"mooring.{m.name}", str(e)) from e
    return tuple(terms)


def _body_pose(scene, s: int) -> dict:
    """lumped_line_term's arguments for a line on the body of slot s: its initial pose c0 (as
    assemble/bodies.py starts it: its rest pose offset by its initial values), its rest pose and
    whether its buoyancy carries the line's pull at rest (physics/bodies.py weight_balanced)."""
    b = scene.bodies[s]
    X = jnp.asarray(body_rest(b, scene.vessel.cog_height))
    turn = jnp.array([0.0, 0.0, b.heading])
    q0 = quat_from_rpy(jnp.asarray(b.initial.roll_pitch_yaw, dtype=float) + turn)
    c0 = Config(X + jnp.asarray(b.initial.position, dtype=float), q0, jnp.zeros(0))
    return dict(c0=c0, end=s, rest=(X, quat_from_rpy(turn)), balanced=weight_balanced(scene, b), holder=b.name)


def lumped_observe(system, z: tuple, c: Config, v) -> dict:
    """For the result file, at one frame (the integrator state's configuration c, velocities v (the
    vessel's six, then six per [[bodies]] body, as the state's) and the terms' states z, as
    State.z): `mooring/<line>/fairlead_tension`, `anchor_tension` (N) and `nodes` ((N + 1, 3), in
    the frame of the vessel's position X0) of each lumped line, and its energies
    `energy/mooring/<line>/<part>` (J: lm.energies, the dissipated work and the fairlead's)."""
    out = {}
    for term, zi in zip(system.all_terms(), z, strict=True):
        if isinstance(term, LumpedLines):
            fair, anchor, nodes, energy = term.observe(zi, c, v)
            for i, name in enumerate(term.names):
                out[f"mooring/{name}/fairlead_tension"] = fair[i]
                out[f"mooring/{name}/anchor_tension"] = anchor[i]
                out[f"mooring/{name}/nodes"] = nodes[i]
                out.update({f"energy/mooring/{name}/{k}": energy[k][i] for k in LINE_ENERGY})
    return out


def with_lines(stepper, terms):
    """A Stepper (run/stepper.py) whose System has the given line terms added beside its own, as
    LumpedLines (how a test or a user adds lumped lines before the scene's keys are wired)."""
    system = stepper.built.system
    term = bodies_term(system)
    S = 0 if term is None else term.S
    return eqx.tree_at(lambda s: s.built.system.terms, stepper, system.terms + group_lines(terms, S))


def line_states(stepper, state, term_index: Optional[int] = None):
    """The lumped lines in a Stepper's state, by line: a dict name -> (its LumpedLineTerm, its states z);
    `term_index`: those of the System's term of that index alone."""
    system = stepper.built.system
    out = {}
    for i, (term, z) in enumerate(zip(system.all_terms(), state.s.z, strict=True)):
        if isinstance(term, LumpedLines) and (term_index is None or term_index == i):
            out.update({t.name: (t, z[j]) for j, t in enumerate(term.lines)})
    return out


def lumped_terms(system) -> tuple:
    """The system's lumped lines, each line's LumpedLineTerm, in its terms' order."""
    return tuple(t for g in system.all_terms() if isinstance(g, LumpedLines) for t in g.lines)


__all__ = ["LumpedLineTerm", "LumpedLines", "group_lines", "lumped_line_term", "read_lumped", "build_lumped_lines", "lumped_observe",
           "lumped_terms", "with_lines", "line_states", "LUMPED_KEYS"]
