"""What a scene will cost before anything is built: unknowns, memory, steps; and the refusal of a
scene this machine cannot hold.

The memory is an estimate of the largest phase, tank by tank, as the model that runs each tank's form
counts it (liquid/cost.py: the element arrays of the assembly, then the solver's blocks, dense or on
the sparse way that assemble/liquid.py `wants_sparse` chooses), plus the result's frames. It is meant
to tell 1 GB from 1 TB, not to predict the process's peak to a few per cent.
"""
from __future__ import annotations

import os
from typing import NamedTuple

from ..liquid.forms import tank_liquid
from ..scene.types import Scene, SceneError
from .effects import count_unknowns
from .liquid import wants_sparse

#: a scene is refused when its estimate exceeds this share of the machine's memory (unless forced)
MEMORY_SHARE = 0.8
#: result fields are not saved when they would exceed this (run/tofile.py)
FIELDS_LIMIT = 200e6


class Cost(NamedTuple):
    unknowns: int
    memory: float                 # bytes, the estimate
    steps: int
    frames: int
    worst: tuple                  # (dotted key of the costliest tank or "", its bytes)


def machine_memory() -> float:
    """Physical memory in bytes (the cgroup limit where it is lower)."""
    total = float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    try:
        with open("/sys/fs/cgroup/memory.max") as f:
            v = f.read().strip()
        if v.isdigit():
            total = min(total, float(v))
    except OSError:
        pass
    return total


def estimate(scene: Scene) -> Cost:
    sim = scene.simulation
    steps = sim.n_steps
    frames = steps // max(1, sim.save_every) + 1
    liquid = scene.effects.liquid and bool(scene.tanks)
    choice = sim.linear_solver
    sparse = wants_sparse(scene)
    worst, total = ("", 0.0), 0.0
    for i, t in enumerate(scene.tanks if scene.effects.liquid else ()):
        b = tank_liquid(t).tank_bytes(t, sparse, choice == "sparse-host", choice == "dense")
        total += b
        if b > worst[1]:
            worst = (f"tanks[{i}].mesh", b)
    nodes = sum((t.mesh[0] + 1) * (t.mesh[1] + 1) * (t.mesh[2] + 1) for t in scene.tanks) if liquid else 0
    fields = 8.0 * 3 * nodes * frames
    total += 8.0 * frames * (32 + 6 * len(scene.probes)) + (fields if fields < FIELDS_LIMIT else 0.0)
    return Cost(count_unknowns(scene), total, steps, frames, worst)


def describe_cost(c: Cost) -> str:
    return (f"cost: {c.unknowns:,} unknowns, about {_bytes(c.memory)} of memory, {c.steps:,} steps, "
            f"{c.frames:,} saved frames (this machine: {_bytes(machine_memory())})")


def check_cost(scene: Scene, force: bool = False) -> Cost:
    """The estimate; SceneError naming the costliest tank's mesh when it exceeds what this machine
    holds, unless `force`."""
    c = estimate(scene)
    limit = MEMORY_SHARE * machine_memory()
    if c.memory > limit and not force:
        key = c.worst[0] or "simulation.duration"
        raise SceneError(key, f"the scene needs about {_bytes(c.memory)} ({c.unknowns:,} unknowns), more than this "
                              f"machine holds ({_bytes(machine_memory())}); use a coarser mesh or "
                              f"[tanks.reduction], or --force to run anyway")
    return c


def _bytes(x: float) -> str:
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if x >= size:
            return f"{x / size:.3g} {unit}"
    return f"{x:.0f} B"
