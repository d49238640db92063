"""The result of a run: a pytree mirroring the HDF5 result file (docs/reference/files.md), and its file io.

The file's datasets are written down once (`schema`); the writer, the reader, `result_frames` (a
Result as datasets) and `result_from` (datasets as a Result) all follow it. The file is written in
chunks while a run goes on (`ResultWriter`): datasets are resizable along time and `steps_done` is
updated after each chunk, so a file left by a killed run opens and holds the steps done.
"""
from __future__ import annotations

import contextlib
import dataclasses
import os
from typing import Optional

import equinox as eqx
import h5py
import jax
import numpy as np

from .._version import __version__
from ..staging import on_device
from .line_energy import LINE_ENERGY, line_energy_of
from .output import OutputLock, ensure_room
from .status import TEXT, Failure, RunResult, Status, code_of, failure_text, is_traced as _is_traced, outcome_of

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


class LineHistory(eqx.Module):
    fairlead_tension: jax.Array  # (n,) N
    anchor_tension: jax.Array    # (n,) N
    nodes: Optional[jax.Array] = None   # (n, s + 1, 3) m: a lumped line's nodes, anchor to fairlead
    energy: Optional[dict] = None       # {part: (n,)} J: a lumped line's energies (LINE_ENERGY)


class ConnectionHistory(eqx.Module):
    force: jax.Array             # (n,) N, positive when it pulls
    extension: jax.Array         # (n,) m: the points' distance less the length


class Result(eqx.Module):
    """A run's frames and how it ended. `outcome` (io.status.RunResult) is a leaf: right under
    `jax.jit` and `vmap`, where a string cannot be; `status` and `status_code` read it (and
    `failure`) once it is concrete. `steps` is the steps done, a leaf too (`steps_done` as an int)."""
    time: jax.Array
    vessel: VesselHistory
    probes: dict
    energy: Energy
    solver: SolverHistory
    tanks: dict
    outcome: RunResult = None
    steps: jax.Array = 0
    failure: Optional[Failure] = None
    note: str = eqx.field(static=True, default="")       # the host's own text of the ending, where it has one
    scene_text: str = eqx.field(static=True, default="")
    dt: float = eqx.field(static=True, default=0.0)       # to put the failed step's time in the text
    tolerance: float = eqx.field(static=True, default=0.0)


    def __init__(self, time, vessel, probes, energy, solver, tanks, outcome=None, steps=0, failure=None, note="",
                 scene_text="", dt=0.0, tolerance=0.0, mooring=None, bodies=None, connections=None, *,
                 status=None, steps_done=None, status_code=None):
        """The fields, or as before `outcome` and `steps` were leaves: `status` (the text, kept as the
        note; its code read from it), `status_code` and `steps_done`."""
        if status is not None:
            note = status
        if status_code is not None or (status is not None and outcome is None):
            outcome = outcome_of(code_of(status) if status_code is None else status_code)
        self.time, self.vessel, self.probes, self.energy, self.solver, self.tanks = time, vessel, probes, energy, solver, tanks
        self.outcome = RunResult.ok if outcome is None else outcome
        self.steps = steps if steps_done is None else steps_done
        self.failure, self.note, self.scene_text, self.dt, self.tolerance = failure, note, scene_text, dt, tolerance
        self.mooring, self.bodies, self.connections = mooring, bodies, connections

    @property
    def status(self) -> str:
        """"ok" or why the run stopped (the result file's `status`: its step, time and residual). Inside a
        transformation, where the outcome is not known yet, a sentence saying to read `outcome`."""
        if self.note:
            return self.note
        if _is_traced(self.outcome):
            return "traced: read result.outcome (io.status.RunResult) once the run is computed"
        code = self.status_code
        if code == Status.OK:
            return "ok"
        if Status(code).numerical and self.failure is not None and not _is_traced(self.failure):
            f = self.failure
            return failure_text(code, int(np.asarray(f.step).reshape(-1)[0]), self.dt,
                                float(np.asarray(f.residual).reshape(-1)[0]),
                                int(np.asarray(f.iterations).reshape(-1)[0]), self.tolerance)
        return TEXT[Status(code)]

    @property
    def status_code(self) -> int:
        """The outcome's io.status.Status code (the first failed run's, for a batch)."""
        v = np.asarray(self.outcome._value).reshape(-1)
        bad = v[v != 0]
        return int(bad[0]) if bad.size else 0

    @property
    def steps_done(self) -> int:
        return int(np.max(np.asarray(self.steps)))

    @property
    def ok(self):
        """Whether the run ended well (a traced boolean inside a transformation)."""
        return self.outcome == RunResult.ok
    mooring: Optional[dict] = None     # {line: LineHistory} of a moored scene
    bodies: Optional[dict] = None      # {body: VesselHistory} of the [[bodies]] (position: offset from rest)
    connections: Optional[dict] = None  # {connection: ConnectionHistory} of the [[connections]]


def schema(probe_names=(), tank_nodes: Optional[dict] = None, lines=(), line_nodes: Optional[dict] = None,
           bodies=(), connections=(), line_energy=()) -> dict:
    """{dataset: shape of one frame} of a result file, in the file's order (`line_energy`: lumped lines)."""
    spec = {"time": (), "vessel/position": (3,), "vessel/quaternion": (4,), "vessel/angular_velocity": (3,),
            "vessel/roll_pitch_yaw": (3,), "energy/kinetic": (), "energy/potential": (),
            "solver/iterations": (), "solver/residual": (), "solver/constraint": ()}
    for p in probe_names:
        spec[f"probes/{p}/position"] = (3,)
        spec[f"probes/{p}/displacement"] = (3,)
    for name, n in (tank_nodes or {}).items():
        spec[f"tanks/{name}/displacement"] = (n, 3)
    for name in lines:
        spec[f"mooring/{name}/fairlead_tension"] = ()
        spec[f"mooring/{name}/anchor_tension"] = ()
    for name, n in (line_nodes or {}).items():       # lumped lines: their nodes (s + 1 of them)
        spec[f"mooring/{name}/nodes"] = (n, 3)
    spec.update({f"energy/mooring/{name}/{k}": () for name in line_energy for k in LINE_ENERGY})
    for name in bodies:
        spec[f"bodies/{name}/position"] = (3,)
        spec[f"bodies/{name}/quaternion"] = (4,)
        spec[f"bodies/{name}/angular_velocity"] = (3,)
        spec[f"bodies/{name}/roll_pitch_yaw"] = (3,)
    for name in connections:
        spec[f"connections/{name}/force"] = ()
        spec[f"connections/{name}/extension"] = ()
    return spec


#: each dataset's `units` attribute (UDUNITS strings, as xarray and CF readers expect; "1": a pure
#: number), by the dataset's name with probe and tank names taken out
UNITS = {"time": "s", "vessel/position": "m", "vessel/quaternion": "1", "vessel/angular_velocity": "rad/s",
         "vessel/roll_pitch_yaw": "rad", "energy/kinetic": "J", "energy/potential": "J", "solver/iterations": "1",
         "solver/residual": "m/s^2", "solver/constraint": "m", "probes/position": "m", "probes/displacement": "m",
         "tanks/displacement": "m", "tanks/nodes": "m", "tanks/elements": "1", "mooring/fairlead_tension": "N",
         "mooring/anchor_tension": "N", "mooring/nodes": "m",
         "bodies/position": "m", "bodies/quaternion": "1",
         "bodies/angular_velocity": "rad/s", "bodies/roll_pitch_yaw": "rad", "connections/force": "N",
         "connections/extension": "m"}

#: a `description` attribute where the unit alone does not say what a dataset holds
DESCRIPTIONS = {
    "vessel/quaternion": "Euler parameters of the attitude, scalar first",
    "vessel/angular_velocity": "angular velocity in the body frame",
    "vessel/position": "inertial position of the vessel's centre of gravity",
    "solver/residual": "largest scaled Newton residual of the steps since the last frame: an acceleration "
                       "error (m/s^2 on translations, rad/s^2 on rotations)",
    "solver/iterations": "largest Newton iteration count of the steps since the last frame",
    "solver/constraint": "largest interface constraint violation of flexible structures (0 without them)",
    "tanks/displacement": "the liquid's deformational displacement at the nodes, tank frame",
    "tanks/elements": "hexahedra: 8 node indices each (0-based)",
    "bodies/position": "offset of the body's centre of gravity from its rest position, inertial",
    "bodies/quaternion": "Euler parameters of the body's attitude (its heading included), scalar first",
    "bodies/angular_velocity": "angular velocity in the body's frame",
    "connections/force": "the connection's force, positive when it pulls its points together",
    "connections/extension": "the distance of the connection's points less its length",
    **{f"energy/mooring/{k}": v for k, v in LINE_ENERGY.items()},
}


def units_of(key: str) -> str:
    """The `units` attribute of a result dataset (see UNITS)."""
    parts = key.split("/")
    if parts[0] in ("probes", "tanks", "mooring", "bodies", "connections") and len(parts) == 3:
        key = f"{parts[0]}/{parts[2]}"
    return "J" if parts[0] == "energy" else UNITS.get(key, "1")


def label(ds, key: str) -> None:
    """Write a dataset's `units` (and `description`, where one is known) attributes."""
    ds.attrs["units"] = units_of(key)
    parts = key.split("/")
    short = f"{parts[0]}/{parts[2]}" if parts[0] in ("probes", "tanks", "bodies", "connections") and len(parts) == 3 \
        else "/".join(parts[:2] + parts[3:]) if parts[:2] == ["energy", "mooring"] else key
    if short in DESCRIPTIONS:
        ds.attrs["description"] = DESCRIPTIONS[short]


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
    for name, m in (r.mooring or {}).items():
        d[f"mooring/{name}/fairlead_tension"] = m.fairlead_tension
        d[f"mooring/{name}/anchor_tension"] = m.anchor_tension
        if m.nodes is not None:
            d[f"mooring/{name}/nodes"] = m.nodes
        d.update({f"energy/mooring/{name}/{k}": v for k, v in (m.energy or {}).items()})
    for name, b in (r.bodies or {}).items():
        d[f"bodies/{name}/position"] = b.position
        d[f"bodies/{name}/quaternion"] = b.quaternion
        d[f"bodies/{name}/angular_velocity"] = b.angular_velocity
        d[f"bodies/{name}/roll_pitch_yaw"] = b.roll_pitch_yaw
    for name, c in (r.connections or {}).items():
        d[f"connections/{name}/force"] = c.force
        d[f"connections/{name}/extension"] = c.extension
    return {k: np.asarray(v) for k, v in d.items()}


def result_from(d: dict, probe_names=(), tanks: Optional[dict] = None, *, status: str = "ok", steps_done=0,
                scene_text: str = "", status_code=None, failure: Optional[Failure] = None, dt: float = 0.0,
                tolerance: float = 0.0) -> Result:
    """A Result from {dataset: array} (the file's names; a leading batch axis is kept as it is) and
    the tanks' meshes {name: (nodes, elements)} of the fields `d` holds. `status`: the host's text of
    the ending ("" to read it from `status_code` and `failure`, which may be traced); `status_code`:
    an io.status.Status code or array of them (from `status` when not given)."""
    probes = {p: ProbeHistory(d[f"probes/{p}/position"], d[f"probes/{p}/displacement"]) for p in probe_names}
    fields = {n: TankField(nodes, elements, d[f"tanks/{n}/displacement"]) for n, (nodes, elements) in (tanks or {}).items()
              if f"tanks/{n}/displacement" in d}
    code = code_of(status) if status_code is None else status_code
    lines = [k.split("/")[1] for k in d if k.startswith("mooring/") and k.endswith("/fairlead_tension")]
    mooring = {n: LineHistory(d[f"mooring/{n}/fairlead_tension"], d[f"mooring/{n}/anchor_tension"],
                              d.get(f"mooring/{n}/nodes"), line_energy_of(d, n)) for n in lines}
    bodies = {n: VesselHistory(*(d[f"bodies/{n}/{k}"] for k in ("position", "quaternion", "angular_velocity",
                                                                 "roll_pitch_yaw")))
              for n in dict.fromkeys(k.split("/")[1] for k in d if k.startswith("bodies/"))}
    connections = {n: ConnectionHistory(d[f"connections/{n}/force"], d[f"connections/{n}/extension"])
                   for n in dict.fromkeys(k.split("/")[1] for k in d if k.startswith("connections/"))}
    return Result(time=d["time"],
                  vessel=VesselHistory(d["vessel/position"], d["vessel/quaternion"], d["vessel/angular_velocity"],
                                       d["vessel/roll_pitch_yaw"]),
                  probes=probes, energy=Energy(d["energy/kinetic"], d["energy/potential"]),
                  solver=SolverHistory(d["solver/iterations"], d["solver/residual"], d.get("solver/constraint")),
                  tanks=fields, outcome=outcome_of(code), steps=steps_done, failure=failure, note=status,
                  scene_text=scene_text, dt=float(dt), tolerance=float(tolerance),
                  mooring=mooring or None, bodies=bodies or None, connections=connections or None)


class ResultWriter:
    """Appends frames to an HDF5 result file as a run goes on. It holds the output's lock from
    before the file is truncated until it is closed (a second writer gets io.output.OutputError)."""

    def __init__(self, path: str, scene_text: str, probe_names, tanks=(), lines=(), line_nodes=None, bodies=(),
                 connections=(), line_energy=()):
        self.path = path
        self.lock = OutputLock(path)
        try:
            self.f = h5py.File(path, "w")
        except BaseException:
            self.lock.release()
            raise
        a = self.f.attrs
        a["format"] = FORMAT
        a["format_version"] = FORMAT_VERSION
        a["scene"] = scene_text
        a["jaxslosh_version"] = __version__
        a["status"] = "running"
        a["status_code"] = int(Status.RUNNING)
        a["steps_done"] = 0
        self.n = 0
        for t in tanks:
            label(self.f.create_dataset(f"tanks/{t.name}/nodes", data=t.nodes), f"tanks/{t.name}/nodes")
            label(self.f.create_dataset(f"tanks/{t.name}/elements", data=t.elements), f"tanks/{t.name}/elements")
        for k, shape in schema(probe_names, {t.name: t.nodes.shape[0] for t in tanks}, lines, line_nodes, bodies,
                               connections, line_energy).items():
            dtype = "i8" if k == "solver/iterations" else "f8"
            label(self.f.create_dataset(k, shape=(0, *shape), maxshape=(None, *shape), dtype=dtype,
                                        chunks=(max(1, min(1024, 2 ** 20 // (8 * max(1, int(np.prod(shape)))))),
                                                *shape)), k)
        self.f.flush()

    def append(self, frames: dict, steps_done: int):
        k = len(frames["time"])
        if k == 0:
            return
        ensure_room(self.path, sum(np.asarray(v).nbytes for v in frames.values()))
        for key, val in frames.items():
            ds = self.f[key]
            ds.resize(self.n + k, axis=0)
            ds[self.n:self.n + k] = val
        self.n += k
        self.f.attrs["steps_done"] = int(steps_done)
        self.f.flush()

    def close(self, status: str, steps_done: int, code: Optional[int] = None, warnings=()):
        """Say how the run ended. On a full disk the attributes may not fit either: the file then
        keeps its last flushed state ("running" and the steps of the last chunk written)."""
        try:
            self.f.attrs["status"] = status
            self.f.attrs["status_code"] = int(code_of(status) if code is None else code)
            self.f.attrs["steps_done"] = int(steps_done)
            if warnings:
                self.f.attrs["warnings"] = np.array(list(warnings), dtype=h5py.string_dtype())
        finally:
            try:
                self.f.close()
            finally:
                self.lock.release()


class _Mesh:
    """What the writer needs of a tank: its name and mesh."""

    def __init__(self, name, nodes, elements):
        self.name, self.nodes, self.elements = name, nodes, elements


def save_result(r: Result, path: str) -> None:
    w = ResultWriter(path, r.scene_text, list(r.probes), [_Mesh(n, t.nodes, t.elements) for n, t in r.tanks.items()],
                     list(r.mooring or {}),
                     {n: m.nodes.shape[-2] for n, m in (r.mooring or {}).items() if m.nodes is not None},
                     list(r.bodies or {}), list(r.connections or {}),
                     [n for n, m in (r.mooring or {}).items() if m.energy is not None])
    w.append(result_frames(r), r.steps_done)
    w.close(r.status, r.steps_done, r.status_code)


def attr_str(v) -> str:
    return v.decode() if isinstance(v, bytes) else str(v)


class ResultFileError(ValueError, OSError):
    """A result (or sweep) file that cannot be read; the message is one line naming the file and
    what is wrong with it (the command line prints it as it is, exit status 2). Both a ValueError
    and an OSError: code written when load_result raised either (a wrong format; h5py's errors)
    still catches it."""


def _h5_reason(e: Exception) -> str:
    """h5py's message on one line and cut short (its tail is HDF5's internals: the time, the file
    descriptor, buffer addresses)."""
    text = " ".join(str(e).split())
    return text if len(text) <= 120 else text[:117] + "..."


@contextlib.contextmanager
def open_h5(path: str):
    """The HDF5 file at `path`, open for reading, or a ResultFileError that says why not. h5py
    reports a damaged file by several exceptions (OSError, RuntimeError, KeyError, ...), wherever
    a read meets the damage: inside this block each becomes a ResultFileError naming the file."""
    if os.path.isdir(path):
        raise ResultFileError(f"{path}: is a directory, not a result file")
    if not os.path.exists(path):
        raise ResultFileError(f"{path}: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise ResultFileError(f"{path}: not an HDF5 file, or truncated or corrupt ({_h5_reason(e)})") from None
    try:
        yield f
    except ResultFileError:
        raise
    except (OSError, RuntimeError, KeyError, ValueError, TypeError, IndexError) as e:
        raise ResultFileError(f"{path}: cannot be read, the file is truncated or corrupt ({_h5_reason(e)})") from None
    finally:
        try:
            f.close()
        except (OSError, RuntimeError):
            pass


@contextlib.contextmanager
def open_format(path: str, expected: str, what: str):
    """open_h5, for a file whose format (file_format) must be `expected` ("sweep", "campaign": what
    the message calls it): a ResultFileError otherwise."""
    with open_h5(path) as f:
        fmt = file_format(f, path)
        if fmt != expected:
            raise ResultFileError(f"{path}: not a jaxslosh {what} file (format {fmt!r})")
        yield f


def file_format(f: h5py.File, path: str) -> str:
    """The file's `format` attribute, after checking its `format_version` is one this jaxslosh reads
    (files written before the attribute existed are version 1); a newer one is refused, since its
    datasets may mean what this version does not know."""
    fmt = attr_str(f.attrs.get("format", ""))
    v = f.attrs.get("format_version", 1)
    try:
        version = int(v)
        if version != float(v):
            raise ValueError
    except (TypeError, ValueError):
        raise ResultFileError(f"{path}: format_version {attr_str(v)!r} is not a whole number") from None
    if version > FORMAT_VERSION:
        raise ResultFileError(f"{path}: format_version {version} is newer than jaxslosh {__version__} reads "
                              f"(up to {FORMAT_VERSION}); upgrade jaxslosh to read it")
    return fmt


def read_frames(f: h5py.File, names, axis: int = 0) -> dict:
    """{dataset: array} of the frame datasets `names` (absent ones skipped), cut to the frames every
    one of them holds along `axis` (a run stopped while writing a chunk may have grown some
    datasets and not yet the others: the frames all hold are the ones written)."""
    present = [k for k in names if k in f]
    if not present:
        return {}
    n = min(f[k].shape[axis] for k in present)
    cut = (slice(None),) * axis + (slice(0, n),)
    return {k: np.asarray(f[k][cut]) for k in present}


#: the datasets every result holds (solver/constraint came later: older files lack it)
REQUIRED = ("time", "vessel/position", "vessel/quaternion", "vessel/angular_velocity", "vessel/roll_pitch_yaw",
            "energy/kinetic", "energy/potential", "solver/iterations", "solver/residual")


def check_required(d: dict, probe_names, path: str) -> None:
    """A ResultFileError naming the first dataset a result needs that `d` lacks."""
    need = list(REQUIRED) + [f"probes/{p}/{q}" for p in probe_names for q in ("position", "displacement")]
    for k in need:
        if k not in d:
            raise ResultFileError(f"{path}: the dataset /{k} is missing")


def load_result(path: str) -> Result:
    """The result file at `path` (docs/reference/files.md). A file that is not one, cannot be read, lacks a
    dataset or has a newer format_version raises ResultFileError (a ValueError) with a one-line
    message naming the file and the fault."""
    with open_h5(path) as f:
        fmt = file_format(f, path)
        if fmt != FORMAT:
            what = ("a sweep file: jaxslosh.io.sweep.load_sweep reads it" if fmt == "jaxslosh.sweep"
                    else f"format {fmt!r}" if fmt else "no format attribute")
            raise ResultFileError(f"{path}: not a jaxslosh result file ({what})")
        a = f.attrs
        probes = list(f["probes"]) if "probes" in f else []
        tanks = {}
        for name in (f["tanks"] if "tanks" in f else []):
            for part in ("nodes", "elements"):
                if f"tanks/{name}/{part}" not in f:
                    raise ResultFileError(f"{path}: the dataset /tanks/{name}/{part} is missing")
            tanks[name] = (np.asarray(f[f"tanks/{name}/nodes"]), np.asarray(f[f"tanks/{name}/elements"]))
        lines = list(f["mooring"]) if "mooring" in f else []
        line_nodes = {n: f[f"mooring/{n}/nodes"].shape[1] for n in lines if f"mooring/{n}/nodes" in f}
        bodies = list(f["bodies"]) if "bodies" in f else []
        connections = list(f["connections"]) if "connections" in f else []
        d = read_frames(f, schema(probes, {name: 0 for name in tanks}, lines, line_nodes, bodies, connections,
                                  list(f["energy/mooring"]) if "energy/mooring" in f else []))
        check_required(d, probes, path)
        status = attr_str(a.get("status", "ok"))
        code = int(a["status_code"]) if "status_code" in a else None
        return result_from(d, probes, tanks, status=status, steps_done=int(a.get("steps_done", 0)),
                           scene_text=attr_str(a.get("scene", "")), status_code=code)


def truncated(r: Result, n: int) -> Result:
    """The first n frames of a result (concrete arrays cut in NumPy: eagerly each leaf compiled a program)."""
    cut = lambda x: x[:n] if _is_traced(x) or not isinstance(x, jax.Array) else on_device(np.asarray(x)[:n])  # noqa: E731
    return dataclasses.replace(
        r, time=cut(r.time), vessel=jax.tree_util.tree_map(cut, r.vessel),
        probes={k: jax.tree_util.tree_map(cut, p) for k, p in r.probes.items()},
        energy=jax.tree_util.tree_map(cut, r.energy), solver=jax.tree_util.tree_map(cut, r.solver),
        tanks={k: TankField(t.nodes, t.elements, cut(t.displacement)) for k, t in r.tanks.items()},
        mooring=None if r.mooring is None else {k: jax.tree_util.tree_map(cut, m) for k, m in r.mooring.items()},
        bodies=None if r.bodies is None else {k: jax.tree_util.tree_map(cut, m) for k, m in r.bodies.items()},
        connections=None if r.connections is None else {k: jax.tree_util.tree_map(cut, m) for k, m in r.connections.items()})
