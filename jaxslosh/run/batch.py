"""A batch of parameter sets in one compiled, vmapped loop (`jaxslosh sweep`)."""
from __future__ import annotations

import dataclasses
import functools
from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from ..io.result import Result, result_from
from ..mooring.term import build_mooring, line_datasets
from ..physics.bodies import body_rest
from ..physics.hull import HullPressure
from ..physics.seakeeping import Excitation, WaveExcitation
from ..scene.keys import check_values, resolve_params, with_overrides
from ..scene.types import Scene, SceneError
from ..staging import XLA_OPTIONS, cached, compile_program, folder
from .capsize import body_vanishing_angles, vanishing_angles
from .loop import advance, concat_frames, core, frame_datasets, start
from .simulate import BATCH_AXIS, failure_message, is_traced, prepare
from .tofile import model_key


_BATCH_FNS: dict = {}


def _excited(b, exc, incident=None):
    """The built model with its wave excitation replaced by `exc` (omega, amp, phase, height), and
    with `incident` (k, amp, phase, cos heading, sin heading) the incident components that the
    nonlinear hydrostatics integrate on the wetted hull: the runs of a campaign differ only in
    their sea, whose components are drawn on the host."""
    omega, amp, phase, height = exc

    def one(t):
        if isinstance(t, WaveExcitation):
            return WaveExcitation(Excitation(omega, amp, phase, height, ramp=t.excitation.ramp))
        if incident is not None and isinstance(t, HullPressure) and t.waves is not None:
            k, a, eps, cb, sb = incident
            return eqx.tree_at(lambda h: h.waves, t, dataclasses.replace(t.waves, omega=omega, k=k, amp=a,
                                                                          phase=eps, cb=cb, sb=sb, height=height))
        return t
    terms = tuple(one(t) for t in b.system.terms)
    if all(x is y for x, y in zip(terms, b.system.terms)):
        raise ValueError("the scene has no wave excitation to replace")
    return b._replace(system=eqx.tree_at(lambda s: s.terms, b.system, terms))


def _batch_fn(scene: Scene, keys: tuple, mesh: Optional[Mesh] = None, excited: bool = False,
              incident: bool = False):
    """The jitted, vmapped run of a batch, kept per scene, keys, times and devices: a second batch
    of the same structure does not compile again. With a device `mesh` each device runs the vmap
    over its own runs (shard_map): the per-run loops of fem/linalg.py then stay on the device's
    share, where the compiler's partitioning of one global vmap gathered every run's matrices on
    every device."""
    cache_key = (scene, keys, mesh, excited, incident)
    try:
        hit = _BATCH_FNS.get(cache_key)
    except TypeError:                 # an unhashable scene: no reuse
        cache_key, hit = None, None
    if hit is not None:
        return hit
    fn = _vmapped(scene, keys, mesh, excited, incident)
    # XLA's options of the single run's loop (staging.XLA_OPTIONS: its classic CPU emitters compile
    # the step's many small fusions in less time, and the loop runs as fast). One program, the
    # initial state in it: compiled apart with its optimisation off, as a single run's is
    # (run/compiled.py), the vmapped loop that takes its carry ran markedly slower (docs/benchmarks.md)
    fn = jax.jit(fn, compiler_options=XLA_OPTIONS or None)
    if cache_key is not None:
        _BATCH_FNS[cache_key] = fn
        while len(_BATCH_FNS) > 8:
            _BATCH_FNS.pop(next(iter(_BATCH_FNS)))
    return fn


def _vmapped(scene: Scene, keys: tuple, mesh: Optional[Mesh], excited: bool, incident: bool):
    """The vmapped run of a batch that _batch_fn compiles (not jitted: see _seas_fn)."""
    setup0 = _setup0(scene)
    n_frames = setup0.n_steps // setup0.save_every

    def one(*v):
        if excited:
            exc, v = v[:4], v[4:]
        if incident:
            inc, v = v[:5], v[5:]
        with jax.ensure_compile_time_eval():     # the liquid's matrices are built on the host, once
            setup = prepare(scene, dict(zip(keys, v)), batch=True)
        b = core(setup.built)
        b = b._replace(system=eqx.tree_at(lambda s: s.liquid, b.system, b.system.liquid.for_batch()))
        if excited:
            b = _excited(b, exc, inc if incident else None)
        carry, f0 = start(b, setup.solver)
        carry, frames = advance(b, setup.solver, carry, n_frames, setup.save_every)
        fr = concat_frames([jax.tree_util.tree_map(lambda x: x[None], f0), frames])
        return carry, fr

    fn = jax.vmap(one, axis_name=BATCH_AXIS)     # the solver's collectives (a failed step's redo) name it
    if mesh is not None:
        fn = jax.shard_map(fn, mesh=mesh, in_specs=PartitionSpec("batch"), out_specs=PartitionSpec("batch"),
                           check_vma=False)
    return fn


def _setup0(scene: Scene):
    """prepare(scene), kept for the next batch of the scene (at most 8 scenes): a batch reads its
    step, sizes and probes' names from it, and building it again took a twentieth of a 64-run
    batch of the paper example."""
    try:
        return _kept_setup(scene)
    except TypeError:                 # an unhashable scene: built each time
        return prepare(scene)


@functools.lru_cache(maxsize=8)
def _kept_setup(scene: Scene):
    # where programs are kept in a folder (the command line, a campaign's workers), so is the model,
    # under the name `jaxslosh run` gives it: a worker's first batch reads it instead of building it
    key = model_key(scene) if folder() is not None else None
    return prepare(scene) if key is None else cached("model", key, lambda: prepare(scene))


#: the seas batches' programs read from the exported programs' folder, per scene and shapes
_SEAS_PROGRAMS: dict = {}


def _seas_fn(scene: Scene, vals: list, incident: bool):
    """The compiled batch of simulate_seas: `_batch_fn`'s, and where programs are kept in a folder
    (cache/programs.py) its exported program, read back by a later process (a campaign's every
    worker, every campaign of the scene) instead of traced: tracing the vmapped loop of the paper
    ship took seconds of each worker's start, more than XLA's cache lookup (docs/benchmarks.md)."""
    if folder() is None:
        return _batch_fn(scene, (), None, excited=True, incident=incident)
    try:
        key = (scene, incident, tuple((v.shape, str(v.dtype)) for v in vals))
        hit = _SEAS_PROGRAMS.get(key)
    except TypeError:                 # an unhashable scene: no reuse in this process
        key, hit = None, None
    if hit is None:
        hit, _ = compile_program("seas-batch", lambda sc, *v: _vmapped(sc, (), None, True, incident)(*v),
                                 (scene, *vals), XLA_OPTIONS or None)
        if key is not None:
            _SEAS_PROGRAMS[key] = hit
            while len(_SEAS_PROGRAMS) > 8:
                _SEAS_PROGRAMS.pop(next(iter(_SEAS_PROGRAMS)))
    return lambda *v: hit(scene, *v)


def check_runs(scene: Scene, params: dict) -> list:
    """Check every run of a batch as a scene file with its values would be checked (check_values);
    SceneError names the key, the run and its values. Returns each run's checked scene (their
    warnings are the loader's for that run)."""
    if is_traced(params):
        return []
    runs = []
    n = len(np.asarray(next(iter(params.values()))))
    for i in range(n):
        values = {k: np.asarray(v)[i] for k, v in params.items()}
        try:
            runs.append(check_values(scene, values))
        except SceneError as e:
            if n == 1:
                raise
            shown = ", ".join(f"{k} = {np.asarray(v).tolist()}" for k, v in values.items())
            raise SceneError(e.key, f"{str(e)[len(e.key) + 2:] if e.key else e} (run {i}: {shown})") from None
    return runs


def simulate_seas(scene: Scene, omega, amp, phase, height, incident=None) -> tuple[Result, list]:
    """Runs of one scene in B seas, one compiled vmapped loop: each run's wave excitation is
    omega (B, N), amp (B, 6, N) per unit height, phase (B, 6, N) and height (B,) (the arrays
    assemble/seakeeping.make_excitation makes of a scene's sea, all with the same component count);
    with the nonlinear hydrostatics, `incident` (k, amp, phase, cos heading, sin heading), each
    (B, N), are the components on the wetted hull (campaign/cases.sea_arrays). Returns (result
    with a leading run axis, one status per run), as simulate_batch."""
    vals = [jnp.asarray(x, dtype=float) for x in (omega, amp, phase, height)]
    if incident is not None:
        vals += [jnp.asarray(x, dtype=float) for x in incident]
    setup0 = _setup0(scene)
    carry, fr = _seas_fn(scene, vals, incident is not None)(*vals)
    return _batch_result(scene, setup0, carry, fr, int(vals[0].shape[0]))


def _batch_result(scene, setup0, carry, fr, B):
    # the failed runs' carries alone are taken apart (one small host copy each); indexing every run's
    # carry on the device took a tenth of a 64-run batch of the paper example
    failed = np.asarray(carry.failed)
    h = setup0.solver.h
    statuses = ["ok"] * B
    for i in np.flatnonzero(failed):
        statuses[i] = failure_message(jax.tree_util.tree_map(lambda x: np.asarray(x[i]), carry), h, setup0.solver.tol)
    b0 = setup0.built
    res = result_from(frame_datasets(b0, fr, fields=False), b0.probes.names,
                      status="ok" if all(s == "ok" for s in statuses) else "some runs failed",
                      steps_done=setup0.n_steps, scene_text=scene.text)
    return res, statuses


def simulate_batch(scene: Scene, params: dict, *, duration: Optional[float] = None,
                   dt: Optional[float] = None) -> tuple[Result, list]:
    """Run a batch of parameter sets in one compiled, vmapped loop.

    `params` maps dotted scene keys to arrays of equal leading length B (one value per run; a
    vector key takes (B, 3), `vessel.inertia` (B, 3) diagonals or (B, 3, 3)). Every run's values
    are checked as a scene file with them would be, before anything is computed (SceneError names
    the key and the run). Returns (result, statuses): the result's arrays carry a leading batch
    axis, statuses is one string per run ("ok" or why it stopped; a failed run keeps its last good
    state after that). With several devices the batch is sharded over them (jax.sharding), B divisible by their count.
    """
    scene = with_overrides(scene, duration=duration, dt=dt)
    keys = list(params)
    vals = [jnp.asarray(params[k], dtype=float) for k in keys]
    if not vals:
        raise ValueError("simulate_batch needs at least one parameter array")
    B = int(vals[0].shape[0])
    if any(int(v.shape[0]) != B for v in vals):
        raise ValueError("every parameter array must have the same leading length")
    check_runs(scene, params)
    devices = jax.devices()
    mesh = None
    if len(devices) > 1 and B % len(devices) == 0:
        mesh = Mesh(np.array(devices), ("batch",))
        vals = [jax.device_put(v, NamedSharding(mesh, PartitionSpec("batch", *([None] * (v.ndim - 1)))))
                for v in vals]
    setup0 = _setup0(scene)
    carry, fr = _batch_fn(scene, tuple(keys), mesh)(*vals)
    res, statuses = _batch_result(scene, setup0, carry, fr, B)
    return _batch_lines(scene, res, fr, params), statuses


def _batch_lines(scene: Scene, res: Result, fr, params: dict) -> Result:
    """A batch that varies the mooring lines' values: each run's line tensions from its own lines
    (_batch_result's come from the scene's)."""
    runs = [resolve_params(scene, {k: np.asarray(v)[i] for k, v in params.items()}) for i in range(len(res.time))]
    if not any(m.model == "catenary" for m in scene.mooring) or not any(k.startswith("mooring.") for k in runs[0]):
        return res
    rest = jnp.asarray(np.array([body_rest(b, scene.vessel.cog_height) for b in scene.bodies]).reshape(-1, 3))
    poses = (lambda i: ()) if not scene.bodies else (      # the bodies' poses, for lines that hold them
        lambda i: (fr.bodies[i][..., :3] + rest, fr.bodies[i][..., 3:7]))
    per_run = [line_datasets(build_mooring(scene, False, True, run), fr.X0[i], fr.q[i], *poses(i))
               for i, run in enumerate(runs)]
    d = {k: jnp.stack([p[k] for p in per_run]) for k in per_run[0]}
    # a lumped line's tensions are its own run's already (its nodes are states of the vmapped run)
    lines = {n: type(m)(d[f"mooring/{n}/fairlead_tension"], d[f"mooring/{n}/anchor_tension"])
             if f"mooring/{n}/fairlead_tension" in d else m for n, m in res.mooring.items()}
    return dataclasses.replace(res, mooring=lines)


def capsize_angles(scene: Scene):
    """The (roll, pitch) angles of vanishing stability of a scene with the nonlinear hydrostatics
    (run/capsize.py), None for other scenes; from the model its batches are built on. Kept per
    scene, as that model is: a campaign asks once per batch, and the GZ curves do not change."""
    return _capsize_angles(scene)[0]


def body_capsize_angles(scene: Scene) -> dict:
    """{name: (roll, pitch) angles of vanishing stability} of the scene's [[bodies]] that float on
    their own hull with the nonlinear hydrostatics (run/capsize.py body_vanishing_angles), kept as
    capsize_angles' are; {} without such bodies."""
    return _capsize_angles(scene)[1]


def _capsize_angles(scene: Scene) -> tuple:
    try:
        return _kept_angles(scene)
    except TypeError:                 # an unhashable scene: computed each time
        return _all_angles(scene)


@functools.lru_cache(maxsize=8)
def _kept_angles(scene: Scene):
    return _all_angles(scene)


def _all_angles(scene: Scene) -> tuple:
    system = _setup0(scene).built.system
    return vanishing_angles(system), body_vanishing_angles(system)
