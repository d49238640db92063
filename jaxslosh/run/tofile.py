"""The command line's run: chunks of the compiled loop appended to the result file as they finish,
with a progress bar, so that long runs show progress and a killed run leaves a readable file."""
from __future__ import annotations

import time as _time
from typing import NamedTuple, Optional

import jax
import numpy as np

from ..io.output import is_disk_full
from ..io.result import ResultWriter
from ..io.status import Status
from ..scene.types import Scene
from .loop import advance, core, frame_datasets, start
from .progress import Progress
from .guard import Interrupted, interrupts
from .simulate import failure_message, prepare
from .validity import Watch


class RunReport(NamedTuple):
    """How a run to a file ended: its status text and code (io.status), the steps in the file, the
    wall seconds of the stepping after the first chunk compiled, and the validity warnings."""
    status: str
    code: int
    steps: int
    wall: float
    warnings: tuple


def run_to_file(scene: Scene, out: str, *, progress: bool = True,
                save_fields: Optional[bool] = None) -> RunReport:
    """The CLI's run: chunks of the compiled loop appended to `out` as they finish. The file always
    says how the run ended (`status`, `status_code`, `steps_done`): ok, a numerical failure, an
    interruption (SIGINT, SIGTERM), a full disk or another error (then re-raised)."""
    setup = prepare(scene)
    b, solver = setup.built, setup.solver
    se = setup.save_every
    n_frames = setup.n_steps // se
    N = b.system.liquid.n_nodes
    if save_fields is None:
        save_fields = N * 3 * 8 * (n_frames + 1) < 200e6
    chunk_frames = scene.simulation.chunk or max(1, min(n_frames, max(1, 500 // se)))
    writer = ResultWriter(out, scene.text, b.probes.names, b.tanks if save_fields else ())
    status, code, steps_written = "ok", Status.OK, 0
    watch = Watch(scene)
    bar = Progress(setup.n_steps, enabled=progress)
    t_loop = None
    try:
        with interrupts():
            carry, f0 = start(core(b), solver)
            pending = jax.tree_util.tree_map(lambda x: np.asarray(x)[None], f0)
            p0 = pending.probes[:1]
            done_frames = 0
            while True:
                ok = ~np.asarray(pending.failed)
                n_ok = int(ok.sum()) if ok.all() else int(np.argmin(ok))
                rows = jax.tree_util.tree_map(lambda x: x[:n_ok], pending)
                watch.update(rows.t, rows.surface, rows.residual)
                steps = min(int(carry.k), setup.n_steps)
                writer.append({k: np.asarray(v) for k, v in frame_datasets(b, rows, p0, save_fields).items()}, steps)
                steps_written = steps
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
                status, code = failure_message(carry, solver.h, solver.tol), int(carry.code)
    except KeyboardInterrupt as e:
        how = str(e) if isinstance(e, Interrupted) else "SIGINT"
        status, code = f"interrupted ({how}) after {steps_written} steps", Status.INTERRUPTED
    except Exception as e:
        if not is_disk_full(e):
            status, code = f"error: {type(e).__name__}: {e}", Status.ERROR
            raise
        status, code = f"disk full ({_reason(e)})", Status.DISK_FULL
    finally:
        bar.close()
        warnings = tuple(watch.warnings())
        try:
            writer.close(status, steps_written, code, warnings)
        except Exception as e:      # a full disk may refuse the closing attributes too
            if not is_disk_full(e):
                raise
            status, code = f"disk full ({_reason(e)})", Status.DISK_FULL
    wall = (_time.perf_counter() - t_loop) if t_loop is not None else 0.0
    return RunReport(status, int(code), steps_written, wall, warnings)


def _reason(e: BaseException) -> str:
    return e.strerror if isinstance(e, OSError) and e.strerror else str(e).splitlines()[0]
