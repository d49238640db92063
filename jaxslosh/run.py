"""The time loop: one jit-compiled `lax.scan` over saved frames (each frame `save_every` steps).

`simulate` runs the whole scan in one call (differentiable: `params` may hold tracers);
`run_to_file` runs the same compiled chunk repeatedly and appends each chunk to the result file,
with a progress bar, so long runs show progress and a killed run leaves a readable file.
A step that fails (Newton not converged, non-finite values) freezes the state; the host finds the
first failure, keeps every frame before it and reports the step, the time and the residual.
"""
from __future__ import annotations

import dataclasses

import math
import sys
import time as _time
from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .build import Built, build
from .integrator import Solver, State, initial_state, make_scheme, make_solver, step_or_retry
from .kinematics import rotation_matrix, rpy_from_quat
from .result import (Energy, ProbeHistory, Result, ResultWriter, SolverHistory, TankField, VesselHistory,
                     truncated)
from .scene_types import Scene


class NumericalFailure(RuntimeError):
    """A step that did not converge or produced non-finite values (exit status 3 on the CLI)."""

    def __init__(self, message: str, result: Optional[Result] = None):
        super().__init__(message)
        self.result = result


class Carry(NamedTuple):
    s: State
    k: jax.Array          # steps done
    failed: jax.Array     # a step has failed: the state is frozen since
    fail_step: jax.Array
    fail_err: jax.Array
    fail_it: jax.Array
    n: jax.Array          # steps attempted, failed or not: the same for every run of a batch (never batched)


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


#: in vmapped batches the Newton preconditioner is carried from step to step and formed anew every
#: this many steps (single runs form it anew when convergence slows, which a batch cannot test per run)
BATCH_REFRESH = 4


class Setup(NamedTuple):
    built: Built
    solver: Solver
    n_steps: int
    save_every: int


def prepare(scene: Scene, params=None, duration=None, dt=None, batch: bool = False) -> Setup:
    """The static model, the solver and the step count. The Newton preconditioner is carried from
    step to step; single runs form it again when convergence slows, `batch` (vmapped runs: no
    lax.cond on a per-run test) every BATCH_REFRESH steps."""
    sim = scene.simulation
    h = float(dt if dt is not None else sim.dt)
    T = float(duration if duration is not None else sim.duration)
    # Under an outer jax.jit (a user's jitted loss) every jnp operation is staged, even on
    # constants; the build relies on the scene's own values being concrete (NumPy meshes, host
    # factors), so what does not depend on traced `params` is evaluated now, as outside jit.
    with jax.ensure_compile_time_eval():
        b = build(scene, params)
        scheme = make_scheme(sim.scheme, sim.alpha, sim.rho_inf)
        solver = make_solver(b.system, h, scheme, sim.tolerance, sim.max_iterations, sim.substeps,
                             reuse=True, adaptive=not batch)
    if batch:      # carried, formed anew every BATCH_REFRESH steps (a cond inside the iterations would
        solver = dataclasses.replace(solver, refresh_every=BATCH_REFRESH)    # run both branches under vmap)
    # a gradient can reach the run only through traced params (a batch is never differentiated):
    # otherwise the Newton solves skip custom_root's tracing of the tangent solves
    traced = any(isinstance(v, jax.core.Tracer) for v in jax.tree_util.tree_leaves(params or {}))
    solver = dataclasses.replace(solver, implicit=traced and not batch)
    if sim.energy_projection:     # the scene check allows it only where it holds (scene._conservative)
        solver = dataclasses.replace(solver, project=True)
    n_steps = int(round(T / h))
    return Setup(b, solver, n_steps, max(1, int(sim.save_every)))


def _frame(b: Built, s: State, it, err, failed) -> Frame:
    sysm = b.system
    flex = getattr(sysm, "flex", None)
    V0, om = s.v[:3], s.v[3:6]
    if flex is None:
        dd = s.v[6:]
    else:
        from .multibody import layout
        dd = layout(sysm).split(s.v)[2]
    A = rotation_matrix(s.c.q)
    pr = b.probes
    if pr.modal is not None:       # reduced liquid: the frame keeps eta, mapped to nodes after the run
        D = s.c.d
        local = pr.points + jnp.einsum("pkc,k->pc", pr.modal, D)
    elif sysm.liquid is not None:
        D = sysm.liquid.full(s.c.d)
        local = pr.points + pr.weights @ D
    else:
        D = jnp.zeros((0, 3))
        local = pr.points
    probes = s.c.X0[None, :] + local @ A.T
    ke = sysm.kinetic_energy(s.c, V0, om, dd)
    pe = sysm.potential_energy(s.c)
    gmax = jnp.zeros(())
    if flex is not None:
        from .multibody import constraint
        gmax = jnp.max(jnp.abs(constraint(sysm, s.c, s.alg)))
        from .multibody import structure_kinetic, structure_potential, _etas
        ke = ke + structure_kinetic(sysm, s.c, s.v)
        pe = pe + structure_potential(sysm, s.c)
        etas = _etas(flex, s.c.eta)
        for sp in pr.on_structures:
            body = flex.bodies[sp.index]
            x = sp.r + sp.W @ body.u(etas[sp.index])
            probes = probes.at[sp.rows].set(s.c.Xs[sp.index][None, :] + x @ rotation_matrix(s.c.qs[sp.index]).T)
    return Frame(s.t, s.c.X0, s.c.q, om, probes, ke, pe, it, err, D, failed, gmax)


def _core(b: Built) -> Built:
    """What the compiled loop needs: the host-side tank blocks (NumPy meshes) stay out of it."""
    return b._replace(tanks=(), structures=())


def _select(pred, a, b):
    return jax.tree_util.tree_map(lambda x, y: jnp.where(pred, x, y), a, b)


@eqx.filter_jit
def start(b: Built, solver: Solver):
    s0, info = initial_state(b.system, solver, b.c0, b.v0, b.alg0)
    failed = ~info.ok
    carry = Carry(s0, jnp.array(0), failed, jnp.where(failed, 0, -1), info.residual, info.iterations, jnp.array(0))
    return carry, _frame(b, s0, info.iterations, info.residual, failed)


#: runs of at least this many steps are checkpointed in blocks (see advance)
REMAT_MIN_STEPS = 5000


@eqx.filter_jit
def advance(b: Built, solver: Solver, carry: Carry, n_frames: int, save_every: int):
    """n_frames frames of save_every steps each: one scan of scans, no Python loop in traced code."""

    def one_step(c: Carry, _):
        s_new, info = step_or_retry(b.system, solver, c.s, c.n)
        bad = ~info.ok & ~c.failed
        keep = c.failed | ~info.ok
        s = _select(keep, c.s, s_new)
        c2 = Carry(s, c.k + jnp.where(keep, 0, 1), c.failed | ~info.ok,
                   jnp.where(bad, c.k + 1, c.fail_step), jnp.where(bad, info.residual, c.fail_err),
                   jnp.where(bad, info.iterations, c.fail_it), c.n + 1)
        return c2, (info.iterations, info.residual)

    def one_frame(c: Carry, _):
        c, (its, errs) = jax.lax.scan(one_step, c, None, length=save_every)
        return c, _frame(b, c.s, its.max(), errs.max(), c.failed)

    def frames(c, n):
        return jax.lax.scan(one_frame, c, None, length=n)

    # Reverse mode through long runs: blocks of K ~ sqrt(n) frames are checkpointed (jax.checkpoint
    # keeps only the block boundaries and recomputes a block's steps when its gradient is taken), so
    # a gradient's memory stops growing with the steps. Measured on the paper example (peak RSS of
    # one gradient): 1.22 / 1.60 / 2.37 GB at 1,000 / 4,000 / 10,000 steps without, 1.76 / 1.67 /
    # 1.45 GB with (a larger compiled program); so only runs of REMAT_MIN_STEPS or more take it.
    K = _block_size(n_frames)
    if n_frames * save_every < REMAT_MIN_STEPS or K < 4:
        return frames(carry, n_frames)
    nb, rem = divmod(n_frames, K)
    carry, fr = jax.lax.scan(jax.checkpoint(lambda c, _: frames(c, K)), carry, None, length=nb)
    fr = jax.tree_util.tree_map(lambda x: x.reshape((nb * K,) + x.shape[2:]), fr)
    if rem:
        carry, tail = frames(carry, rem)
        fr = _concat_frames([fr, tail])
    return carry, fr


def _block_size(n: int) -> int:
    """Frames per checkpointed block: a divisor of n near sqrt(n) where there is one (no remainder
    scan, so the step is compiled once), else sqrt(n)."""
    r = math.isqrt(n)
    for k in sorted(range(max(1, r // 2), 2 * r + 1), key=lambda k: abs(k - r)):
        if n % k == 0:
            return k
    return r


def _concat_frames(frames):
    return jax.tree_util.tree_map(lambda *xs: jnp.concatenate(xs), *frames)


def _nodal(b: Built, D):
    """Frames' liquid displacement as nodal fields (..., N, 3): a reduced liquid's frames hold its
    modal coordinates (storing the nodal field every step cost more than the step itself)."""
    if b.probes.modal is not None:
        return jnp.einsum("...k,knc->...nc", D, b.system.liquid.U)
    return D


def _to_result(b: Built, fr: Frame, scene_text: str, status: str, steps_done: int) -> Result:
    probes = {}
    for i, name in enumerate(b.probes.names):
        pos = fr.probes[:, i, :]
        probes[name] = ProbeHistory(pos, pos - pos[0])
    tanks = {}
    D = _nodal(b, fr.D)
    for t in b.tanks:
        N = t.nodes.shape[0]
        tanks[t.name] = TankField(t.nodes, t.elements, D[:, t.node_offset:t.node_offset + N, :])
    return Result(time=fr.t, vessel=VesselHistory(fr.X0, fr.q, fr.omega, rpy_from_quat(fr.q)), probes=probes,
                  energy=Energy(fr.ke, fr.pe), solver=SolverHistory(fr.iterations, fr.residual, fr.gmax), tanks=tanks,
                  status=status, steps_done=steps_done, scene_text=scene_text)


def _failure_message(carry: Carry, h: float, tol: float, max_iter: int) -> str:
    k = int(carry.fail_step)
    err = float(carry.fail_err)
    if k == 0:
        return f"the initial accelerations could not be solved (scaled residual {err:.3g})"
    t = k * h
    if not math.isfinite(err):
        return f"step {k} (t = {t:.6g} s): non-finite values (NaN or Inf) in the solution"
    return (f"step {k} (t = {t:.6g} s): Newton did not converge in {int(carry.fail_it)} iterations "
            f"(scaled residual {err:.3g}, tolerance {tol:.3g})")


def simulate(scene: Scene, params: Optional[dict] = None, *, duration: Optional[float] = None,
             dt: Optional[float] = None, throw: bool = False) -> Result:
    """Run a scene; the result holds every `save_every`-th step, t = 0 included.

    `params` maps dotted scene keys to replacement values, which may be JAX tracers:
    `jax.grad` of any scalar function of the result works with respect to them.
    A numerical failure truncates the result to the frames before it and sets `status`
    (or raises NumericalFailure when `throw=True`); under tracing the status cannot be read.
    """
    setup = prepare(scene, params, duration, dt)
    b, solver = setup.built, setup.solver
    n_frames = setup.n_steps // setup.save_every
    carry, f0 = start(_core(b), solver)
    carry, frames = advance(_core(b), solver, carry, n_frames, setup.save_every)
    fr = _concat_frames([jax.tree_util.tree_map(lambda x: x[None], f0), frames])
    traced = isinstance(carry.failed, jax.core.Tracer)
    if traced:
        return _to_result(b, fr, scene.text, "ok", setup.n_steps)
    if bool(carry.failed):
        msg = _failure_message(carry, solver.h, solver.tol, solver.max_iter)
        n_ok = int(np.sum(~np.asarray(fr.failed)))
        res = _to_result(b, fr, scene.text, msg, int(carry.k))
        res = truncated(res, n_ok)
        if throw:
            raise NumericalFailure(msg, res)
        return res
    return _to_result(b, fr, scene.text, "ok", int(carry.k))


class Progress:
    """A progress bar on stderr (no dependency; quiet when stderr is not a terminal unless forced)."""

    def __init__(self, total: int, enabled: bool = True, width: int = 30):
        self.total, self.enabled, self.width = max(1, total), enabled, width
        self.t0 = _time.perf_counter()
        self.last = -1.0

    def update(self, done: int, extra: str = ""):
        if not self.enabled:
            return
        now = _time.perf_counter()
        if now - self.last < 0.2 and done < self.total:
            return
        self.last = now
        frac = min(1.0, done / self.total)
        bar = "#" * int(frac * self.width) + "-" * (self.width - int(frac * self.width))
        el = now - self.t0
        eta = el / frac - el if frac > 0 else 0.0
        sys.stderr.write(f"\r[{bar}] {100 * frac:5.1f}% step {done}/{self.total} {el:6.1f}s elapsed, {eta:6.1f}s left {extra}")
        sys.stderr.flush()

    def close(self):
        if self.enabled:
            sys.stderr.write("\n")
            sys.stderr.flush()


def run_to_file(scene: Scene, out: str, *, duration=None, dt=None, progress: bool = True,
                save_fields: Optional[bool] = None):
    """The CLI's run: chunks of the compiled loop appended to `out` as they finish.
    Returns (status, steps done, wall seconds of the loop after the first chunk compiled)."""
    setup = prepare(scene, None, duration, dt)
    b, solver = setup.built, setup.solver
    se = setup.save_every
    n_frames = setup.n_steps // se
    N = 0 if b.system.liquid is None else b.system.liquid.n_nodes
    if save_fields is None:
        save_fields = N * 3 * 8 * (n_frames + 1) < 200e6
    chunk_frames = scene.simulation.chunk or max(1, min(n_frames, max(1, 500 // se)))
    writer = ResultWriter(out, scene.text, b.probes.names, b.tanks if save_fields else ())
    status, steps_done = "ok", 0
    bar = Progress(setup.n_steps, enabled=progress)
    t_loop = None
    try:
        carry, f0 = start(_core(b), solver)
        first = jax.tree_util.tree_map(lambda x: np.asarray(x)[None], f0)
        p0 = first.probes[0]
        pending, done_frames = first, 0
        while True:
            ok = ~np.asarray(pending.failed)
            n_ok = int(ok.sum()) if ok.all() else int(np.argmin(ok))
            writer.append(_file_frames(b, pending, p0, n_ok, save_fields), min(int(carry.k), setup.n_steps))
            if bool(carry.failed) or done_frames >= n_frames:
                break
            carry, fr = advance(_core(b), solver, carry, chunk_frames, se)
            fr = jax.device_get(fr)
            if t_loop is None:
                t_loop = _time.perf_counter()
            take = min(chunk_frames, n_frames - done_frames)
            pending = jax.tree_util.tree_map(lambda x: x[:take], fr)
            done_frames += take
            bar.update(min(int(carry.k), setup.n_steps))
        if bool(carry.failed):
            status = _failure_message(carry, solver.h, solver.tol, solver.max_iter)
        steps_done = min(int(carry.k), setup.n_steps)
    finally:
        bar.close()
        writer.close(status, steps_done)
    wall = (_time.perf_counter() - t_loop) if t_loop is not None else 0.0
    return status, steps_done, wall


def _file_frames(b: Built, fr: Frame, p0, n: int, save_fields: bool) -> dict:
    """Frames (first n rows) as {dataset: array} for the result file."""
    q = np.asarray(fr.q[:n])
    d = {"time": fr.t[:n], "vessel/position": fr.X0[:n], "vessel/quaternion": q,
         "vessel/angular_velocity": fr.omega[:n], "vessel/roll_pitch_yaw": np.asarray(rpy_from_quat(q)).reshape(-1, 3),
         "energy/kinetic": fr.ke[:n], "energy/potential": fr.pe[:n], "solver/iterations": fr.iterations[:n],
         "solver/residual": fr.residual[:n], "solver/constraint": fr.gmax[:n]}
    for i, name in enumerate(b.probes.names):
        d[f"probes/{name}/position"] = fr.probes[:n, i]
        d[f"probes/{name}/displacement"] = fr.probes[:n, i] - p0[i]
    if save_fields:
        D = _nodal(b, fr.D[:n])
        for t in b.tanks:
            d[f"tanks/{t.name}/displacement"] = D[:, t.node_offset:t.node_offset + t.nodes.shape[0]]
    return {k: np.asarray(v) for k, v in d.items()}


_BATCH_FNS: dict = {}


def _batch_fn(scene: Scene, keys: tuple, duration, dt):
    """The jitted, vmapped run of a batch, kept per scene, keys and times: a second batch of the
    same structure does not compile again."""
    cache_key = (scene, keys, duration, dt)
    try:
        hit = _BATCH_FNS.get(cache_key)
    except TypeError:                 # an unhashable scene: no reuse
        cache_key, hit = None, None
    if hit is not None:
        return hit
    setup0 = prepare(scene, None, duration, dt)
    n_frames = setup0.n_steps // setup0.save_every

    def one(*v):
        with jax.ensure_compile_time_eval():     # the liquid's matrices are built on the host, once
            setup = prepare(scene, dict(zip(keys, v)), duration, dt, batch=True)
        b = _core(setup.built)
        carry, f0 = start(b, setup.solver)
        carry, frames = advance(b, setup.solver, carry, n_frames, setup.save_every)
        fr = _concat_frames([jax.tree_util.tree_map(lambda x: x[None], f0), frames])
        return carry, fr

    fn = jax.jit(jax.vmap(one))
    if cache_key is not None:
        _BATCH_FNS[cache_key] = fn
        while len(_BATCH_FNS) > 8:
            _BATCH_FNS.pop(next(iter(_BATCH_FNS)))
    return fn


def simulate_batch(scene: Scene, params: dict, *, duration: Optional[float] = None,
                   dt: Optional[float] = None) -> tuple[Result, list]:
    """Run a batch of parameter sets in one compiled, vmapped loop.

    `params` maps dotted scene keys to arrays of equal leading length B (one value per run).
    Returns (result, statuses): the result's arrays carry a leading batch axis, statuses is one
    string per run ("ok" or why it stopped; a failed run keeps its last good state after that).
    With several devices the batch is sharded over them (jax.sharding), B divisible by their count.
    """
    keys = list(params)
    vals = [jnp.asarray(params[k], dtype=float) for k in keys]
    if not vals:
        raise ValueError("simulate_batch needs at least one parameter array")
    B = int(vals[0].shape[0])
    if any(int(v.shape[0]) != B for v in vals):
        raise ValueError("every parameter array must have the same leading length")
    devices = jax.devices()
    if len(devices) > 1 and B % len(devices) == 0:
        from jax.sharding import Mesh, NamedSharding, PartitionSpec
        mesh = Mesh(np.array(devices), ("batch",))
        vals = [jax.device_put(v, NamedSharding(mesh, PartitionSpec("batch", *([None] * (v.ndim - 1)))))
                for v in vals]
    setup0 = prepare(scene, None, duration, dt)
    carry, fr = _batch_fn(scene, tuple(keys), duration, dt)(*vals)
    statuses = []
    h = setup0.solver.h
    for i in range(B):
        ci = jax.tree_util.tree_map(lambda x: x[i], carry)
        statuses.append(_failure_message(ci, h, setup0.solver.tol, setup0.solver.max_iter)
                        if bool(ci.failed) else "ok")
    b0 = setup0.built
    probes = {}
    for i, name in enumerate(b0.probes.names):
        pos = fr.probes[:, :, i, :]
        probes[name] = ProbeHistory(pos, pos - pos[:, :1])
    res = Result(time=fr.t, vessel=VesselHistory(fr.X0, fr.q, fr.omega, rpy_from_quat(fr.q)), probes=probes,
                 energy=Energy(fr.ke, fr.pe), solver=SolverHistory(fr.iterations, fr.residual, fr.gmax), tanks={},
                 status="ok" if all(s == "ok" for s in statuses) else "some runs failed",
                 steps_done=setup0.n_steps, scene_text=scene.text)
    return res, statuses
