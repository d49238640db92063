"""The RAO file (docs/reference/files.md): complex responses per unit wave amplitude over frequency and
heading, written by `jaxslosh rao`.

    /                  attrs: format = "jaxslosh.rao", format_version = 1, scene, jaxslosh_version
    /frequency (f,) rad/s; /heading (h,) rad
    /rao/vessel        (f, h, 6) complex: surge, sway, heave (m/m), roll, pitch, yaw (rad/m)
    /rao/probes/<name> (f, h, 3) complex (m/m)
    /rao/bodies/<name> (f, h, 6) complex: each of the [[bodies]], as /rao/vessel (its translations
                       along the inertial axes, its phase for a wave eta = cos(w t) at the vessel's
                       COG at rest)

Complex values are HDF5 compound (r, i) pairs, which h5py reads back as numpy complex128. The phase
is that of x = Re(X e^{i w t}) for a wave eta = cos(w t) at the COG's rest position.
"""
from __future__ import annotations

from typing import NamedTuple

import h5py
import numpy as np

from .._version import __version__
from .output import OutputLock
from .result import ResultFileError, attr_str, file_format, open_h5

RAO_FORMAT = "jaxslosh.rao"


class RaoData(NamedTuple):
    frequency: np.ndarray
    heading: np.ndarray
    vessel: np.ndarray
    probes: dict
    scene_text: str = ""
    bodies: dict = {}


def write_rao(path: str, frequency, heading, vessel, probes: dict, scene_text: str = "", bodies=None) -> None:
    lock = OutputLock(path)
    try:
        with h5py.File(path, "w") as f:
            f.attrs["format"] = RAO_FORMAT
            f.attrs["format_version"] = 1
            f.attrs["scene"] = scene_text
            f.attrs["jaxslosh_version"] = __version__
            f.create_dataset("frequency", data=np.asarray(frequency, dtype=float)).attrs["units"] = "rad/s"
            f.create_dataset("heading", data=np.asarray(heading, dtype=float)).attrs["units"] = "rad"
            ds = f.create_dataset("rao/vessel", data=np.asarray(vessel, dtype=complex))
            # per unit wave amplitude: surge, sway, heave m/m (a pure number), roll, pitch, yaw rad/m
            ds.attrs["units"] = "m/m, m/m, m/m, rad/m, rad/m, rad/m"     # along the last axis
            ds.attrs["description"] = "complex response per unit wave amplitude: surge, sway, heave (m/m), " \
                                      "roll, pitch, yaw (rad/m)"
            g = f.create_group("rao/probes")
            for name, v in probes.items():
                g.create_dataset(name, data=np.asarray(v, dtype=complex)).attrs["units"] = "m/m"
            for name, v in (bodies or {}).items():
                b = f.create_dataset(f"rao/bodies/{name}", data=np.asarray(v, dtype=complex))
                b.attrs["units"], b.attrs["description"] = ds.attrs["units"], ds.attrs["description"]
    finally:
        lock.release()


def load_rao(path: str) -> RaoData:
    """An RAO file read back; a file that is not one raises ResultFileError naming it."""
    with open_h5(path) as f:
        fmt = file_format(f, path)
        if fmt != RAO_FORMAT:
            raise ResultFileError(f"{path}: not a jaxslosh RAO file (format {fmt!r})")
        for k in ("frequency", "heading", "rao/vessel"):
            if k not in f:
                raise ResultFileError(f"{path}: the dataset /{k} is missing")
        probes = {k: f["rao/probes"][k][()] for k in f["rao/probes"]} if "rao/probes" in f else {}
        bodies = {k: f["rao/bodies"][k][()] for k in f["rao/bodies"]} if "rao/bodies" in f else {}
        return RaoData(f["frequency"][()], f["heading"][()], f["rao/vessel"][()], probes,
                       attr_str(f.attrs.get("scene", "")), bodies)
