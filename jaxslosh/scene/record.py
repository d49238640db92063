"""`[vessel.forced]` read and checked: the harmonic and spin-up profiles' keys, and a motion record
(`file = "motion.csv"`, docs/guide/tank-tests.md).

The file is comma-separated text: a header row with `t` and any of surge, sway, heave (m), roll,
pitch, yaw (rad), then one row per sample. Blank lines and lines starting with `#` are skipped.
The times must increase strictly; every value must be a finite number; at least `MIN_ROWS` rows
(the interpolant, a natural cubic spline, needs four points to carry any curvature). Every error
names the file's line, and the column where one is at fault. NumPy only; no JAX.
"""
from __future__ import annotations

import csv
import functools
import math
import os

from .fields import non_negative, one_of, positive, read
from .types import DOFS, Forced, SceneError, Simulation, Vessel

MIN_ROWS = 4


def read_record(path: str, where: str, shown: str) -> tuple[tuple[float, ...], tuple[tuple[str, tuple], ...]]:
    """(times, ((dof, values), ...)) of a record, the dofs in the file's column order; SceneError at
    `where` naming the line and column at fault (`shown`: the file's name as the scene writes it).
    Read once per version of the file (a sweep parses its scene again for every run)."""
    try:
        st = os.stat(path)
    except OSError:
        raise SceneError(where, f"no such file: {path}") from None
    return _read_record(path, where, shown, st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=8)
def _read_record(path, where, shown, mtime_ns, size):
    try:
        # utf-8-sig: a spreadsheet's "CSV UTF-8" starts with a byte-order mark, which would otherwise
        # stick to the first header name; newline="" lets the csv reader take \n, \r\n or \r line ends
        with open(path, newline="", encoding="utf-8-sig") as fh:
            lines = [(n, row) for n, row in enumerate(csv.reader(fh), start=1)
                     if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    except FileNotFoundError:
        raise SceneError(where, f"no such file: {path}") from None
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise SceneError(where, f"{shown}: cannot be read as comma-separated text ({e})") from None
    if not lines:
        raise SceneError(where, f"{shown}: is empty; it needs a header row (t and any of {', '.join(DOFS)})")
    head_line, head = lines[0]
    names = [c.strip().lower() for c in head]
    for k, name in enumerate(names):
        if name != "t" and name not in DOFS:
            raise SceneError(where, f"{shown}: line {head_line}, column {k + 1} {head[k].strip()!r}: not a record column "
                                    f"(t and any of {', '.join(DOFS)})")
        if names.index(name) != k:
            raise SceneError(where, f"{shown}: line {head_line}: column {name!r} is given twice")
    if "t" not in names:
        raise SceneError(where, f"{shown}: line {head_line}: no column t (the time, s) in the header {head}")
    if len(names) == 1:
        raise SceneError(where, f"{shown}: line {head_line}: no motion column besides t (any of {', '.join(DOFS)})")
    values = []
    for n, row in lines[1:]:
        if len(row) != len(names):
            raise SceneError(where, f"{shown}: line {n}: {len(row)} values where the header has {len(names)} columns")
        out = []
        for name, cell in zip(names, row):
            try:
                x = float(cell)
            except ValueError:
                raise SceneError(where, f"{shown}: line {n}, column {name}: {cell.strip()!r} is not a number") from None
            if not math.isfinite(x):
                raise SceneError(where, f"{shown}: line {n}, column {name}: {cell.strip()} (every value must be a "
                                        f"finite number)")
            out.append(x)
        values.append((n, out))
    if len(values) < MIN_ROWS:
        raise SceneError(where, f"{shown}: {len(values)} rows of samples; a record needs at least {MIN_ROWS} "
                                f"(its interpolant has continuous acceleration)")
    it = names.index("t")
    for (n0, a), (n, b) in zip(values[:-1], values[1:]):
        if not b[it] > a[it]:
            raise SceneError(where, f"{shown}: line {n}, column t: {b[it]:g} s does not follow {a[it]:g} s on line {n0}: "
                                    f"the times must increase")
    times = tuple(v[it] for _, v in values)
    cols = tuple((name, tuple(v[k] for _, v in values)) for k, name in enumerate(names) if name != "t")
    return times, cols


#: the keys of each [vessel.forced] profile (dof for the two of one dof; a record's columns name its dofs)
FORCED_PROFILES = {"harmonic": ("dof", "amplitude", "frequency", "ramp", "phase"),
                   "spin-up": ("dof", "rate", "duration"), "record": ("file",)}
FORCED_REQUIRED = {"harmonic": ("dof", "amplitude", "frequency"), "spin-up": ("dof", "rate", "duration"),
                   "record": ("file",)}


def read_forced(table, base_dir: str) -> Forced:
    """`[vessel.forced]`: a harmonic or spin-up profile of one dof, or a record (`file`) of any dofs."""
    where = "vessel.forced"
    f = read(table, where, {
        "dof": ("str", one_of(DOFS)), "profile": ("str", one_of(tuple(FORCED_PROFILES))),
        "amplitude": ("float", None), "frequency": ("float", positive), "ramp": ("float", non_negative),
        "rate": ("float", None), "duration": ("float", positive), "phase": ("float", None), "file": ("str", None),
    })
    profile = f.get("profile", "record" if "file" in f else "harmonic")
    f["profile"] = profile
    for k in FORCED_REQUIRED[profile]:
        if k not in f:
            raise SceneError(f"{where}.{k}", "a required key is missing" if k == "dof"
                             else f"is required for the {profile} profile")
    for k in f:
        if k != "profile" and k not in FORCED_PROFILES[profile]:
            takes = ", ".join(FORCED_PROFILES[profile])
            why = " (the record's columns name the dofs it prescribes)" if profile == "record" and k == "dof" else ""
            raise SceneError(f"{where}.{k}", f"does not belong to the {profile} profile (it takes {takes}){why}")
    if profile == "spin-up" and f["dof"] not in ("roll", "pitch", "yaw"):
        raise SceneError(f"{where}.dof", f"the spin-up profile turns a rotation (roll, pitch or yaw), not {f['dof']!r}")
    if profile == "record":
        shown = f["file"]
        f["file"] = shown if os.path.isabs(shown) else os.path.join(base_dir, shown)
        f["times"], f["columns"] = read_record(f["file"], f"{where}.file", shown)
    return Forced(**f)


def forced_span(vessel: Vessel, sim: Simulation) -> None:
    """A record must cover the run, from t = 0 to the duration: the motion is not guessed outside it."""
    f = vessel.forced
    if f is None or f.profile != "record":
        return
    t0, t1 = f.times[0], f.times[-1]
    name = os.path.basename(f.file)
    if t0 > 0.0:
        raise SceneError("vessel.forced.file", f"{name}: the record starts at t = {t0:g} s; it must cover the run "
                                               f"from t = 0")
    if sim.n_steps * sim.dt > t1 * (1 + 1e-12) + 1e-12:
        raise SceneError("vessel.forced.file", f"{name}: the record ends at t = {t1:g} s, before the run's end "
                                               f"t = {sim.n_steps * sim.dt:g} s (simulation.duration)")
