"""Multibody hydrodynamic databases: the coupled radiation and diffraction of several bodies in one
file (docs/guide/bodies-and-connections.md, coupled hydrodynamics).

* **Capytaine**: a dataset of several bodies solved together (`Multibody`, or bodies joined) names
  its dofs `<body>__<Dof>` along `radiating_dof` and `influenced_dof` (e.g. "barge__Surge"). Each
  body's dofs rotate about that body's rotation centre, which must be its COG (Capytaine's
  `rigid_body_dofs(rotation_center=cog)`), and the wave phases are relative to the dataset's
  origin, which the scene takes as the vessel's COG at rest (horizontally): the file's axes are the
  scene's inertial axes, so each body's dofs are along them whatever its heading.
* **WAMIT** (NBODY > 1): the `.1` and `.3` hold 6 N dofs, body k's in rows 6 k + 1 ... 6 k + 6, in
  the order of the run's bodies, which the scene's `[vessel]` and `[[bodies]]` then follow by
  their file order (`bodies` below); each body about its own origin (its COG: XBODY), phases
  relative to the global origin.

Read into `Tables` over the 6 N dofs (body by body, ours: surge ... yaw, A[i, j] the force on dof
i per acceleration of dof j, X for our e^{+i w t}). Checked on reading: A(w) and B(w) symmetric
(Green's reciprocity: A_ij = A_ji) and B(w) positive semi-definite (radiating waves takes energy
away), each within `TOLERANCE` of the sizes involved (a coarse panel model's accuracy): where not,
one warning names the worst entries (the file is used as it is).
"""
from __future__ import annotations

import functools
import os
from typing import NamedTuple, Optional

import numpy as np

from .database import DOF_NAMES, DatabaseError, _merge_complex, _open_netcdf, _rows, read_wamit, tables_from_dataset
from .tables import Tables

#: relative to the diagonal's size (symmetry) or the largest eigenvalue (semi-definiteness): the
#: accuracy of a panel model's cross terms (a coarse mesh of two boxes: 1 to 3 %)
TOLERANCE = 0.05
SEP = "__"


class Multibody(NamedTuple):
    names: tuple            # the bodies, in the tables' order (6 dofs each)
    tables: Tables          # over 6 N dofs, about each body's COG, phases from the file's origin
    warnings: tuple         # the reading's checks that failed (one line each)


def dof_label(names, k: int) -> str:
    return f"{names[k // 6]}__{DOF_NAMES[k % 6]}"


def netcdf_bodies(path: str) -> Optional[tuple]:
    """The bodies a Capytaine dataset names in its dofs (`<body>__<Dof>`), in order; None for a
    single body's dataset (plain dof names)."""
    ds = _open_netcdf(path)
    labels = [str(x) for x in ds["radiating_dof"].values] if "radiating_dof" in ds.coords else []
    if not labels or not all(SEP in x for x in labels):
        return None
    return tuple(dict.fromkeys(x.split(SEP)[0] for x in labels))


def netcdf_centres(path: str) -> dict:
    """{body: (x, y, z)} of a multibody Capytaine dataset: each body's `rotation_center` (where its
    dofs rotate: its COG), else its `center_of_mass`, in the dataset's coordinates (Capytaine stores
    them along the dimensions (body, space_coordinate)); {} where the file holds neither."""
    ds = _open_netcdf(path)
    names = netcdf_bodies(path) or ()
    for key in ("rotation_center", "center_of_mass"):
        if key not in ds.variables or ds[key].ndim != 2 or "body" not in ds[key].dims:
            continue
        da = ds[key].transpose("body", ...)
        labels = [str(x) for x in ds["body"].values] if "body" in ds.coords else list(names)
        if len(labels) != da.shape[0] or da.shape[1] != 3:
            continue
        return {n: tuple(float(c) for c in row) for n, row in zip(labels, np.asarray(da.values, dtype=float))}
    return {}


def read_multibody_netcdf(path: str, names) -> Multibody:
    """The coupled tables of `names` (every body of the dataset, in the scene's order)."""
    ds = _merge_complex(_open_netcdf(path))
    have = netcdf_bodies(path) or ()
    if sorted(have) != sorted(names):
        raise DatabaseError(f"{path}: the dataset's bodies {list(have)} are not the scene's {list(names)}")
    t = tables_from_dataset(ds, dofs=[f"{b}{SEP}{d}" for b in names for d in DOF_NAMES])
    return Multibody(tuple(names), t, tuple(check_coupled(t, names, path)))


def wamit_bodies(path: str) -> int:
    """How many bodies a WAMIT `.1` holds (its largest dof index / 6)."""
    rows = _rows(path, (4, 5), ".1 (PER I J A B)")
    top = max((max(int(r[1]), int(r[2])) for _, r in rows), default=0)
    return max(1, (top + 5) // 6)


def read_multibody_wamit(path: str, names, rho: float, g: float, length: float = 1.0) -> Multibody:
    """WAMIT's NBODY `.1` (with its `.3`) of 6 N dofs, body k the k-th of `names`."""
    if wamit_bodies(path) != len(names):
        raise DatabaseError(f"{path}: holds {wamit_bodies(path)} bodies (6 dofs each), the scene {len(names)}")
    t = read_wamit(path, rho, g, length, dofs=6 * len(names)).tables
    return Multibody(tuple(names), t, tuple(check_coupled(t, names, path)))


def check_coupled(t: Tables, names, path: str) -> list:
    """One line for A or B not symmetric, one for B not positive semi-definite, beyond TOLERANCE,
    naming the worst entry and frequency; nothing where the file passes. Entries are compared in
    the units of the diagonal: X_ij / sqrt(max_w |X_ii| max_w |X_jj|) (translations and rotations
    alike; a damping that vanishes at some frequencies measured by its size over the table)."""
    out = []
    for what, M in (("added mass", t.added_mass), ("radiation damping", t.damping)):
        d = np.sqrt(np.abs(np.einsum("nii->ni", M)).max(axis=0))
        ref = np.maximum(d[:, None] * d[None, :], 1e-300)[None]
        asym = np.abs(M - M.transpose(0, 2, 1)) / ref
        m, i, j = np.unravel_index(np.argmax(asym), asym.shape)
        if asym[m, i, j] > TOLERANCE:
            bad = int((asym > TOLERANCE).sum() // 2)
            out.append(f"{path}: the {what} is not symmetric within {100 * TOLERANCE:g} % of its diagonal ({bad} "
                       f"entries): worst {dof_label(names, i)} / {dof_label(names, j)} at {t.omega[m]:.4g} rad/s, "
                       f"{M[m, i, j]:.6g} against {M[m, j, i]:.6g} (reciprocity: a coarse mesh or a file cut); used "
                       f"as it is (its symmetric part in the radiation memory)")
    d = np.sqrt(np.abs(np.einsum("nii->ni", t.damping)).max(axis=0))
    Bn = t.damping / np.maximum(d[:, None] * d[None, :], 1e-300)[None]
    lam, vec = np.linalg.eigh(0.5 * (Bn + Bn.transpose(0, 2, 1)))
    rel = lam[:, 0] / np.maximum(np.abs(lam).max(), 1e-300)
    m = int(np.argmin(rel))
    if rel[m] < -TOLERANCE:
        k = int(np.argmax(np.abs(vec[m, :, 0])))
        out.append(f"{path}: the radiation damping is not positive semi-definite at {t.omega[m]:.4g} rad/s: an "
                   f"eigenvalue {100 * rel[m]:.3g} % of the largest, mostly {dof_label(names, k)} (the bodies would "
                   f"gain energy radiating waves: irregular frequencies, or a gap resonance the mesh does not "
                   f"resolve)")
    return out


def read_multibody(path: str, names, rho: float, g: float, length: float = 1.0) -> Multibody:
    """A multibody file's coupled tables (cached per file and its modification time: the loader,
    each build, RAO and mode iteration ask for them)."""
    return _read_cached(path, os.path.getmtime(path), tuple(names), rho, g, length)


@functools.lru_cache(maxsize=8)
def _read_cached(path, mtime, names, rho, g, length) -> Multibody:
    if os.path.splitext(path)[1].lower() == ".1":
        return read_multibody_wamit(path, names, rho, g, length)
    return read_multibody_netcdf(path, names)


def file_bodies(path: str) -> Optional[tuple]:
    """The bodies of a NetCDF multibody dataset (names), the count of a WAMIT NBODY `.1`'s (an int),
    or None for a single body's file."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".1":
        n = wamit_bodies(path)
        return n if n > 1 else None
    return netcdf_bodies(path)
