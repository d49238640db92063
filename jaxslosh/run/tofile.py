"""The command line's run: chunks of the compiled loop appended to the result file as they finish,
with its progress on stderr, so that long runs show progress and a killed run leaves a readable file.

The chunk is compiled ahead of time (`advance.lower(...).compile()`, equinox's AOT API), as a phase
of its own: the first chunk then runs precompiled, so the stepping phase, its rate and its estimate
hold steps only, and the compile time is measured apart instead of hiding in the first chunk."""
from __future__ import annotations

from typing import Optional

import jax
import numpy as np

from ..io.result import ResultWriter
from ..scene.types import Scene
from .loop import advance, core, frame_datasets, start
from .progress import Progress
from .simulate import failure_message, prepare


def run_to_file(scene: Scene, out: str, *, progress: bool = True,
                save_fields: Optional[bool] = None):
    """The CLI's run: chunks of the compiled loop appended to `out` as they finish. Returns
    (status, steps done, {phase: wall seconds}): phases "build" (the model on the host), "compile"
    (the initial state and the chunk compiled), "stepping" (every chunk run and written), one after
    the other on one clock, so their sum is the run's wall time. `progress`: draw them on stderr."""
    bar = Progress(enabled=progress)
    status, steps_done = "ok", 0
    writer = None
    try:
        bar.phase("build", "building the model")
        setup = prepare(scene)
        b, solver = setup.built, setup.solver
        se = setup.save_every
        n_frames = setup.n_steps // se
        N = b.system.liquid.n_nodes
        if save_fields is None:
            save_fields = N * 3 * 8 * (n_frames + 1) < 200e6
        chunk_frames = scene.simulation.chunk or max(1, min(n_frames, max(1, 500 // se)))
        writer = ResultWriter(out, scene.text, b.probes.names, b.tanks if save_fields else ())
        bar.phase("compile", "compiling the step")
        carry, f0 = start(core(b), solver)
        chunk = advance.lower(core(b), solver, carry, chunk_frames, se).compile()
        bar.phase("stepping", "stepping", total=setup.n_steps)
        first = jax.tree_util.tree_map(lambda x: np.asarray(x)[None], f0)
        p0 = first.probes[:1]
        pending, done_frames = first, 0
        while True:
            ok = ~np.asarray(pending.failed)
            n_ok = int(ok.sum()) if ok.all() else int(np.argmin(ok))
            rows = jax.tree_util.tree_map(lambda x: x[:n_ok], pending)
            writer.append({k: np.asarray(v) for k, v in frame_datasets(b, rows, p0, save_fields).items()},
                          min(int(carry.k), setup.n_steps))
            if bool(carry.failed) or done_frames >= n_frames:
                break
            carry, fr = chunk(core(b), solver, carry, chunk_frames, se)
            fr = jax.device_get(fr)
            take = min(chunk_frames, n_frames - done_frames)
            pending = jax.tree_util.tree_map(lambda x: x[:take], fr)
            done_frames += take
            bar.update(min(int(carry.k), setup.n_steps))
        if bool(carry.failed):
            status = failure_message(carry, solver.h, solver.tol)
        steps_done = min(int(carry.k), setup.n_steps)
    finally:
        times = bar.close()
        if writer is not None:
            writer.close(status, steps_done)
    return status, steps_done, times
