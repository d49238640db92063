"""Hydrodynamic databases in and out: Capytaine's NetCDF datasets and WAMIT's `.1`, `.3`, `.hst`
files, read into the same `Tables` a scene's `[vessel.hydrodynamics]` holds (about the COG, our
phase convention), and written from them.

Conventions, and what each reader undoes:

* **Ours** (tables.py, spectra.py): rows and columns surge, sway, heave, roll, pitch, yaw about the
  COG, body axes x forward, y to port, z up; A[i, j] the force on dof i per unit acceleration of
  dof j; an excitation X per unit wave amplitude at the COG's rest position with
  F = Re(X a e^{i w t}) for eta = Re(a e^{i w t}); headings the direction the waves travel to, from
  +x towards +y.
* **Capytaine** (its `assemble_dataset`, saved by `capytaine.io.xarray.save_dataset_as_netcdf`, or
  `export_dataset(..., format="netcdf")`: complex arrays split along a `complex` dimension
  ['re', 'im']): dimensional, `added_mass(omega, influenced_dof, radiating_dof)`, time factor
  e^{-i w t} (our X is the complex conjugate of its `excitation_force`), rotations about the dataset's
  `rotation_center`, wave phases relative to its coordinates' origin; `wave_direction` as our
  heading; an `omega = inf` row is A_inf (its forces NaN).
* **WAMIT** (manual, "Definitions of output quantities"): non-dimensional with the length ULEN,
  A_ij / (rho L^k), B_ij / (rho L^k w), k = 3, 4, 5 for translation-translation, mixed and
  rotation-rotation; X_i / (rho g A L^m), m = 2 for forces, 3 for moments; C_ij / (rho g L^k),
  k = 2 for (3, 3), 3 for (3, 4), (3, 5), 4 for the others. Time factor e^{+i w t}, as ours: X is
  taken as written (modulus and phase in degrees; the real and imaginary columns are used). `.1`
  lines: PER I J A [B] with PER the period, I the force's dof and J the motion's, PER = -1 the zero
  frequency (skipped) and PER = 0 the infinite one (A_inf); `.3` lines: PER BETA I |X| phase Re Im,
  BETA in degrees; `.hst`: I J C. Moments and rotations about WAMIT's origin (XBODY = 0: the body
  and global systems coincide), phases relative to the same origin.

A file whose origin (WAMIT) or rotation centre (Capytaine) is not the COG is moved to it: the scene
gives the COG's position in the file's coordinates (`cog`). Rigid motions about a point P a vector r
from the COG are xi_P = T xi_G with T = [[I, -[r]x], [0, I]], forces F_G = T^T F_P, so
A_G = T^T A_P T (B likewise), X_G = T^T X_P e^{-i k (r0_x cos beta + r0_y sin beta)} with r0 the
phase origin from the COG. The hydrostatic stiffness (.hst, Capytaine's `hydrostatic_stiffness`) is
returned about the file's point as written: the scene's [vessel.hydrostatics] stays what the model
uses, and the loader compares the two where the points agree.
"""
from __future__ import annotations

import os
from typing import NamedTuple, Optional

import numpy as np

from .spectra import wavenumber
from .tables import Tables

DOF_NAMES = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
NETCDF_MISSING = "reading a NetCDF dataset needs xarray and h5netcdf: pip install 'jaxslosh[netcdf]'"


class DatabaseError(ValueError):
    """A hydrodynamic database that cannot be read: the message names the file and the fault."""


class Database(NamedTuple):
    tables: Tables                    # about the COG, our conventions
    stiffness: Optional[np.ndarray]   # (6, 6) hydrostatic stiffness as written (about the file's point), or None
    rho: Optional[float]              # the water density the file's dimensional values used (None: WAMIT)
    g: Optional[float]
    point_is_cog: bool                # the file's rotations were about the COG already


def _k_exponent(i, j):
    return 3 + (i >= 3) + (j >= 3)


def _shift_matrix(r):
    r = np.asarray(r, dtype=float)
    S = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    T = np.eye(6)
    T[:3, 3:] = -S
    return T


def move_to_cog(tables: Tables, r_point, r_phase, g: float, depth=None) -> Tables:
    """Tables about a point P (vector `r_point` from the COG) with wave phases relative to a point
    `r_phase` from the COG, moved to the COG (see the module's docstring)."""
    T = _shift_matrix(r_point)
    tr = lambda a: None if a is None else np.einsum("ki,...kl,lj->...ij", T, a, T)  # noqa: E731
    X = tables.excitation
    if X is not None:
        k = wavenumber(tables.omega, g, depth)                          # (n,)
        heads = np.asarray(tables.headings, dtype=float)
        kr = k[:, None] * (r_phase[0] * np.cos(heads)[None, :] + r_phase[1] * np.sin(heads)[None, :])
        X = np.einsum("ki,nhk->nhi", T, X) * np.exp(-1j * kr)[:, :, None]
    return Tables(tables.omega, tr(tables.added_mass), tr(tables.damping), tr(tables.added_mass_infinite),
                  tables.headings, X)


# ------------------------------------------------------------------------------------------------
# Capytaine


def tables_from_dataset(ds, prefix: str = "", dofs=None) -> Tables:
    """Our tables from a Capytaine dataset (complex values merged), about its rotation centre and
    phase origin: finite positive frequencies ascending, A_inf from an omega = inf row. `prefix`:
    one body's block of a multibody dataset (dofs "<body>__Surge", ...); `dofs`: these dofs in this
    order (several bodies' coupled tables, hydro/multibody.py)."""
    names = [str(x) for x in ds["influenced_dof"].values]
    order = list(dofs) if dofs is not None else [prefix + d for d in DOF_NAMES]
    if not set(order) <= set(names) or (not prefix and dofs is None and len(names) != 6):
        raise DatabaseError(f"the dataset's dofs {names} are not the six rigid-body dofs {order}")
    if "omega" not in ds.coords:
        raise DatabaseError("the dataset has no omega coordinate")
    w_all = np.asarray(ds["omega"].values, dtype=float)
    if "omega" not in ds["added_mass"].dims:      # one frequency: a scalar coordinate
        ds = ds.expand_dims("omega")
        w_all = np.atleast_1d(w_all)
    sel = dict(influenced_dof=order, radiating_dof=order)
    A_all = ds["added_mass"].sel(**sel).transpose("omega", "influenced_dof", "radiating_dof").values
    B_all = ds["radiation_damping"].sel(**sel).transpose("omega", "influenced_dof", "radiating_dof").values
    fin = np.isfinite(w_all) & (w_all > 0)
    idx = np.flatnonzero(fin)[np.argsort(w_all[fin])]
    w = w_all[idx]
    Ainf = A_all[np.flatnonzero(np.isinf(w_all))[0]] if np.isinf(w_all).any() else None
    X = heads = None
    if "excitation_force" in ds and "wave_direction" in ds["excitation_force"].dims:
        F = ds["excitation_force"].sel(influenced_dof=order).transpose("omega", "wave_direction",
                                                                        "influenced_dof").values[idx]
        heads = np.asarray(ds["wave_direction"].values, dtype=float)
        hs = np.argsort(heads)
        X, heads = np.conj(F[:, hs]), heads[hs]        # Capytaine's e^{-i w t} -> ours
    return Tables(w, A_all[idx], B_all[idx], Ainf, heads, X)


def _open_netcdf(path):
    try:
        import xarray as xr
    except ImportError:
        raise DatabaseError(NETCDF_MISSING) from None
    last = None
    for engine in _engines():
        try:
            with xr.open_dataset(path, engine=engine) as ds:
                return ds.load()
        except (OSError, ValueError, TypeError) as e:
            last = e
    raise DatabaseError(f"not a NetCDF file this installation reads ({' '.join(str(last).split())[:120]})")


def _merge_complex(ds):
    """Capytaine's `merge_complex_values`, without Capytaine: arrays with a `complex` dimension
    ['re', 'im'] become complex."""
    if "complex" not in ds.dims:
        return ds
    ds = ds.copy()
    for name in list(ds.data_vars):
        da = ds[name]
        if "complex" in da.dims:
            ds[name] = da.sel(complex="re", drop=True) + 1j * da.sel(complex="im", drop=True)
    return ds.drop_vars("complex", errors="ignore")


def read_netcdf(path: str, cog=None, g: float = 9.81, body=None) -> Database:
    """A Capytaine NetCDF dataset. `cog`: the COG in the dataset's coordinates (default: its
    `center_of_mass` where it has one, else its rotation centre, else the origin). A multibody
    dataset (dofs "<body>__Surge", ...) gives the block of `body` as it is (each body's dofs about
    its COG, phases from the file's origin: hydro/multibody.py)."""
    ds = _merge_complex(_open_netcdf(path))
    labels = [str(x) for x in ds["influenced_dof"].values] if "influenced_dof" in ds.coords else []
    if labels and all("__" in x for x in labels):
        have = list(dict.fromkeys(x.split("__")[0] for x in labels))
        if body not in have:
            raise DatabaseError(f"a multibody dataset of the bodies {have}, none of them named {body!r}")
        t = tables_from_dataset(ds, body + "__")
        rho = float(ds["rho"].values) if "rho" in ds else None
        return Database(t, None, rho, float(ds["g"].values) if "g" in ds else None, True)
    try:
        t = tables_from_dataset(ds)
    except KeyError as e:
        raise DatabaseError(f"not a Capytaine hydrodynamic dataset (no {e})") from None
    rc = np.asarray(ds["rotation_center"].values, dtype=float) if "rotation_center" in ds else np.zeros(3)
    if cog is None:
        cog = np.asarray(ds["center_of_mass"].values, dtype=float) if "center_of_mass" in ds else rc
    cog = np.asarray(cog, dtype=float)
    depth = float(ds["water_depth"].values) if "water_depth" in ds else np.inf
    g_file = float(ds["g"].values) if "g" in ds else None
    t = move_to_cog(t, rc - cog, -cog, g_file or g, None if not np.isfinite(depth) else depth)
    C = None
    if "hydrostatic_stiffness" in ds:
        C = ds["hydrostatic_stiffness"].sel(influenced_dof=list(DOF_NAMES), radiating_dof=list(DOF_NAMES)).values
    rho = float(ds["rho"].values) if "rho" in ds else None
    return Database(t, C, rho, g_file, bool(np.allclose(rc, cog)))


def write_netcdf(path: str, tables: Tables, rho: float, g: float, stiffness=None, depth=None) -> None:
    """Our tables as a Capytaine-shaped NetCDF dataset (what `capytaine.io.xarray.save_dataset_as_netcdf`
    writes: complex values split along `complex`, A_inf as an omega = inf row, the excitation in
    Capytaine's e^{-i w t} convention), about the COG (rotation centre and phase origin at 0)."""
    import xarray as xr
    w = np.asarray(tables.omega, dtype=float)
    A, B = tables.added_mass, tables.damping
    if tables.added_mass_infinite is not None:
        w = np.append(w, np.inf)
        A = np.concatenate([A, tables.added_mass_infinite[None]])
        B = np.concatenate([B, np.zeros((1, 6, 6))])
    dofs = list(DOF_NAMES)
    with np.errstate(divide="ignore"):
        period = np.where(np.isinf(w), 0.0, 2 * np.pi / w)
    coords = {"omega": w, "period": ("omega", period), "influenced_dof": dofs, "radiating_dof": dofs,
              "complex": ["re", "im"], "rho": rho, "g": g, "forward_speed": 0.0,
              "water_depth": np.inf if depth is None else float(depth),
              "rotation_center": ("space_coordinate", np.zeros(3)), "center_of_mass": ("space_coordinate", np.zeros(3)),
              "space_coordinate": ["x", "y", "z"]}
    data = {"added_mass": (("omega", "influenced_dof", "radiating_dof"), A),
            "radiation_damping": (("omega", "influenced_dof", "radiating_dof"), B)}
    if tables.excitation is not None:
        F = np.conj(tables.excitation)
        if tables.added_mass_infinite is not None:
            F = np.concatenate([F, np.full((1,) + F.shape[1:], np.nan + 0j)])
        coords["wave_direction"] = np.asarray(tables.headings, dtype=float)
        data["excitation_force"] = (("complex", "omega", "wave_direction", "influenced_dof"),
                                    np.stack([F.real, F.imag]))
    if stiffness is not None:
        data["hydrostatic_stiffness"] = (("influenced_dof", "radiating_dof"), np.asarray(stiffness, dtype=float))
    ds = xr.Dataset(data, coords=coords, attrs={"source": "jaxslosh"})
    save_netcdf(ds, path)


def _engines():
    out = []
    for mod, engine in (("h5netcdf", "h5netcdf"), ("netCDF4", "netcdf4"), ("scipy", "scipy")):
        try:
            __import__(mod)
            out.append(engine)
        except ImportError:
            pass
    return out


def save_netcdf(ds, path: str) -> None:
    """A dataset with complex values already split (Capytaine's layout) to a NetCDF file, with the
    first NetCDF engine installed (h5netcdf, netCDF4, else SciPy's NetCDF 3)."""
    engines = _engines()
    if not engines:
        raise DatabaseError(NETCDF_MISSING)
    ds.to_netcdf(path, engine=engines[0])


# ------------------------------------------------------------------------------------------------
# WAMIT


def _rows(path, cols, what):
    """[(line number, numbers)] of a WAMIT file: every non-blank line holds `cols` numbers (a pair
    (min, max) where the count may vary), finite. A line that does not is a DatabaseError naming
    the file and the line: a file cut in the middle of a line, or not a WAMIT file."""
    lo, hi = (cols, cols) if isinstance(cols, int) else cols
    out = []
    try:
        with open(path) as f:
            for n, line in enumerate(f, start=1):
                words = line.replace("D", "E").replace("d", "e").split()
                if not words:
                    continue
                try:
                    x = [float(w) for w in words]
                except ValueError:
                    raise DatabaseError(f"{path}, line {n}: not a WAMIT {what} line ({line.strip()[:60]!r})") from None
                if not lo <= len(x) <= hi:
                    want = f"{lo}" if lo == hi else f"{lo} or {hi}"
                    raise DatabaseError(f"{path}, line {n}: {len(x)} numbers where a WAMIT {what} line has {want} "
                                        f"(the file is cut, or not a WAMIT file)")
                if not all(np.isfinite(x)):
                    raise DatabaseError(f"{path}, line {n}: a value is not finite ({line.strip()[:60]!r})")
                out.append((n, x))
    except OSError as e:
        raise DatabaseError(f"{path}: cannot be read ({e.strerror})") from None
    return out


def _blocks(path, rows, key, entry, names):
    """The rows of a WAMIT file grouped into blocks of one period (`key(row)`: the block's key,
    None for rows outside the check), in file order. Refused, naming the file and the line: a
    block's entry (`entry(row)`) given twice, a block that lacks entries the others have (a file
    cut in the middle of a block), a period given in two separate places, finite periods that are
    not monotone."""
    blocks: list = []            # [(key, first line, {entry: row})]
    for n, r in rows:
        k = key(r)
        if not blocks or blocks[-1][0] != k:
            if any(b[0] == k for b in blocks):
                raise DatabaseError(f"{path}, line {n}: period {k[0]:g} s appears again after other periods: the "
                                    f"lines of one period belong together")
            blocks.append((k, n, {}))
        e = entry(r)
        if e in blocks[-1][2]:
            raise DatabaseError(f"{path}, line {n}: {_show_entry(e)} is given twice for period {k[0]:g} s")
        blocks[-1][2][e] = r
    union = set().union(*(b[2] for b in blocks)) if blocks else set()
    for k, n, got in blocks:
        missing = sorted(union - set(got))
        if missing:
            shown = ", ".join(_show_entry(e) for e in missing[:4]) + (", ..." if len(missing) > 4 else "")
            raise DatabaseError(f"{path}, line {n}: the block of period {k[0]:g} s from this line lacks "
                                f"{len(missing)} of the {len(union)} {names} the other periods have ({shown}): the "
                                f"file is cut or incomplete")
    per = [k[0] for k, _, _ in blocks if k[0] > 0]
    lines = [n for k, n, _ in blocks if k[0] > 0]
    if len(per) > 2:
        up = per[1] > per[0]
        for a, b, n in zip(per[1:], per[2:], lines[2:]):
            if (b > a) != up:
                raise DatabaseError(f"{path}, line {n}: period {b:g} s after {a:g} s: the periods must be monotone "
                                    f"({'ascending' if up else 'descending'} until this line)")
    return blocks


def _show_entry(e):
    return "(" + ", ".join(f"{x:g}" for x in e) + ")"


def read_wamit(path: str, rho: float, g: float, length: float = 1.0, cog=(0.0, 0.0, 0.0), depth=None,
               dofs: int = 6) -> Database:
    """WAMIT's `.1` at `path` with the `.3` and `.hst` of the same stem where they exist, made
    dimensional with `rho`, `g` and the length ULEN, moved from WAMIT's origin to the COG at `cog`
    (its position in WAMIT's coordinates). A file cut in the middle of a block, a block missing
    (I, J) pairs the others have, or periods out of order is refused (DatabaseError, with the line).
    `dofs`: 6 (the first body's), or 6 N for the N bodies of an NBODY run (each about its own
    origin, not moved: hydro/multibody.py)."""
    stem = os.path.splitext(path)[0]
    rows = _rows(path, (4, 5), ".1 (PER I J A B)")
    if not rows:
        raise DatabaseError(f"{path}: no coefficients (lines PER I J A B)")
    for n, r in rows:
        if r[0] > 0 and len(r) < 5:
            raise DatabaseError(f"{path}, line {n}: 4 numbers where a finite period's line has 5 (PER I J A B): "
                                f"the file is cut, or not a WAMIT .1 file")
    _blocks(path, rows, lambda r: (r[0],), lambda r: (int(r[1]), int(r[2])), "(I, J) pairs")
    per = np.array([r[0] for _, r in rows])
    fin = per > 0
    periods = np.unique(per[fin])
    if periods.size == 0:
        raise DatabaseError(f"{path}: no finite period (lines PER I J A B with PER > 0)")
    w = np.sort(2 * np.pi / periods)
    n = w.size
    A, B = np.zeros((n, dofs, dofs)), np.zeros((n, dofs, dofs))
    Ainf = None
    for _, r in rows:
        p, i, j = r[0], int(r[1]) - 1, int(r[2]) - 1
        if not (0 <= i < dofs and 0 <= j < dofs):
            continue                                   # generalized modes (or other bodies): not ours
        k = _k_exponent(i % 6, j % 6)
        if p == 0:                                     # zero period: infinite frequency
            Ainf = np.zeros((dofs, dofs)) if Ainf is None else Ainf
            Ainf[i, j] = r[3] * rho * length ** k
        elif p > 0:
            m = int(np.argmin(np.abs(w - 2 * np.pi / p)))
            A[m, i, j] = r[3] * rho * length ** k
            B[m, i, j] = r[4] * rho * length ** k * w[m]
    X = heads = None
    if os.path.exists(stem + ".3"):
        r3 = [(ln, r) for ln, r in _rows(stem + ".3", 7, ".3 (PER BETA I |X| phase Re Im)") if r[0] > 0]
        _blocks(stem + ".3", r3, lambda r: (r[0],), lambda r: (r[1], int(r[2])), "(BETA, I) entries")
        heads_deg = np.unique(np.round([r[1] for _, r in r3], 9))
        heads = np.radians(heads_deg)
        p3 = np.unique([r[0] for _, r in r3])
        if p3.size != periods.size or not np.allclose(np.sort(p3), periods, rtol=1e-6):
            raise DatabaseError(f"{stem}.3: its periods ({p3.size}) are not those of {path} ({periods.size})")
        X = np.zeros((n, heads.size, dofs), dtype=complex)
        for _, r in r3:
            m = int(np.argmin(np.abs(w - 2 * np.pi / r[0])))
            h = int(np.argmin(np.abs(heads_deg - r[1])))
            i = int(r[2]) - 1
            if 0 <= i < dofs:
                X[m, h, i] = complex(r[5], r[6]) * rho * g * length ** (2 if i % 6 < 3 else 3)
    C = None
    if os.path.exists(stem + ".hst"):
        C = np.zeros((6, 6))
        for _, r in _rows(stem + ".hst", 3, ".hst (I J C)"):
            i, j = int(r[0]) - 1, int(r[1]) - 1
            if 0 <= i < 6 and 0 <= j < 6:
                k = 2 if (i, j) == (2, 2) else (3 if 2 in (i, j) else 4)
                C[i, j] = r[2] * rho * g * length ** k
    cog = np.asarray(cog, dtype=float)
    t = Tables(w, A, B, Ainf, heads, X)
    if dofs == 6:
        t = move_to_cog(t, -cog, -cog, g, depth)
    return Database(t, C, None, None, bool(np.allclose(cog, 0.0)))


def write_wamit(stem: str, tables: Tables, rho: float, g: float, length: float = 1.0, stiffness=None) -> list:
    """Our tables as WAMIT's `.1`, `.3` (when they hold an excitation) and `.hst` (given a
    stiffness), non-dimensional as the manual defines, about the COG as WAMIT's origin, 15
    significant digits. Returns the files written."""
    out = []
    w = np.asarray(tables.omega, dtype=float)
    with open(stem + ".1", "w") as f:
        if tables.added_mass_infinite is not None:
            for i in range(6):
                for j in range(6):
                    f.write(f"{0.0:22.15E} {i + 1:5d} {j + 1:5d} "
                            f"{tables.added_mass_infinite[i, j] / (rho * length ** _k_exponent(i, j)):22.15E}\n")
        for m in np.argsort(-w):                        # by increasing period, as WAMIT lists them
            for i in range(6):
                for j in range(6):
                    norm = rho * length ** _k_exponent(i, j)
                    f.write(f"{2 * np.pi / w[m]:22.15E} {i + 1:5d} {j + 1:5d} {tables.added_mass[m, i, j] / norm:22.15E} "
                            f"{tables.damping[m, i, j] / (norm * w[m]):22.15E}\n")
    out.append(stem + ".1")
    if tables.excitation is not None:
        with open(stem + ".3", "w") as f:
            for m in np.argsort(-w):
                for h, beta in enumerate(tables.headings):
                    for i in range(6):
                        x = tables.excitation[m, h, i] / (rho * g * length ** (2 if i < 3 else 3))
                        f.write(f"{2 * np.pi / w[m]:22.15E} {np.degrees(beta):22.15E} {i + 1:5d} {abs(x):22.15E} "
                                f"{np.degrees(np.angle(x)):22.15E} {x.real:22.15E} {x.imag:22.15E}\n")
        out.append(stem + ".3")
    if stiffness is not None:
        with open(stem + ".hst", "w") as f:
            for i in range(6):
                for j in range(6):
                    k = 2 if (i, j) == (2, 2) else (3 if 2 in (i, j) else 4)
                    f.write(f"{i + 1:5d} {j + 1:5d} {stiffness[i, j] / (rho * g * length ** k):22.15E}\n")
        out.append(stem + ".hst")
    return out


def read_database(path: str, rho: float, g: float, cog=None, length: float = 1.0, depth=None, body=None) -> Database:
    """A Capytaine NetCDF dataset (.nc) or WAMIT's .1 (with its .3 and .hst), by the file's extension
    (`body`: the block of that body in a multibody dataset; WAMIT's NBODY files give the first
    body's)."""
    if not os.path.exists(path):
        raise DatabaseError(f"{path}: no such file")
    ext = os.path.splitext(path)[1].lower()
    if ext in (".nc", ".cdf", ".netcdf", ".h5"):
        return read_netcdf(path, cog, g, body)
    if ext == ".1":
        return read_wamit(path, rho, g, length, (0.0, 0.0, 0.0) if cog is None else cog, depth)
    raise DatabaseError(f"{path}: unknown format {ext or '(no extension)'}: a Capytaine NetCDF dataset (.nc) or "
                        f"WAMIT's .1 (with .3 and .hst beside it)")
