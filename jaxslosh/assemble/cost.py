"""What a scene will cost before anything is built: unknowns, memory, steps; and the refusal of a
scene this machine cannot hold.

The memory is an estimate of the largest phase, tank by tank, as assemble/ assembles them: the element
arrays of the assembly, then the solver's blocks (dense inverses below `SPARSE_AUTO` unknowns; above
it the sparse matrices and the fast-diagonalization blocks, the JAX factors of shaped tanks, or the
sparse factor that the modal basis of a reduced tank needs), plus the result's frames. It is meant to tell 1 GB from 1 TB, not
to predict the process's peak to a few per cent.
"""
from __future__ import annotations

import os
from typing import NamedTuple

from ..scene.types import Scene, SceneError
from ..solve.factored import DENSE_MAX
from ..liquid.nodal.sparse import SPARSE_AUTO
from .effects import count_unknowns, free_liquid_dofs

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


def _factor_bytes(t, nf: int) -> float:
    """The liquid block's JAX factors of a tank the fast diagonalization does not take (solve/
    factored.py): the step's and the mass's, dense inverses or banded block factors, whose RCM
    bandwidth is about twice the dofs of a cross-section across the two shortest node counts."""
    if nf <= DENSE_MAX:
        return 2 * 8.0 * nf * nf
    a, b, _ = sorted(n + 1 for n in t.mesh)
    return 2 * 8.0 * 2 * nf * min(nf, 2 * 3 * a * b)


def _tank_bytes(t, sparse: bool, host_lu: bool = False, rt_dense: bool = False) -> float:
    nx, ny, nz = t.mesh
    E = nx * ny * nz
    N = (nx + 1) * (ny + 1) * (nz + 1)
    nf = free_liquid_dofs(t)
    assembly = 8.0 * E * (24 * 24) * 3 + 8.0 * E * 64 * 3            # COO rows, columns and values
    if t.form.face_normal and not t.form.reduced:
        # face-normal at full order (liquid/face/build.py): dense M, K and inverses on the ~3E
        # faces, or (sparse) dense blocks on the elements and top faces only, ~7 of them while the
        # Schur complement's inverses are formed (liquid/face/schur.py)
        return max(assembly, 8.0 * 6 * (3 * E) ** 2 if rt_dense else 8.0 * 7 * (E + nx * ny) ** 2)
    if not sparse:
        solver = 8.0 * (N * N + 4.0 * nf * nf)                      # mass, stiffness, two or three inverses
    else:
        solver = 8.0 * 81 * 3 * nf * 2 + 8.0 * nx * ny * (3 * (nz + 1)) ** 2   # sparse products, box blocks
        if not t.geometry.plain_box and not host_lu and not t.form.reduced:
            solver += _factor_bytes(t, nf)
        if t.form.reduced:                                           # the basis: a sparse factor of the mesh
            solver = max(solver, 8.0 * nf * 30 * max(nx * ny, ny * nz, nx * nz) ** 0.5)
    return max(assembly, solver)


def estimate(scene: Scene) -> Cost:
    sim = scene.simulation
    steps = sim.n_steps
    frames = steps // max(1, sim.save_every) + 1
    liquid = sum(free_liquid_dofs(t) for t in scene.tanks) if scene.effects.liquid else 0
    choice = sim.linear_solver
    sparse = choice in ("sparse", "sparse-host") or (choice == "auto" and liquid > SPARSE_AUTO
                                    and not any(t.form.elastic for t in scene.tanks))
    worst, total = ("", 0.0), 0.0
    for i, t in enumerate(scene.tanks if scene.effects.liquid else ()):
        b = _tank_bytes(t, sparse, choice == "sparse-host", choice == "dense")
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
