"""The time loop: one jit-compiled `lax.scan` over saved frames (each frame `save_every` steps).

`simulate` runs the whole scan in one call (differentiable: `params` may hold tracers);
`run_to_file` (tofile.py) runs the same compiled chunk repeatedly and appends each chunk to the
result file; `simulate_batch` (batch.py) runs a vmapped batch. A step that fails (Newton not
converged, non-finite values) freezes the state; the host finds the first failure, keeps every
frame before it and reports the step, the time and the residual.
"""
from __future__ import annotations

import dataclasses
from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..assemble.system import Built, build
from ..io.status import failure_text, is_traced, outcome_of
from ..io.result import Failure, Result, result_from, truncated
from ..scene.keys import check_values, with_overrides
from ..scene.types import Scene
from ..solve.linear import Solver, make_solver
from ..staging import one_blas_thread
from .compiled import compile_run
from .loop import Carry, Frame, advance, core, frame_datasets, start, tank_blocks, with_first


class NumericalFailure(RuntimeError):
    """A step that did not converge or produced non-finite values (exit status 3 on the CLI)."""

    def __init__(self, message: str, result: Optional[Result] = None):
        super().__init__(message)
        self.result = result


#: in vmapped batches the Newton preconditioner is carried from step to step and formed anew every
#: this many steps (single runs form it anew when convergence slows, which a batch cannot test per run)
BATCH_REFRESH = 4
#: the name of the vmapped runs' axis in batches (run/batch.py): the solver's collectives over the runs
BATCH_AXIS = "runs"


class Setup(NamedTuple):
    built: Built
    solver: Solver
    n_steps: int
    save_every: int


def prepare(scene: Scene, params=None, batch: bool = False, check: bool = True) -> Setup:
    """The static model, the solver and the step count. The Newton preconditioner is carried from
    step to step; single runs form it again when convergence slows, `batch` (vmapped runs: no
    lax.cond on a per-run test) every BATCH_REFRESH steps. `check`: concrete params are checked as
    a scene file with them would be."""
    sim = scene.simulation
    h, T = float(sim.dt), float(sim.duration)
    concrete = {k: v for k, v in (params or {}).items() if not is_traced(v)}
    if concrete and check:        # checked as a scene file with these values would be (a tracer has no value to check)
        check_values(scene, concrete)
    # Under an outer jax.jit (a user's jitted loss) every jnp operation is staged, even on
    # constants; the build relies on the scene's own values being concrete (NumPy meshes, host
    # factors), so what does not depend on traced `params` is evaluated now, as outside jit.
    with jax.ensure_compile_time_eval(), one_blas_thread():     # the solver's host factors too
        b = build(scene, params)
        scheme = sim.time_scheme()
        solver = make_solver(b.system, h, scheme, sim.tolerance, sim.max_iterations, sim.substeps,
                             reuse=True, adaptive=not batch)
    if batch:      # carried, formed anew every BATCH_REFRESH steps (a cond inside the iterations would
        solver = dataclasses.replace(solver, refresh_every=BATCH_REFRESH,    # run both branches under vmap)
                                     batch_axis=BATCH_AXIS)
    # a gradient can reach the run only through traced params (a batch is never differentiated):
    # otherwise the Newton solves skip custom_root's tracing of the tangent solves
    traced = is_traced(params or {})
    solver = dataclasses.replace(solver, implicit=traced and not batch)
    if sim.energy_projection:     # the scene check allows it only where it holds (scene._conservative)
        solver = dataclasses.replace(solver, project=True)
    n_steps = int(round(T / h))
    return Setup(b, solver, n_steps, max(1, int(sim.save_every)))


def _trace_clean() -> bool:
    """No JAX transformation (jit, grad, vmap) is tracing the caller (JAX's own test; a JAX without
    it: taken as traced, the staged path, which is right everywhere)."""
    clean = getattr(getattr(getattr(jax, "_src", None), "core", None), "trace_state_clean", None)
    return bool(clean()) if clean is not None else False


def to_result(b: Built, fr: Frame, scene_text: str, status: str, carry: Carry, solver: Solver) -> Result:
    """The result of a run's frames and its final carry: the outcome, steps done and first failure
    are the carry's (leaves, traced inside a transformation); `status` the host's text ("" where the
    carry is traced: the result reads its outcome once computed)."""
    tanks = {t.name: (t.nodes, t.elements) for t in tank_blocks(b)}
    failure = Failure(carry.fail_step, carry.fail_err, carry.fail_it)
    d = frame_datasets(b, fr)
    if not is_traced(fr):      # host-joined frames (under jax.grad a field may be concrete while others are traced)
        d = jax.device_put(d)       # the result holds jax arrays as before (a transfer, no compiled program)
    return result_from(d, b.probes.names, tanks, status=status, steps_done=carry.k,
                       scene_text=scene_text, status_code=carry.code, failure=failure, dt=float(solver.h),
                       tolerance=float(solver.tol))


def failure_message(carry: Carry, h: float, tol: float) -> str:
    """The sentence of a carry's first failure (io/status.py)."""
    return failure_text(int(carry.code), int(carry.fail_step), float(h), float(carry.fail_err), int(carry.fail_it), tol)


def _raise_on_derivatives(res: Result, failed, code) -> Result:
    """`res` with its derivatives tied to the failure check: a gradient of a function of the frames
    needs no frame's value (d sum(x) / dx is 1), so the compiler drops the check on the values and
    the gradient of a failed run came back as a number. Each tangent is scaled by 1 + 0 * (the
    checked failure flag), a factor the derivative's program must compute, so it raises too."""

    @jax.custom_jvp
    def tie(x, failed, code):
        return x

    @tie.defjvp
    def _(primals, tangents):
        x, failed, code = primals
        token = outcome_of(code).error_if(jnp.zeros((), x.dtype), failed)
        return x, tangents[0] * (1.0 + 0.0 * token)

    floats, rest = eqx.partition(res, eqx.is_inexact_array)
    floats = jax.tree_util.tree_map(lambda x: tie(x, failed, code), floats)
    return eqx.combine(floats, rest)


def simulate(scene: Scene, params: Optional[dict] = None, *, duration: Optional[float] = None,
             dt: Optional[float] = None, throw: bool = True, check: bool = True) -> Result:
    """Run a scene; the result holds every `save_every`-th step, t = 0 included.

    `params` maps dotted scene keys to replacement values, which may be JAX tracers:
    `jax.grad` of any scalar function of the result works with respect to them. Concrete values
    are checked as the scene file with them would be (SceneError naming the key); `check=False`
    takes them as they are (a numerical experiment: a coefficient set to zero to switch its term
    off, say).

    How the run ended is the result's `outcome` (io.status.RunResult), a leaf: right inside
    `jax.jit`, `jax.grad` and `vmap`. A numerical failure (a step's Newton iterations that do not
    converge, non-finite values) raises by default: NumericalFailure (with the truncated result)
    when called outside a transformation, and inside one an error when the compiled run reaches it
    (equinox's error_if), so that neither a value nor a gradient of a failed run comes back
    silently. With `throw=False` the run returns: outside a transformation its frames are cut at
    the failure and `status` names the step; inside one the frames after the failure repeat the
    last good state (the values and their gradients are those of the run up to the failure) and
    `result.outcome`, `result.failure.step` and `result.steps` say what happened.
    """
    scene = with_overrides(scene, duration=duration, dt=dt)
    setup = prepare(scene, params, check=check)
    b, solver = setup.built, setup.solver
    n_frames = setup.n_steps // setup.save_every
    bc = core(b)
    if not _trace_clean():      # traced params too: only a transformation makes tracers
        carry, f0 = start(bc, solver)       # inside a JAX transformation: staged into the caller's program
        carry, frames = advance(bc, solver, carry, n_frames, setup.save_every)
    else:    # compiled as `jaxslosh run` compiles (XLA options, both programs at once), then run
        carry, f0, run = compile_run(bc, solver, n_frames, setup.save_every)
        carry, frames = run(bc, solver, carry, n_frames, setup.save_every)
    fr = with_first(f0, frames)
    if isinstance(carry.failed, jax.core.Tracer):
        res = to_result(b, fr, scene.text, "", carry, solver)
        if throw:
            res = _raise_on_derivatives(res.outcome.error_if(res, carry.failed), carry.failed, carry.code)
        return res
    if bool(carry.failed):
        msg = failure_message(carry, solver.h, solver.tol)
        n_ok = int(np.sum(~np.asarray(fr.failed)))
        res = truncated(to_result(b, fr, scene.text, msg, carry, solver), n_ok)
        if throw:
            raise NumericalFailure(msg, res)
        return res
    return to_result(b, fr, scene.text, "ok", carry, solver)
