"""The command line's run: chunks of the compiled loop appended to the result file as they finish,
with a progress bar, so that long runs show progress and a killed run leaves a readable file."""
from __future__ import annotations

import time as _time
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
    """The CLI's run: chunks of the compiled loop appended to `out` as they finish.
    Returns (status, steps done, wall seconds of the loop after the first chunk compiled)."""
    setup = prepare(scene)
    b, solver = setup.built, setup.solver
    se = setup.save_every
    n_frames = setup.n_steps // se
    N = b.system.liquid.n_nodes
    if save_fields is None:
        save_fields = N * 3 * 8 * (n_frames + 1) < 200e6
    chunk_frames = scene.simulation.chunk or max(1, min(n_frames, max(1, 500 // se)))
    writer = ResultWriter(out, scene.text, b.probes.names, b.tanks if save_fields else ())
    status, steps_done = "ok", 0
    bar = Progress(setup.n_steps, enabled=progress)
    t_loop = None
    try:
        carry, f0 = start(core(b), solver)
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
            carry, fr = advance(core(b), solver, carry, chunk_frames, se)
            fr = jax.device_get(fr)
            if t_loop is None:
                t_loop = _time.perf_counter()
            take = min(chunk_frames, n_frames - done_frames)
            pending = jax.tree_util.tree_map(lambda x: x[:take], fr)
            done_frames += take
            bar.update(min(int(carry.k), setup.n_steps))
        if bool(carry.failed):
            status = failure_message(carry, solver.h, solver.tol)
        steps_done = min(int(carry.k), setup.n_steps)
    finally:
        bar.close()
        writer.close(status, steps_done)
    wall = (_time.perf_counter() - t_loop) if t_loop is not None else 0.0
    return status, steps_done, wall
