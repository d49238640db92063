"""What a Dask worker runs: a batch of a campaign's cases in one compiled, vmapped loop
(run/batch.simulate_seas), reduced to their statistics on the worker (only those travel back).

Every batch of a campaign has the same length (a short last batch is padded with copies of its
last case, whose results are dropped), so that a worker compiles the scene's loop once per sea
structure (component count) and a case's numbers do not depend on which batch, worker or order
ran it."""
from __future__ import annotations

import dataclasses
import os
from typing import Optional

import jax
import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from ..assemble.hull import hull_waves
from ..cache.programs import install as install_cache
from ..cache import programs
from ..run.batch import body_capsize_angles, capsize_angles, simulate_seas
from ..run.capsize import case_capsize
from ..scene.load import parse_scene
from ..scene.types import Scene
from .cases import case_scene, sea_arrays
from .stats import case_statistics, channels

_TEMPLATES: dict = {}


def configure_jax(cache_dir: Optional[str], programs_dir: Optional[str] = None):
    """float64, and the client's persistent compilation cache folder (shared by every worker of
    one machine: the second worker to compile a scene's loop reads the first one's), and its
    exported programs' folder (cache/programs.py): a worker that finds the batch's program and
    model there neither traces the vmapped loop nor builds the model (seconds of each worker's
    start, docs/benchmarks.md)."""
    jax.config.update("jax_enable_x64", True)
    install_cache()             # a worker process is an entry point of its own
    if cache_dir:
        jax.config.update("jax_compilation_cache_dir", cache_dir)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
        jax.config.update("jax_persistent_cache_min_entry_size_bytes", -1)
    if programs_dir and programs.folder() != programs_dir:
        programs.use(programs_dir)


def template_scene(text: str, path: str, duration: Optional[float]) -> Scene:
    key = (text, path, duration)
    if key not in _TEMPLATES:
        scene = parse_scene(tomllib.loads(text), text=text, path=path)
        if duration is not None:
            scene = dataclasses.replace(scene, simulation=dataclasses.replace(scene.simulation,
                                                                              duration=float(duration)))
        _TEMPLATES.clear()
        _TEMPLATES[key] = scene
    return _TEMPLATES[key]


def structure_scene(template: Scene, case: Scene) -> Scene:
    """The scene a batch is compiled for: the template with the case's sea structure (its
    component count; with the nonlinear hydrostatics, its depth and frequency range), the sea's
    values fixed; the runs replace its excitation by their own."""
    w = dataclasses.replace(template.waves, spreading=case.waves.spreading, directions=case.waves.directions,
                            components=case.waves.components)
    if hull_waves(template):
        # the wetted hull's wave pressure is compiled for the depth, and its panels for the top of
        # the frequency range (scene/hulls.py BoxHull.divisions)
        w = dataclasses.replace(w, depth=case.waves.depth, omega_range=case.waves.omega_range)
    return dataclasses.replace(template, waves=w)


def run_batch(text: str, path: str, duration: Optional[float], values: list, batch: int,
              cache_dir: Optional[str] = None, programs_dir: Optional[str] = None, scenes: Optional[list] = None) -> list:
    """Run the cases `values` (their [waves] values, all of one sea structure) padded to `batch`
    runs; returns per case {"status": ..., "stats": {channel: {std, significant, max, mpm, tz,
    spectrum}}, "pid": the worker's process id}. `scenes`: the cases' scenes (case_scene's) where
    the caller has them (the batches run in the campaign's own process, which built every case's
    scene to check it: reading each again cost as much)."""
    configure_jax(cache_dir, programs_dir)
    template = template_scene(text, path, duration)
    if scenes is None:
        scenes = [case_scene(template, v, duration) for v in values]
    seas = [sea_arrays(s) for s in scenes]
    seas += [seas[-1]] * (batch - len(seas))
    omega, amp, phase, hs = (np.stack([s[k] for s in seas]) for k in range(4))
    incident = None if seas[0][4] is None else tuple(np.stack([s[4][k] for s in seas]) for k in range(5))
    structure = structure_scene(template, scenes[0])
    result, statuses = simulate_seas(structure, omega, amp, phase, hs, incident)
    t = np.asarray(result.time)
    angles, body_angles = capsize_angles(structure), body_capsize_angles(structure)
    out = []
    for i, s in enumerate(scenes):
        if statuses[i] == "ok" and (angles is not None or body_angles):     # the vessel's hull, then each body's
            bodies = {n: (np.asarray(result.bodies[n].roll_pitch_yaw[i]), a) for n, a in body_angles.items()}
            statuses[i] = case_capsize(result.vessel.roll_pitch_yaw[i], angles, bodies) or "ok"
        st = case_statistics(t[i], channels(result, i), s.waves.ramp) if statuses[i] == "ok" else None
        out.append({"status": statuses[i], "stats": st, "pid": os.getpid()})
    return out
