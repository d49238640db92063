"""The result of a run: a pytree mirroring the HDF5 result file (SPEC section 3), and its file io.

The file is written in chunks while a run goes on (`ResultWriter`): datasets are resizable along
time and `steps_done` is updated after each chunk, so a file left by a killed run opens and holds
the steps done.
"""
from __future__ import annotations

from typing import Optional

import equinox as eqx
import h5py
import jax
import numpy as np

from .._version import __version__

FORMAT = "jaxslosh.result"
FORMAT_VERSION = 1


class VesselHistory(eqx.Module):
    position: jax.Array          # (n, 3)
    quaternion: jax.Array        # (n, 4)
    angular_velocity: jax.Array  # (n, 3)
    roll_pitch_yaw: jax.Array    # (n, 3)


class ProbeHistory(eqx.Module):
    position: jax.Array          # (n, 3)
    displacement: jax.Array      # (n, 3)


class Energy(eqx.Module):
    kinetic: jax.Array
    potential: jax.Array

    @property
    def total(self):
        return self.kinetic + self.potential


class SolverHistory(eqx.Module):
    iterations: jax.Array
    residual: jax.Array
    constraint: Optional[jax.Array] = None   # max |g| of the interface constraints per step, m (0 without structures)


class TankField(eqx.Module):
    nodes: np.ndarray            # (m, 3) tank-local
    elements: np.ndarray         # (e, 8)
    displacement: jax.Array      # (k, m, 3) tank frame, deformational


class Result(eqx.Module):
    time: jax.Array
    vessel: VesselHistory
    probes: dict
    energy: Energy
    solver: SolverHistory
    tanks: dict
    status: str = eqx.field(static=True, default="ok")
    steps_done: int = eqx.field(static=True, default=0)
    scene_text: str = eqx.field(static=True, default="")


class ResultWriter:
    """Appends frames to an HDF5 result file as a run goes on."""

    def __init__(self, path: str, scene_text: str, probe_names, tanks=()):
        self.path = path
        self.f = h5py.File(path, "w")
        a = self.f.attrs
        a["format"] = FORMAT
        a["format_version"] = FORMAT_VERSION
        a["scene"] = scene_text
        a["jaxslosh_version"] = __version__
        a["status"] = "running"
        a["steps_done"] = 0
        self.n = 0
        self.probe_names = list(probe_names)
        self.tank_names = []
        spec = {"time": (), "vessel/position": (3,), "vessel/quaternion": (4,), "vessel/angular_velocity": (3,),
                "vessel/roll_pitch_yaw": (3,), "energy/kinetic": (), "energy/potential": (),
                "solver/iterations": (), "solver/residual": (), "solver/constraint": ()}
        for p in self.probe_names:
            spec[f"probes/{p}/position"] = (3,)
            spec[f"probes/{p}/displacement"] = (3,)
        for t in tanks:
            self.f.create_dataset(f"tanks/{t.name}/nodes", data=t.nodes)
            self.f.create_dataset(f"tanks/{t.name}/elements", data=t.elements)
            spec[f"tanks/{t.name}/displacement"] = (t.nodes.shape[0], 3)
            self.tank_names.append(t.name)
        for k, shape in spec.items():
            dtype = "i8" if k == "solver/iterations" else "f8"
            self.f.create_dataset(k, shape=(0, *shape), maxshape=(None, *shape), dtype=dtype,
                                  chunks=(max(1, min(1024, 2 ** 20 // (8 * max(1, int(np.prod(shape)))))), *shape))
        self.f.flush()

    def append(self, frames: dict, steps_done: int):
        k = len(frames["time"])
        if k == 0:
            return
        for key, val in frames.items():
            ds = self.f[key]
            ds.resize(self.n + k, axis=0)
            ds[self.n:self.n + k] = val
        self.n += k
        self.f.attrs["steps_done"] = int(steps_done)
        self.f.flush()

    def close(self, status: str, steps_done: int):
        self.f.attrs["status"] = status
        self.f.attrs["steps_done"] = int(steps_done)
        self.f.close()


def result_frames(r: Result) -> dict:
    """The flat {dataset: array} view of a Result, as the file stores it."""
    d = {"time": r.time, "vessel/position": r.vessel.position, "vessel/quaternion": r.vessel.quaternion,
         "vessel/angular_velocity": r.vessel.angular_velocity, "vessel/roll_pitch_yaw": r.vessel.roll_pitch_yaw,
         "energy/kinetic": r.energy.kinetic, "energy/potential": r.energy.potential,
         "solver/iterations": r.solver.iterations, "solver/residual": r.solver.residual,
         "solver/constraint": (r.solver.constraint if r.solver.constraint is not None else np.zeros_like(r.time))}
    for name, p in r.probes.items():
        d[f"probes/{name}/position"] = p.position
        d[f"probes/{name}/displacement"] = p.displacement
    for name, t in r.tanks.items():
        d[f"tanks/{name}/displacement"] = t.displacement
    return {k: np.asarray(v) for k, v in d.items()}


def save_result(r: Result, path: str) -> None:
    class _T:  # the writer needs name/nodes/elements of each tank
        def __init__(self, name, t):
            self.name, self.nodes, self.elements = name, t.nodes, t.elements
    w = ResultWriter(path, r.scene_text, list(r.probes), [_T(n, t) for n, t in r.tanks.items()])
    w.append(result_frames(r), r.steps_done)
    w.close(r.status, r.steps_done)


def _attr_str(v) -> str:
    return v.decode() if isinstance(v, bytes) else str(v)


def load_result(path: str) -> Result:
    with h5py.File(path, "r") as f:
        a = f.attrs
        if _attr_str(a.get("format", "")) != FORMAT:
            raise ValueError(f"{path}: not a jaxslosh result file")
        n = f["time"].shape[0]
        g = lambda k: np.asarray(f[k][:n])  # noqa: E731
        probes = {}
        if "probes" in f:
            for name in f["probes"]:
                probes[name] = ProbeHistory(g(f"probes/{name}/position"), g(f"probes/{name}/displacement"))
        tanks = {}
        if "tanks" in f:
            for name in f["tanks"]:
                tanks[name] = TankField(np.asarray(f[f"tanks/{name}/nodes"]), np.asarray(f[f"tanks/{name}/elements"]),
                                        g(f"tanks/{name}/displacement"))
        return Result(
            time=g("time"),
            vessel=VesselHistory(g("vessel/position"), g("vessel/quaternion"), g("vessel/angular_velocity"),
                                 g("vessel/roll_pitch_yaw")),
            probes=probes, energy=Energy(g("energy/kinetic"), g("energy/potential")),
            solver=SolverHistory(g("solver/iterations"), g("solver/residual"),
                                 g("solver/constraint") if "solver/constraint" in f else None), tanks=tanks,
            status=_attr_str(a.get("status", "ok")), steps_done=int(a.get("steps_done", 0)),
            scene_text=_attr_str(a.get("scene", "")))


def truncated(r: Result, n: int, status: Optional[str] = None, steps_done: Optional[int] = None) -> Result:
    """The first n frames of a result."""
    cut = lambda x: x[:n]  # noqa: E731
    return Result(
        time=cut(r.time), vessel=jax.tree_util.tree_map(cut, r.vessel),
        probes={k: jax.tree_util.tree_map(cut, p) for k, p in r.probes.items()},
        energy=jax.tree_util.tree_map(cut, r.energy), solver=jax.tree_util.tree_map(cut, r.solver),
        tanks={k: TankField(t.nodes, t.elements, cut(t.displacement)) for k, t in r.tanks.items()},
        status=r.status if status is None else status,
        steps_done=r.steps_done if steps_done is None else steps_done, scene_text=r.scene_text)
