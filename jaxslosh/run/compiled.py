"""The run's two programs compiled ahead of time, as one phase: the command line's runs
(run/tofile.py) and `js.simulate` called outside any JAX transformation (run/simulate.py) step with
them. Compiled ahead of time, a program takes XLA options (staging.XLA_OPTIONS, START_OPTIONS),
XLA compiles in the background while Python traces the next, and the programs can be read back from
the exported programs' folder where the entry point installed the compile cache (jaxslosh/cache,
through the hooks of jaxslosh/staging.py: this module imports no cache)."""
from __future__ import annotations

import hashlib

import jax
import numpy as np

from ..solve.factored import FactoredInverse
from ..staging import START_OPTIONS, XLA_OPTIONS, cached, folder, lower_program, program_key, remember
from .loop import carry_shapes, traced_advance, traced_init


def compile_run(bc, solver, chunk_frames: int, save_every: int):
    """The run's two programs compiled ahead of time (from the exported programs' folder where a
    process compiled them before, cache/programs.py): runs `start`; returns its carry and frame, and the
    compiled chunk, called as `chunk(bc, solver, carry, chunk_frames, save_every)`.

    The chunk is traced first, for the shapes of start's carry (loop.carry_shapes, which traces no
    solve); XLA compiles it in the background while Python traces `start`, which XLA then compiles
    beside it with its optimisation off: `start` runs once, and its two Newton solves (with
    structures) compiled optimised took as long as the chunk. On two cores the compile phase is then
    about the chunk's tracing and XLA work alone.

    The compiled pair is kept in the process for the next run of the same structure (a script that
    calls js.simulate again with other values). Where programs are kept in a folder (the command
    line), start's result is kept there too, named by the program and the model's values: a second
    run of the scene reads it and neither loads nor runs `start`."""
    key = program_key("run", (bc, solver, chunk_frames, save_every))
    if key in _RUNS:
        start, chunk = _RUNS[key]
        carry, f0 = start(bc, solver)
        return carry, f0, chunk
    like = carry_shapes(bc, solver)

    def lowered_chunk(carry_like):
        return lower_program("advance", traced_advance, (bc, solver, carry_like, chunk_frames, save_every),
                             XLA_OPTIONS).compile_in_background()
    chunk = lowered_chunk(like)
    # the next process given the same command line loads the chunk ahead (executables.preload); not
    # `start`, whose result that process reads (below)
    remember([chunk.path])
    started = []

    def first():
        # in the background as well: its executable is written there, after its result is ready
        started.append(lower_program("start", traced_init, (bc, solver), START_OPTIONS).compile_in_background().result())
        return started[0](bc, solver)

    # The initial state depends on the model's values alone: where the programs are kept in a folder
    # (the command line), so is it, and a second run of the scene neither loads nor runs `start`.
    state = None if key is None or folder() is None else (key, _digest((bc, solver)))
    carry, f0 = first() if state is None else cached("initial-state", state, lambda: jax.device_get(first()))
    if not same_shapes(carry, like):      # a guard: loop.carry_shapes is tested to agree with init
        chunk = lowered_chunk(carry)
    chunk = chunk.result()
    if key is not None and started:
        _RUNS[key] = started[0], chunk
        while len(_RUNS) > KEEP:       # the oldest first (a script that tries many structures)
            _RUNS.pop(next(iter(_RUNS)))
    return carry, f0, chunk


def _digest(tree) -> str:
    """A hash of the values of every array in `tree` (its structure and static values are in the
    program's key). The liquid block's factors (solve/factored.py) are named by the hash of the
    matrix they factor, which they carry: their tens of megabytes are not hashed again."""
    h = hashlib.sha256()
    for x in jax.tree_util.tree_leaves(tree, is_leaf=lambda x: isinstance(x, FactoredInverse)):
        if isinstance(x, FactoredInverse):
            h.update(f"factored {x.content_key}".encode())
        elif isinstance(x, (jax.Array, np.ndarray, np.generic)):
            a = np.ascontiguousarray(np.asarray(x))
            h.update(f"{a.dtype}{a.shape}".encode())
            h.update(a.tobytes())
    return h.hexdigest()


#: compiled (start, chunk) pairs of this process, by program_key; at most KEEP of them
_RUNS: dict = {}
KEEP = 8


def same_shapes(a, b) -> bool:
    """Two trees of arrays (or of their shapes) of the same structure, shapes and types."""
    la, ta = jax.tree_util.tree_flatten(a)
    lb, tb = jax.tree_util.tree_flatten(b)
    return ta == tb and all(x.shape == y.shape and x.dtype == y.dtype for x, y in zip(la, lb))
