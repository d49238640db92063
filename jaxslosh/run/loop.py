"""The compiled time loop: one `lax.scan` over saved frames (each frame `save_every` steps) around
the step of solve/integrator.py. A step that fails (Newton not converged, non-finite values)
freezes the state; the carry remembers the first failure, so the host can report it."""
from __future__ import annotations

import math
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..assemble.system import Built
from ..io.status import Status, is_traced
from ..mooring.lumped_term import lumped_observe
from ..mooring.term import mooring_datasets
from ..physics.bodies import bodies_term
from ..physics.kinematics import rotation_matrix, rpy_from_quat
from ..physics.terms import Config
from ..solve.integrator import State, initial_state, initial_state_like, step_or_retry
from ..solve.linear import Solver


class Carry(NamedTuple):
    """The loop's state: the integrator's state and how the run is going."""
    s: State
    k: jax.Array          # steps done
    failed: jax.Array     # a step has failed: the state is frozen since
    fail_step: jax.Array
    fail_err: jax.Array
    fail_it: jax.Array
    n: jax.Array          # steps attempted, failed or not: the same for every run of a batch (never batched)
    code: jax.Array       # io.status.Status of the first failure (OK while none)
    end: jax.Array        # the run's last step: the steps of a last chunk past it are skipped (not
    #                       run, not counted); never batched, so a batch's skip stays a branch


    @property
    def status(self):
        return self.code


class Frame(NamedTuple):
    t: jax.Array
    X0: jax.Array
    q: jax.Array
    omega: jax.Array
    probes: jax.Array
    ke: jax.Array
    pe: jax.Array
    iterations: jax.Array
    residual: jax.Array
    D: jax.Array          # liquid nodal displacement (N, 3), empty without liquid; a reduced liquid's eta (m,)
    failed: jax.Array
    gmax: jax.Array       # max |g| of the interface constraints (m), 0 without structures
    surface: jax.Array    # (tanks, 2): lowest and highest vertical displacement of each free surface (m)
    lines: dict = {}      # the lumped mooring lines' datasets (mooring/lumped_term.lumped_observe), empty without
    bodies: jax.Array = None   # (S, 10): each [[bodies]] body's COG offset from its rest position (3, inertial),
    #                            quaternion (4), angular velocity (3, body frame); (0, 10) without
    links: jax.Array = None    # (n, 2): each connection's force (positive when it pulls) and extension
    body_d: jax.Array = None   # the bodies' tanks' liquid unknowns (modal coordinates), stacked; (0,) without


def probe_positions(b: Built, c: Config):
    """(P, 3) inertial positions of the probes' material points in configuration c (the frames' and
    the frequency domain's one definition: analysis/linear.py differentiates it)."""
    sysm, pr = b.system, b.probes
    A = rotation_matrix(c.q)
    local = pr.points + sysm.liquid.probe_displacements(pr.weights, pr.modal, c.d)
    probes = c.X0[None, :] + local @ A.T
    if pr.on_structures:                  # probes on the structures: the term that owns them
        structures, = sysm.owners()
        etas = structures.split_eta(c.eta)
        for sp in pr.on_structures:
            body = structures.bodies[sp.index]
            x = sp.r + sp.W @ body.u(etas[sp.index])
            probes = probes.at[sp.rows].set(c.Xs[sp.index][None, :] + x @ rotation_matrix(c.qs[sp.index]).T)
    for bp in pr.on_bodies:               # probes in a body's tanks: its liquid, in its frame
        tank = bodies_term(sysm).bodies[bp.index].tank
        # its weights on the body's liquid unknowns (assemble/probes.py), whatever the liquid's form
        x = bp.r if tank is None else bp.r + jnp.einsum("pkc,k->pc", bp.modal, c.eta[bp.offset:bp.offset + bp.n])
        probes = probes.at[bp.rows].set(c.Xs[bp.index][None, :] + x @ rotation_matrix(c.qs[bp.index]).T)
    return probes


def _frame(b: Built, s: State, it, err, failed) -> Frame:
    """What a saved frame keeps of a state: the vessel, the probes, the energies, the solver's figures
    and the liquid's field (its nodal displacement, or a modal liquid's coordinates)."""
    sysm = b.system
    probes = probe_positions(b, s.c)
    ke, pe = sysm.energy(s.c, s.v)
    gmax = jnp.max(jnp.abs(sysm.constraint(s.c, s.alg)), initial=0.0)
    heave = [sysm.liquid.surface_heave(s.c.d, idx) for idx in b.surfaces]
    surface = jnp.array([[h.min(), h.max()] for h in heave]).reshape(len(heave), 2)
    bodies, links = body_frames(sysm, s.c, s.v)
    lines = lumped_observe(sysm, s.z, s.c, s.v)
    term = bodies_term(sysm)
    body_d = s.c.eta if term is not None and term.M else jnp.zeros(0)
    return Frame(s.t, s.c.X0, s.c.q, s.v[3:6], probes, ke, pe, it, err, sysm.liquid.frame_field(s.c.d), failed, gmax,
                 surface, lines, bodies, links, body_d)


def body_frames(sysm, c: Config, v):
    """((S, 10) the bodies' offsets, attitudes and rates, (n, 2) the connections' forces and
    extensions) of a state (physics/bodies.py)."""
    term = bodies_term(sysm)
    if term is None:
        return jnp.zeros((0, 10)), jnp.zeros((0, 2))
    S = term.S
    vy = v[:6 + 6 * S]
    bodies = jnp.zeros((0, 10))
    if S:
        rest = jnp.stack([b.rest for b in term.bodies])
        bodies = jnp.concatenate([c.Xs - rest, c.qs, vy[6:].reshape(S, 6)[:, 3:]], axis=1)
    T, e = term.link_states(c, vy)
    return bodies, jnp.stack([T, e], axis=1).reshape(-1, 2)


def tank_blocks(b: Built) -> tuple:
    """The host-side blocks of every tank: the vessel's, then each body's (assemble/bodies.BodyTanks)."""
    return tuple(b.tanks) + tuple(t for bt in b.body_tanks for t in bt.tanks)


def core(b: Built) -> Built:
    """What the compiled loop needs: the host-side tank blocks (NumPy meshes) stay out of it."""
    return b._replace(tanks=(), structures=(), body_tanks=())


def _select(pred, a, b):
    return jax.tree_util.tree_map(lambda x, y: jnp.where(pred, x, y), a, b)


def init(b: Built, solver: Solver) -> tuple[Carry, Frame]:
    """The state at t = 0 (consistent accelerations; structures in static equilibrium) and its frame."""
    with jax.named_scope("initial state"):
        s0, info = initial_state(b.system, solver, b.c0, b.v0, b.alg0)
    carry = _first_carry(s0, info)
    return carry, observe(b, carry, info.iterations, info.residual)


def _first_carry(s0, info) -> Carry:
    failed = ~info.ok
    code = jnp.where(failed, int(Status.INITIAL), int(Status.OK))
    return Carry(s0, jnp.array(0), failed, jnp.where(failed, 0, -1), info.residual, info.iterations, jnp.array(0),
                 code, jnp.array(NO_END, dtype=jnp.array(0).dtype))


#: the `end` of a run that has none set (Stepper, simulate: their scans end with the run)
NO_END = 2 ** 31 - 1


def ending_at(carry: Carry, n_steps: int) -> Carry:
    """The carry of a run of n_steps stepped in chunks: a last chunk's steps past n_steps are skipped."""
    return carry._replace(end=jnp.asarray(n_steps, dtype=carry.end.dtype))


def carry_shapes(b: Built, solver: Solver) -> Carry:
    """The shapes and types of init's carry, without tracing its Newton solves (what the loop is
    lowered for while init is still being traced: run/compiled.compile_run)."""
    return eqx.filter_eval_shape(
        lambda b_, s_: _first_carry(*initial_state_like(b_.system, s_, b_.c0, b_.v0, b_.alg0)), b, solver)


def loop_step(b: Built, solver: Solver, c: Carry) -> tuple[Carry, tuple]:
    """One step of the loop: the integrator's step (retried as sub-steps where the scene asks);
    a step that fails freezes the state and records the first failure's step, residual and code.
    A step past the run's `end` is skipped: the state stays, nothing is counted."""

    def go(c: Carry):
        s_new, info = step_or_retry(b.system, solver, c.s, c.n, ~c.failed)
        # the time from the step index, t = (k + 1) h (runs start at t = 0), not the running sum of h:
        # summing rounds at every step (2000 steps of 0.01 s ended at 20.000000000000327)
        s_new = s_new._replace(t=(c.k + 1).astype(s_new.t.dtype) * solver.h)
        bad = ~info.ok & ~c.failed
        keep = c.failed | ~info.ok
        s = _select(keep, c.s, s_new)
        why = jnp.where(jnp.isfinite(info.residual), int(Status.NEWTON), int(Status.NONFINITE))
        c2 = Carry(s, c.k + jnp.where(keep, 0, 1), c.failed | ~info.ok,
                   jnp.where(bad, c.k + 1, c.fail_step), jnp.where(bad, info.residual, c.fail_err),
                   jnp.where(bad, info.iterations, c.fail_it), c.n + 1, jnp.where(bad, why, c.code), c.end)
        return c2, (info.iterations.astype(jnp.int32), info.residual.astype(c.fail_err.dtype))

    def idle(c: Carry):
        return c, (jnp.zeros((), jnp.int32), jnp.zeros((), c.fail_err.dtype))

    if solver.implicit:           # reverse mode may reach the run: a cond (a while loop has no transpose)
        return jax.lax.cond(c.n < c.end, go, idle, c)
    # No gradient reaches the run (Solver.implicit is False): the step as a loop of zero or one pass.
    # XLA's CPU layouts the constants inside a conditional's branch as they come, so a cond around the
    # step re-lays the face-normal liquid's fields (transposes and copies) at every residual of every
    # Newton iteration, 15-25 % of its step (docs/benchmarks.md, the shaped tanks against their floor);
    # a while loop's body gets them laid out once, before the loops.
    def once(x):
        _, c1, _ = x
        c2, out = go(c1)
        return jnp.ones((), jnp.int32), c2, out

    passes = (c.n < c.end).astype(jnp.int32)
    _, c2, out = jax.lax.while_loop(lambda x: x[0] < passes, once, (jnp.zeros((), jnp.int32),) + idle(c))
    return c2, out


def observe(b: Built, c: Carry, iterations=None, residual=None) -> Frame:
    """The frame of a state (iterations and residual of the steps since the last frame, if known)."""
    z = jnp.zeros((), dtype=c.fail_err.dtype)
    return _frame(b, c.s, jnp.zeros((), jnp.int32) if iterations is None else iterations,
                  z if residual is None else residual, c.failed)


#: init and the loop as traced (each trace counted, eqx.debug.get_num_traces: tests guard recompiles)
traced_init = eqx.debug.assert_max_traces(init, max_traces=None)
start = eqx.filter_jit(traced_init)


#: runs of at least this many steps are checkpointed in blocks (see advance)
REMAT_MIN_STEPS = 5000


def _advance(b: Built, solver: Solver, carry: Carry, n_frames: int, save_every: int):
    """n_frames frames of save_every steps each: one scan of scans, no Python loop in traced code."""

    def one_step(c: Carry, _):
        return loop_step(b, solver, c)

    def one_frame(c: Carry, _):
        c, (its, errs) = jax.lax.scan(one_step, c, None, length=save_every)
        with jax.named_scope("frame"):
            return c, observe(b, c, its.max(), errs.max())

    def frames(c, n):
        return jax.lax.scan(one_frame, c, None, length=n)

    # Reverse mode through long runs: blocks of K ~ sqrt(n) frames are checkpointed (jax.checkpoint
    # keeps only the block boundaries and recomputes a block's steps when its gradient is taken), so
    # a gradient's memory stops growing with the steps; the checkpointed program is larger, so only
    # runs of REMAT_MIN_STEPS or more take it (docs/benchmarks.md, gradient memory, has the measurements).
    K = _block_size(n_frames)
    if n_frames * save_every < REMAT_MIN_STEPS or K < 4:
        return frames(carry, n_frames)
    nb, rem = divmod(n_frames, K)
    carry, fr = jax.lax.scan(jax.checkpoint(lambda c, _: frames(c, K)), carry, None, length=nb)
    fr = jax.tree_util.tree_map(lambda x: x.reshape((nb * K,) + x.shape[2:]), fr)
    if rem:
        carry, tail = frames(carry, rem)
        fr = concat_frames([fr, tail])
    return carry, fr


traced_advance = eqx.debug.assert_max_traces(_advance, max_traces=None)
advance = eqx.filter_jit(traced_advance)


def _block_size(n: int) -> int:
    """Frames per checkpointed block: a divisor of n near sqrt(n) where there is one (no remainder
    scan, so the step is compiled once), else sqrt(n)."""
    r = math.isqrt(n)
    for k in sorted(range(max(1, r // 2), 2 * r + 1), key=lambda k: abs(k - r)):
        if n % k == 0:
            return k
    return r


def concat_frames(frames):
    """Frames joined along their frame axis. Concrete frames are fetched once and joined on the host
    (NumPy copies the same values; an eager jnp op per field compiled a program each); traced ones
    stay jnp, in the caller's (differentiable) program."""
    if not is_traced(frames):
        return jax.tree_util.tree_map(lambda *xs: np.concatenate(xs), *jax.device_get(frames))
    return jax.tree_util.tree_map(lambda *xs: jnp.concatenate(xs), *frames)


def with_first(f0, frames):
    """The frames after the first frame `f0` (concat_frames: on the host where concrete)."""
    lift = (lambda x: np.asarray(x)[None]) if not is_traced(f0) else (lambda x: x[None])
    return concat_frames([jax.tree_util.tree_map(lift, f0), frames])


# Concrete frames: one program, not one per eager op. At LLVM's optimisation level 0 its numbers are
# the eager ops' to the bit (optimised, the fused program contracts multiply-adds: last-bit changes).
_rpy_jit = jax.jit(rpy_from_quat, compiler_options={"xla_backend_optimization_level": 0})


def nodal(b: Built, D):
    """Frames' liquid fields as nodal displacements (..., N, 3): a modal liquid's frames hold its
    modal coordinates (storing the nodal field every step cost more than the step itself)."""
    return b.system.liquid.nodal_fields(D)


def frame_datasets(b: Built, fr: Frame, p0=None, fields: bool = True) -> dict:
    """Frames (leading axes [batch,] frame) as the result file's datasets (io/result.py `schema`).
    `p0`: the probes' initial positions (default: the first frame's); `fields`: the tanks' nodal
    displacement fields too (b.tanks: the host-side blocks)."""
    rpy = rpy_from_quat if is_traced(fr.q) else _rpy_jit
    d = {"time": fr.t, "vessel/position": fr.X0, "vessel/quaternion": fr.q, "vessel/angular_velocity": fr.omega,
         "vessel/roll_pitch_yaw": rpy(fr.q), "energy/kinetic": fr.ke, "energy/potential": fr.pe,
         "solver/iterations": fr.iterations, "solver/residual": fr.residual, "solver/constraint": fr.gmax}
    P = fr.probes                                                   # (..., n, P, 3)
    p0 = P[..., :1, :, :] if p0 is None else p0
    for i, name in enumerate(b.probes.names):
        d[f"probes/{name}/position"] = P[..., i, :]
        d[f"probes/{name}/displacement"] = P[..., i, :] - p0[..., i, :]
    term = bodies_term(b.system)
    poses = () if term is None or not term.S else (      # the bodies' poses, for lines that hold them
        fr.bodies[..., :3] + jnp.stack([body.rest for body in term.bodies]), fr.bodies[..., 3:7])
    d.update(mooring_datasets(b.system, fr.X0, fr.q, *poses))        # quasi-static lines: from the poses
    d.update(fr.lines)                                       # lumped lines: from their states
    if term is not None:
        for i, name in enumerate(term.names):
            B = fr.bodies[..., i, :]
            d[f"bodies/{name}/position"] = B[..., :3]
            d[f"bodies/{name}/quaternion"] = B[..., 3:7]
            d[f"bodies/{name}/angular_velocity"] = B[..., 7:]
            d[f"bodies/{name}/roll_pitch_yaw"] = rpy(B[..., 3:7])
        for i, name in enumerate(term.link_names):
            d[f"connections/{name}/force"] = fr.links[..., i, 0]
            d[f"connections/{name}/extension"] = fr.links[..., i, 1]
    if fields and b.tanks:
        D = nodal(b, fr.D)
        for t in b.tanks:
            d[f"tanks/{t.name}/displacement"] = D[..., t.node_offset:t.node_offset + t.nodes.shape[0], :]
    for bt in b.body_tanks if fields else ():     # a body's tanks: their fields from its liquid's coordinates
        floating = term.bodies[bt.body]
        eta = fr.body_d[..., bt.offset:bt.offset + floating.nf]
        flat = eta.reshape(-1, floating.nf)       # the frames' kept field of each (a full-order liquid's: nodal)
        D = floating.tank.nodal_fields(jax.vmap(floating.tank.frame_field)(flat))
        D = D.reshape(eta.shape[:-1] + D.shape[1:])
        for t in bt.tanks:
            d[f"tanks/{t.name}/displacement"] = D[..., t.node_offset:t.node_offset + t.nodes.shape[0], :]
    return d

