"""The sweep file (`jaxslosh sweep`): the datasets of a result file (docs/reference/files.md) with a leading
run axis, the grid under /sweep/<key> (one value per run) and one status per run (attribute
`statuses`)."""
from __future__ import annotations

from typing import NamedTuple

import h5py
import numpy as np

from .._version import __version__
from .result import (Result, ResultFileError, attr_str, check_required, label, open_format, read_frames,
                     result_from, result_frames, schema)


SWEEP_FORMAT = "jaxslosh.sweep"


def write_sweep(path, scene, params, result, statuses):
    with h5py.File(path, "w") as f:
        f.attrs["format"] = SWEEP_FORMAT
        f.attrs["format_version"] = 1
        f.attrs["scene"] = scene.text
        f.attrs["jaxslosh_version"] = __version__
        f.attrs["statuses"] = np.array(statuses, dtype=h5py.string_dtype())
        f.attrs["status"] = "ok" if all(s == "ok" for s in statuses) else "some runs failed"
        f.attrs["runs"] = len(statuses)
        for k, v in params.items():
            f.create_dataset(f"sweep/{k}", data=np.asarray(v))
        for k, v in result_frames(result).items():
            label(f.create_dataset(k, data=v), k)


class Sweep(NamedTuple):
    """A sweep file read back: the grid {key: values, one per run}, the runs' results as one Result
    with a leading run axis, each run's status, and the scene's TOML text."""
    params: dict
    result: Result
    statuses: list
    scene_text: str


def load_sweep(path) -> Sweep:
    """The sweep file at `path`; a file that is not one or cannot be read raises ResultFileError."""
    with open_format(path, SWEEP_FORMAT, "sweep") as f:
        probes = list(f["probes"]) if "probes" in f else []
        bodies, links = (list(f[g]) if g in f else [] for g in ("bodies", "connections"))
        params = read_frames(f, [f"sweep/{k}" for k in (f["sweep"] if "sweep" in f else [])])
        d = read_frames(f, schema(probes, bodies=bodies, connections=links), axis=1)
        check_required(d, probes, path)
        runs = d["time"].shape[0]
        if not params or any(len(v) != runs for v in params.values()):
            raise ResultFileError(f"{path}: the grid /sweep/<key> is missing or does not hold one value per run")
        statuses = [attr_str(x) for x in f.attrs.get("statuses", ["ok"] * runs)]
        scene = attr_str(f.attrs.get("scene", ""))
    r = result_from(d, probes, status="ok" if all(x == "ok" for x in statuses) else "some runs failed",
                    scene_text=scene)
    return Sweep({k[len("sweep/"):]: v for k, v in params.items()}, r, statuses, scene)
