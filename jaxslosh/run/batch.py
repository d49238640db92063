"""A batch of parameter sets in one compiled, vmapped loop (`jaxslosh sweep`)."""
from __future__ import annotations

from typing import Optional

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from ..io.result import Result, result_from
from ..scene.keys import with_overrides
from ..scene.types import Scene
from .loop import advance, concat_frames, core, frame_datasets, start
from .simulate import failure_message, prepare


_BATCH_FNS: dict = {}


def _batch_fn(scene: Scene, keys: tuple):
    """The jitted, vmapped run of a batch, kept per scene, keys and times: a second batch of the
    same structure does not compile again."""
    cache_key = (scene, keys)
    try:
        hit = _BATCH_FNS.get(cache_key)
    except TypeError:                 # an unhashable scene: no reuse
        cache_key, hit = None, None
    if hit is not None:
        return hit
    setup0 = prepare(scene)
    n_frames = setup0.n_steps // setup0.save_every

    def one(*v):
        with jax.ensure_compile_time_eval():     # the liquid's matrices are built on the host, once
            setup = prepare(scene, dict(zip(keys, v)), batch=True)
        b = core(setup.built)
        carry, f0 = start(b, setup.solver)
        carry, frames = advance(b, setup.solver, carry, n_frames, setup.save_every)
        fr = concat_frames([jax.tree_util.tree_map(lambda x: x[None], f0), frames])
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
    scene = with_overrides(scene, duration=duration, dt=dt)
    keys = list(params)
    vals = [jnp.asarray(params[k], dtype=float) for k in keys]
    if not vals:
        raise ValueError("simulate_batch needs at least one parameter array")
    B = int(vals[0].shape[0])
    if any(int(v.shape[0]) != B for v in vals):
        raise ValueError("every parameter array must have the same leading length")
    devices = jax.devices()
    if len(devices) > 1 and B % len(devices) == 0:
        mesh = Mesh(np.array(devices), ("batch",))
        vals = [jax.device_put(v, NamedSharding(mesh, PartitionSpec("batch", *([None] * (v.ndim - 1)))))
                for v in vals]
    setup0 = prepare(scene)
    carry, fr = _batch_fn(scene, tuple(keys))(*vals)
    statuses = []
    h = setup0.solver.h
    for i in range(B):
        ci = jax.tree_util.tree_map(lambda x: x[i], carry)
        statuses.append(failure_message(ci, h, setup0.solver.tol)
                        if bool(ci.failed) else "ok")
    b0 = setup0.built
    res = result_from(frame_datasets(b0, fr, fields=False), b0.probes.names,
                      status="ok" if all(s == "ok" for s in statuses) else "some runs failed",
                      steps_done=setup0.n_steps, scene_text=scene.text)
    return res, statuses
