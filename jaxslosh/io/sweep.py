"""The sweep file (`jaxslosh sweep`): the datasets of a result file (SPEC section 3) with a leading
run axis, the grid under /sweep/<key> (one value per run) and one status per run (attribute
`statuses`)."""
from __future__ import annotations

import h5py
import numpy as np

from .._version import __version__
from .result import result_frames


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
            f.create_dataset(k, data=v)
