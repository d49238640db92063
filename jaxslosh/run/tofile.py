"""The command line's run: chunks of the compiled loop appended to the result file as they finish,
with its progress on stderr, so that long runs show progress and a killed run leaves a readable file
that says how it ended.

The chunk is compiled ahead of time (compile_run: traced once and exported, cache/programs.py), as a phase
of its own: the first chunk then runs precompiled, so the stepping phase, its rate and its estimate
hold steps only, and the compile time is measured apart instead of hiding in the first chunk."""
from __future__ import annotations

import dataclasses
import hashlib
import os
from typing import NamedTuple, Optional

import jax
import numpy as np

from ..io.output import is_disk_full
from ..io.result import ResultWriter
from ..io.status import Status
from ..scene.types import Scene
from .guard import Interrupted, interrupts
from .capsize import body_vanishing_angles, vanishing_angles
from ..staging import cached
from .compiled import compile_run
from ..mooring.lumped_term import lumped_terms
from ..mooring.term import mooring_term
from ..physics.bodies import bodies_term
from .loop import core, ending_at, frame_datasets, tank_blocks
from .progress import Progress
from .simulate import failure_message, prepare
from .validity import Watch


class RunReport(NamedTuple):
    """How a run to a file ended: its status text and code (io.status), the steps in the file, the
    wall seconds of its phases ({"build", "compile", "stepping"}, contiguous on one clock: their sum
    is the run's wall time), and the validity warnings."""
    status: str
    code: int
    steps: int
    times: dict
    warnings: tuple


def run_to_file(scene: Scene, out: str, *, progress: bool = True,
                save_fields: Optional[bool] = None) -> RunReport:
    """The CLI's run: chunks of the compiled loop appended to `out` as they finish. The file always
    says how the run ended (`status`, `status_code`, `steps_done`): ok, a numerical failure, an
    interruption (SIGINT, SIGTERM), a full disk or another error (then re-raised). `progress`: draw
    the phases on stderr."""
    bar = Progress(enabled=progress)
    status, code, steps_written = "ok", Status.OK, 0
    watch = None
    writer = None
    try:
        with interrupts() as stop:
            bar.phase("build", "building the model")
            # a second run of the scene reads the model the first one built (programs.cached)
            key = model_key(scene)
            setup = prepare(scene) if key is None else cached("model", key, lambda: prepare(scene))
            b, solver = setup.built, setup.solver
            watch = Watch(scene, np.asarray(solver.noise))
            watch.watch_capsize(vanishing_angles(b.system), body_vanishing_angles(b.system),
                                getattr(bodies_term(b.system), "names", ()))
            watch.watch_liquid(b.system.liquid)
            watch.watch_bodies(b)
            se = setup.save_every
            n_frames = setup.n_steps // se
            N = b.system.liquid.n_nodes
            if save_fields is None:
                save_fields = N * 3 * 8 * (n_frames + 1) < 200e6
            chunk_frames = scene.simulation.chunk or max(1, min(n_frames, max(1, 500 // se)))
            lumped = lumped_terms(b.system)
            writer = ResultWriter(out, scene.text, b.probes.names, tank_blocks(b) if save_fields else (),
                                  (*getattr(mooring_term(b.system), "names", ()), *(t.name for t in lumped)),
                                  {t.name: t.line.segments + 1 for t in lumped},
                                  bodies=getattr(bodies_term(b.system), "names", ()),
                                  connections=getattr(bodies_term(b.system), "link_names", ()),
                                  line_energy=[t.name for t in lumped])
            stop.check()
            bar.phase("compile", "compiling the step")
            bc = core(b)
            carry, f0, chunk = compile_run(bc, solver, chunk_frames, se)
            carry = ending_at(carry, setup.n_steps)     # a last chunk's steps past the end are skipped
            stop.check()
            bar.phase("stepping", "stepping", total=setup.n_steps)
            pending = jax.tree_util.tree_map(lambda x: np.asarray(x)[None], f0)
            p0 = pending.probes[:1]
            done_frames = 0
            while True:
                ok = ~np.asarray(pending.failed)
                n_ok = int(ok.sum()) if ok.all() else int(np.argmin(ok))
                rows = jax.tree_util.tree_map(lambda x: x[:n_ok], pending)
                watch.update(rows.t, rows.surface, rows.residual, rows.D, rows.q, rows.body_d, rows.bodies)
                steps = min(int(carry.k), setup.n_steps)
                writer.append({k: np.asarray(v) for k, v in frame_datasets(b, rows, p0, save_fields).items()}, steps)
                steps_written = steps
                if bool(carry.failed) or done_frames >= n_frames:
                    break
                stop.check()
                carry, fr = chunk(bc, solver, carry, chunk_frames, se)
                fr = jax.device_get(fr)
                take = min(chunk_frames, n_frames - done_frames)
                pending = jax.tree_util.tree_map(lambda x: x[:take], fr)
                done_frames += take
                bar.update(min(int(carry.k), setup.n_steps))
            if bool(carry.failed):
                status, code = failure_message(carry, solver.h, solver.tol), int(carry.code)
    except KeyboardInterrupt as e:
        how = str(e) if isinstance(e, Interrupted) else "SIGINT"       # Python's own KeyboardInterrupt
        status, code = f"interrupted ({how}) after {steps_written} steps", Status.INTERRUPTED
        if writer is None:          # nothing was written yet: nothing to say it in
            raise
    except Exception as e:
        if not is_disk_full(e) or writer is None:
            status, code = f"error: {type(e).__name__}: {e}", Status.ERROR
            raise
        status, code = f"disk full ({_reason(e)})", Status.DISK_FULL
    finally:
        times = bar.close()
        warnings = tuple(watch.warnings()) if watch is not None else ()
        if writer is not None:
            try:
                writer.close(status, steps_written, code, warnings)
            except Exception as e:      # a full disk may refuse the closing attributes too
                if not is_disk_full(e):
                    raise
                status, code = f"disk full ({_reason(e)})", Status.DISK_FULL
    return RunReport(status, int(code), steps_written, times, warnings)


def model_key(scene: Scene):
    """What a model built from `scene` depends on: the scene and the contents of every file it names
    (a tank's or the hull's mesh, a hydrodynamic database), so that a model kept from a file that has
    changed since is not read back; None where such a file cannot be read (the model is not kept)."""
    files = set()

    def walk(x, base):
        if dataclasses.is_dataclass(x):
            base = getattr(x, "base_dir", "") or base
            for f in dataclasses.fields(x):
                v = getattr(x, f.name)
                if f.name == "file" and isinstance(v, str):
                    if v:
                        files.add(v if os.path.isabs(v) else os.path.join(base, v))
                else:
                    walk(v, base)
        elif isinstance(x, (tuple, list)):
            for v in x:
                walk(v, base)
        elif isinstance(x, dict):
            for v in x.values():
                walk(v, base)

    walk(scene, os.path.dirname(os.path.abspath(scene.path)) if scene.path else os.getcwd())
    try:
        contents = []
        for f in sorted(files):
            with open(f, "rb") as fh:
                contents.append((f, hashlib.sha256(fh.read()).hexdigest()))
    except OSError:
        return None
    return scene, tuple(contents)


def _reason(e: BaseException) -> str:
    return e.strerror if isinstance(e, OSError) and e.strerror else str(e).splitlines()[0]
