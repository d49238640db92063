"""Loader of the wave tables of a scene: `[waves]`, `[vessel.hull]`, `[vessel.hydrodynamics]`.

Same rules as load.py (the field reader of fields.py): an unknown key, a wrong type, a missing required
key or an impossible value is a SceneError naming the dotted key; a doubtful but legal choice is a
warning. Cross-checks that need several tables (an excitation source for the waves, headings inside
the tables, the hull against the hydrostatics) are in `check_waves`.
"""
from __future__ import annotations

import dataclasses
import math
import os
from typing import NamedTuple, Optional

import numpy as np

from ..hydro.capytaine import CAPYTAINE_MISSING, have_capytaine
from ..hydro.database import DatabaseError, read_database
from ..hydro.spectra import wavenumber
from .fields import at_least, non_negative, one_of, positive, read, show
from .types import HULLS, WAVES, Hull, Hydrodynamics, Hydrostatics, Scene, SceneError, Waves

WAVE_TYPES = tuple(WAVES)
DEFAULT_DIRECTIONS = 15          # headings of a spread sea when `directions` is not given
HULL_TYPES = tuple(HULLS)
EXCITATION_SOURCES = ("auto", "table", "froude-krylov")
HULL_MISMATCH_TOLERANCE = 0.01   # relative: the box's closed-form hydrostatics against the scene's table


def read_waves(table, warnings: list[str]) -> Waves:
    where = "waves"
    v = read(table, where, {
        "type": ("str", one_of(WAVE_TYPES)), "heading": ("float", None), "amplitude": ("float", non_negative),
        "period": ("float", positive), "frequency": ("float", positive), "phase": ("float", None),
        "hs": ("float", non_negative), "tp": ("float", positive), "gamma": ("float", _at_least_one),
        "seed": ("int", non_negative), "components": ("int", at_least(1)), "frequency_range": ("numbers", None),
        "ramp": ("float", non_negative), "depth": ("float", positive),
        "spreading": ("float", non_negative), "directions": ("int", at_least(1)),
    }, required=("type",))
    kind = v["type"]
    irregular = ("hs", "tp", "seed", "components", "frequency_range", "spreading", "directions")
    own = {"regular": ("amplitude", "period", "frequency", "phase"),
           "jonswap": irregular + ("gamma",), "pierson-moskowitz": irregular}
    for other, keys in own.items():
        if other != kind:
            for k in keys:
                if k in v and k not in own[kind]:
                    raise SceneError(f"{where}.{k}", f'is a key of type = "{other}" waves, not of type = "{kind}"')
    common = {"heading": v.get("heading", 0.0), "ramp": v.get("ramp", 0.0), "depth": v.get("depth")}
    if kind == "regular":
        if "amplitude" not in v:
            raise SceneError(f"{where}.amplitude", "a required key is missing (regular waves)")
        if ("period" in v) == ("frequency" in v):
            raise SceneError(f"{where}.period", "give exactly one of period (s) or frequency (rad/s)")
        omega = v["frequency"] if "frequency" in v else 2.0 * math.pi / v["period"]
        return WAVES[kind](amplitude=v["amplitude"], omega=omega, phase=v.get("phase", 0.0), **common)
    for k in ("hs", "tp"):
        if k not in v:
            raise SceneError(f"{where}.{k}", f"a required key is missing ({kind} sea)")
    wp = 2.0 * math.pi / v["tp"]
    rng = v.get("frequency_range", [0.5 * wp, 3.0 * wp])
    if not (isinstance(rng, list) and len(rng) == 2 and all(isinstance(x, float) for x in rng)):
        raise SceneError(f"{where}.frequency_range", f"must be 2 numbers [low, high] in rad/s, got {show(rng)}")
    lo, hi = rng
    if not 0 < lo < hi:
        raise SceneError(f"{where}.frequency_range", f"must satisfy 0 < low < high, got {show(rng)}")
    if not lo <= wp <= hi:
        warnings.append(f"waves.frequency_range = {show(rng)} rad/s does not hold the spectral peak "
                        f"{wp:.4g} rad/s: most of the sea's energy is left out")
    spreading = v.get("spreading", 0.0)
    if "directions" in v and spreading == 0:
        raise SceneError(f"{where}.directions", "only goes with spreading > 0 (a long-crested sea has one heading)")
    directions = v.get("directions", DEFAULT_DIRECTIONS) if spreading > 0 else 1
    return WAVES[kind](hs=v["hs"], tp=v["tp"], gamma=v.get("gamma", 3.3) if kind == "jonswap" else 1.0,
                 seed=v.get("seed", 0), components=v.get("components", 100), omega_range=(lo, hi),
                 spreading=spreading, directions=directions, **common)


def _at_least_one(v):
    return None if v >= 1.0 else f"must be >= 1, got {v}"


def read_hull(table, base_dir: str = "", where: str = "vessel.hull") -> Hull:
    """`[vessel.hull]` (or a body's `[bodies.hull]`: `where` names its keys)."""
    v = read(table, where, {
        "type": ("str", one_of(HULL_TYPES)), "length": ("float", positive), "beam": ("float", positive),
        "draft": ("float", positive), "kg": ("float", None), "file": ("str", None), "cog": ("vec3", None),
        "depth": ("float", positive),
    })
    hull_type = v.get("type", "box")
    if hull_type == "box":
        for k in ("length", "beam", "draft", "kg"):
            if k not in v:
                raise SceneError(f"{where}.{k}", "a required key is missing (box hull)")
        for k in ("file", "cog"):
            if k in v:
                raise SceneError(f"{where}.{k}", 'is a key of type = "mesh" hulls, not of a box')
        if v["kg"] <= 0:
            raise SceneError(f"{where}.kg", f"the COG must lie above the keel (kg > 0), got {show(v['kg'])}")
        if "depth" in v and v["depth"] <= v["draft"]:
            raise SceneError(f"{where}.depth", f"the deck must lie above the waterline: depth {show(v['depth'])} m "
                                               f"is not above the draft {show(v['draft'])} m")
        return HULLS["box"](length=v["length"], beam=v["beam"], draft=v["draft"], kg=v["kg"],
                    depth=v.get("depth"), base_dir=base_dir)
    for k in ("length", "beam", "draft", "kg", "depth"):
        if k in v:
            raise SceneError(f"{where}.{k}", 'is a key of box hulls, not of type = "mesh"')
    if "file" not in v:
        raise SceneError(f"{where}.file", "a required key is missing (mesh hull)")
    return HULLS["mesh"](file=v["file"], cog=v.get("cog", (0.0, 0.0, 0.0)), base_dir=base_dir)


def _shape(x):
    a = np.asarray(x, dtype=float)
    return a.shape


def _array(v: dict, key: str, where: str, shapes: tuple, what: str):
    """A numbers array of one of `shapes` (None stands for any positive count); as nested tuples."""
    x = v[key]
    shape = _shape(x)
    for sh in shapes:
        if len(sh) == len(shape) and all(a is None or a == b for a, b in zip(sh, shape)):
            return _tuples(x)
    want = " or ".join("(" + ", ".join("n" if a is None else str(a) for a in sh) + ")" for sh in shapes)
    raise SceneError(f"{where}.{key}", f"must be {what} of shape {want}, got shape {shape}")


def _tuples(x):
    return tuple(_tuples(e) for e in x) if isinstance(x, list) else float(x)


class FileContext(NamedTuple):
    """What reading a hydrodynamic database needs besides its table: the scene's folder (a relative
    `file` is relative to it), water density and gravity (WAMIT's files are non-dimensional; the
    wavenumber that moves phases), the water depth (None: deep)."""
    base_dir: str = ""
    rho: float = 1025.0
    g: float = 9.81
    depth: Optional[float] = None
    body: Optional[str] = None       # the body whose block a multibody file gives (the vessel's name, a body's)


#: the tables a `file` holds: the scene may not give them too
FILE_TABLES = ("frequencies", "added_mass", "damping", "added_mass_infinite", "headings", "excitation_amplitude",
               "excitation_phase", "capytaine", "panel_size")


def _from_file(v: dict, where: str, files: Optional[FileContext], hydrostatics, hull, warnings: list[str]) -> dict:
    """The tables of `file` (hydro/database.py) as the table's own keys would hold them."""
    for k in FILE_TABLES:
        if k in v:
            raise SceneError(f"{where}.{k}", "the tables come from `file`; remove this key (or the file)")
    files = files or FileContext()
    path = v["file"] if os.path.isabs(v["file"]) else os.path.join(files.base_dir, v["file"])
    try:
        db = read_database(path, files.rho, files.g, v.get("cog"), v.get("length_scale", 1.0), files.depth, files.body)
    except DatabaseError as e:
        raise SceneError(f"{where}.file", " ".join(str(e).split())) from None
    t = db.tables
    if t.omega.size < 4 or t.added_mass is None:
        raise SceneError(f"{where}.file", f"{path}: holds {t.omega.size} frequencies of added mass and damping; "
                                          f"the radiation memory needs at least 4")
    out = dict(v, frequencies=t.omega.tolist(), added_mass=t.added_mass.tolist(), damping=t.damping.tolist())
    if t.added_mass_infinite is not None:
        out["added_mass_infinite"] = t.added_mass_infinite.tolist()
    if t.excitation is not None:
        out.update(headings=t.headings.tolist(), excitation_amplitude=np.abs(t.excitation).tolist(),
                   excitation_phase=np.angle(t.excitation).tolist())
    if db.rho is not None and abs(db.rho / files.rho - 1) > 1e-9:
        warnings.append(f"{where}.file: the dataset was computed with water density {db.rho:.6g} kg/m^3, the scene "
                        f"has {files.rho:.6g}: its coefficients are used as they are")
    _check_database(where, path, db, files, hydrostatics, hull, v.get("length_scale", 1.0), warnings)
    return out


#: a database's heave RAO is checked at its lowest frequency where that is a long wave (k L below
#: this) well below heave resonance (w^2 (m + A_33) below this share of rho g A_w): there its
#: modulus lies within about 0.75 and 1.4 of the limit 1, and outside RAO_LIMIT_BAND it cannot
LONG_WAVE_KL, QUASI_STATIC, RAO_LIMIT_BAND = 0.5, 0.25, (0.5, 2.0)
#: a file's C_33 this far from rho g A_w is not a hull detail: units or a length scale
GROSS_MISMATCH = (0.5, 2.0)


def _check_database(where, path, db, files, hydrostatics, hull, length, warnings):
    """What a database can be checked against in the scene: its hydrostatic stiffness against the
    scene's restoring (rho g A_w, rho g V GM about the COG), and its heave RAO at the lowest frequency
    against the long-wave limit 1. One warning each at most, with the likely cause: for WAMIT's
    non-dimensional files a length_scale (ULEN) other than the run's, estimated from the ratio."""
    if hydrostatics is None:
        return
    h, rg = hydrostatics, files.rho * files.g
    wamit = os.path.splitext(path)[1].lower() == ".1"
    rgA = rg * h.waterplane_area

    def cause(ratio, what):             # ratio: file / scene of a quantity scaling as ULEN^2
        if wamit:
            est = length / math.sqrt(ratio)
            return (f"WAMIT's files are non-dimensional, and the scene reads them with length_scale = {length:g} m: "
                    f"length_scale = {est:.3g} m would make {what} agree (give the ULEN of the WAMIT run)")
        return "the file was computed for another hull, draft or units than the scene's [vessel.hydrostatics]"

    C = db.stiffness
    gross = False
    if C is not None and np.abs(C).max() > 0:
        r33 = C[2, 2] / rgA
        if r33 > 0 and not GROSS_MISMATCH[0] <= r33 <= GROSS_MISMATCH[1]:
            gross = True
            warnings.append(f"{where}.file: the file's hydrostatic stiffness C_33 = {C[2, 2]:.6g} N/m is {r33:.3g} "
                            f"times the scene's rho g A_w = {rgA:.6g} N/m: {cause(r33, 'them')}")
        else:
            pairs = [("waterplane_area", 2, rgA)]
            if db.point_is_cog:     # roll and pitch restoring depend on the point they are about
                pairs += [("gm_t", 3, rg * h.displaced_volume * h.gm_t), ("gm_l", 4, rg * h.displaced_volume * h.gm_l)]
            off = [f"C_{i + 1}{i + 1} {C[i, i]:.6g} against {mine:.6g} ({key})" for key, i, mine in pairs
                   if abs(C[i, i] - mine) > HULL_MISMATCH_TOLERANCE * abs(mine)]
            if off:
                warnings.append(f"{where}.file: the file's hydrostatic stiffness differs from the scene's "
                                f"[vessel.hydrostatics] by more than {100 * HULL_MISMATCH_TOLERANCE:g} %: "
                                f"{'; '.join(off)}; the restoring uses [vessel.hydrostatics]")
    t = db.tables
    if gross or t.excitation is None or t.added_mass is None or not t.headings.size:
        return
    w0 = float(t.omega[0])
    span = (hull.span() if hull is not None else None) or 3.5 * math.sqrt(h.waterplane_area)
    k0 = float(wavenumber(w0, files.g, files.depth))
    mass = files.rho * h.displaced_volume          # afloat: the whole mass is the displacement's
    inertia = w0 ** 2 * (mass + t.added_mass[0, 2, 2])
    if k0 * span > LONG_WAVE_KL or not 0 <= inertia <= QUASI_STATIC * rgA:
        return                                      # not a long, quasi-static wave: the limit says nothing
    x3 = np.abs(t.excitation[0, :, 2])
    H = float(np.median(x3 / np.abs(rgA - inertia + 1j * w0 * t.damping[0, 2, 2])))
    if not RAO_LIMIT_BAND[0] <= H <= RAO_LIMIT_BAND[1]:
        ratio = float(np.median(x3)) / rgA
        warnings.append(f"{where}.file: the heave RAO at the lowest frequency {w0:.4g} rad/s (a long wave: k L = "
                        f"{k0 * span:.2g}) is {H:.3g} m/m, where it tends to 1; the file's heave excitation "
                        f"{float(np.median(x3)):.6g} N/m against rho g A_w = {rgA:.6g} N/m: "
                        + (cause(ratio, "them") if ratio > 0 else "the excitation is zero"))


def read_hydrodynamics(table, hull: Optional[Hull], files: Optional[FileContext] = None,
                       warnings: Optional[list] = None, hydrostatics=None,
                       where: str = "vessel.hydrodynamics") -> Hydrodynamics:
    v = read(table, where, {
        "frequencies": ("numbers", None), "added_mass": ("numbers", None), "damping": ("numbers", None),
        "added_mass_infinite": ("numbers", None), "headings": ("numbers", None),
        "excitation_amplitude": ("numbers", None), "excitation_phase": ("numbers", None),
        "viscous_damping": ("numbers", None), "capytaine": ("bool", None), "panel_size": ("float", positive),
        "memory_order": ("int", non_negative), "excitation": ("str", one_of(EXCITATION_SOURCES)),
        "file": ("str", None), "cog": ("vec3", None), "length_scale": ("float", positive),
    })
    for k in ("cog", "length_scale"):
        if k in v and "file" not in v:
            raise SceneError(f"{where}.{k}", "only goes with `file` (a hydrodynamic database)")
    if "file" in v:
        v = _from_file(v, where, files, hydrostatics, hull, warnings if warnings is not None else [])
    capy = v.get("capytaine", False)
    out = {"capytaine": capy, "panel_size": v.get("panel_size"), "memory_order": v.get("memory_order", 0),
           "excitation": v.get("excitation", "auto"), "file": v.get("file", ""),
           "cog": tuple(v["cog"]) if "cog" in v else None, "length_scale": v.get("length_scale", 1.0)}
    if capy:
        if hull is None:
            raise SceneError(f"{where}.capytaine", "needs a [vessel.hull] table (the geometry to solve for)")
        for k in ("added_mass", "damping", "added_mass_infinite", "headings", "excitation_amplitude", "excitation_phase"):
            if k in v:
                raise SceneError(f"{where}.{k}", "with capytaine = true the tables are computed; remove this key "
                                                 "(or capytaine = true)")
        if not have_capytaine():
            raise SceneError(f"{where}.capytaine", CAPYTAINE_MISSING)
    if "frequencies" in v:
        w = v["frequencies"]
        if not (isinstance(w, list) and w and all(isinstance(x, float) for x in w)):
            raise SceneError(f"{where}.frequencies", f"must be a list of numbers (rad/s), got {show(w)}")
        if w[0] <= 0 or any(b <= a for a, b in zip(w, w[1:])):
            raise SceneError(f"{where}.frequencies", "must be positive and strictly ascending (rad/s)")
        if len(w) < 4:
            raise SceneError(f"{where}.frequencies", f"needs at least 4 frequencies, got {len(w)}")
        out["frequencies"] = tuple(w)
    n = len(out.get("frequencies", ()))
    tabled = [k for k in ("added_mass", "damping", "excitation_amplitude", "excitation_phase") if k in v]
    if tabled and not n:
        raise SceneError(f"{where}.frequencies", f"a required key is missing (the tables {', '.join(tabled)} "
                                                 f"are per frequency)")
    if ("added_mass" in v) != ("damping" in v):
        missing = "damping" if "added_mass" in v else "added_mass"
        raise SceneError(f"{where}.{missing}", "added_mass and damping come together (the radiation memory needs both)")
    for k in ("added_mass", "damping"):
        if k in v:
            out[k] = _array(v, k, where, ((n, 6), (n, 6, 6)), "one row of 6 (diagonal) or a 6 x 6 per frequency")
    if "added_mass" in v:
        A = np.asarray(out["added_mass"])
        diag = A if A.ndim == 2 else A[:, range(6), range(6)]
        if (diag < 0).any():
            i, j = np.argwhere(diag < 0)[0]
            raise SceneError(f"{where}.added_mass", f"diagonal added mass must be >= 0: {diag[i, j]:.6g} at "
                                                    f"frequency {out['frequencies'][i]:g} rad/s, dof {j + 1}")
        Bd = np.asarray(out["damping"])
        bdiag = Bd if Bd.ndim == 2 else Bd[:, range(6), range(6)]
        if (bdiag < 0).any():
            i, j = np.argwhere(bdiag < 0)[0]
            raise SceneError(f"{where}.damping", f"diagonal radiation damping must be >= 0 (a body does not gain "
                                                 f"energy from radiating waves): {bdiag[i, j]:.6g} at frequency "
                                                 f"{out['frequencies'][i]:g} rad/s, dof {j + 1}")
    if "added_mass_infinite" in v:
        if "added_mass" not in v:
            raise SceneError(f"{where}.added_mass_infinite", "needs the added_mass and damping tables")
        out["added_mass_infinite"] = _array(v, "added_mass_infinite", where, ((6,), (6, 6)), "6 values or a 6 x 6")
    if "viscous_damping" in v:
        out["viscous_damping"] = _array(v, "viscous_damping", where, ((6,), (6, 6)), "6 values or a 6 x 6")
        Bv = np.asarray(out["viscous_damping"])
        Bv = np.diag(Bv) if Bv.ndim == 1 else Bv
        if np.linalg.eigvalsh(0.5 * (Bv + Bv.T)).min() < -1e-12 * max(1.0, np.abs(Bv).max()):
            raise SceneError(f"{where}.viscous_damping", "must be positive semi-definite (damping dissipates)")
    if ("excitation_amplitude" in v) != ("excitation_phase" in v):
        missing = "excitation_phase" if "excitation_amplitude" in v else "excitation_amplitude"
        raise SceneError(f"{where}.{missing}", "excitation_amplitude and excitation_phase come together")
    if "excitation_amplitude" in v:
        if "headings" not in v:
            raise SceneError(f"{where}.headings", "a required key is missing (the excitation tables' headings, rad)")
        h = v["headings"]
        if isinstance(h, float):
            h = [h]
        if not (isinstance(h, list) and h and all(isinstance(x, float) for x in h)):
            raise SceneError(f"{where}.headings", f"must be a list of numbers (rad), got {show(v['headings'])}")
        if any(b <= a for a, b in zip(h, h[1:])):
            raise SceneError(f"{where}.headings", "must be strictly ascending")
        out["headings"] = tuple(h)
        nh = len(h)
        shapes = ((n, nh, 6),) + (((n, 6),) if nh == 1 else ())
        out["excitation_amplitude"] = _array(v, "excitation_amplitude", where, shapes, "6 values per frequency and heading")
        out["excitation_phase"] = _array(v, "excitation_phase", where, shapes, "6 values per frequency and heading")
        if (np.asarray(out["excitation_amplitude"]) < 0).any():
            raise SceneError(f"{where}.excitation_amplitude", "amplitudes must be >= 0 (the phase carries the sign)")
    elif "headings" in v:
        raise SceneError(f"{where}.headings", "is only used with excitation_amplitude and excitation_phase")
    if not capy and not any(k in out for k in ("added_mass", "excitation_amplitude", "viscous_damping")):
        raise SceneError(where, "holds nothing: give added_mass and damping, excitation tables, viscous_damping, "
                                "or capytaine = true")
    return Hydrodynamics(**out)


def hull_hydrostatics(hull: Hull, hydrostatics: Optional[Hydrostatics], warnings: list[str]) -> Optional[Hydrostatics]:
    """A box hull without a [vessel.hydrostatics] table gives its closed forms; with one, the two
    are compared (a mismatch is warned about: the excitation's long-wave limit then disagrees with
    the restoring)."""
    box = hull.closed_hydrostatics()
    if box is None:
        return hydrostatics
    if hydrostatics is None:
        return Hydrostatics(**box)
    for key in ("waterplane_area", "displaced_volume", "gm_t", "gm_l"):
        given, closed = getattr(hydrostatics, key), box[key]
        if abs(given - closed) > HULL_MISMATCH_TOLERANCE * max(abs(closed), 1e-12):
            warnings.append(f"vessel.hydrostatics.{key} = {given:.6g} differs from the box hull's {closed:.6g} "
                            f"(vessel.hull); the restoring uses the table, the Froude-Krylov forces the box")
    return hydrostatics


def check_waves(scene: Scene, path: str, warnings: list[str]) -> Scene:
    """Cross-checks of the wave tables; resolves a mesh file against the scene's folder."""
    ves, waves = scene.vessel, scene.waves
    hd = ves.hydrodynamics
    if hd is not None and path:
        scene = dataclasses.replace(scene, vessel=dataclasses.replace(
            ves, hydrodynamics=dataclasses.replace(hd, base_dir=os.path.dirname(os.path.abspath(path)))))
        ves, hd = scene.vessel, scene.vessel.hydrodynamics
    nonlinear = ves.hydrostatics is not None and ves.hydrostatics.nonlinear
    if ves.hull is not None and not ves.hull.closed_form and not (hd is not None and hd.capytaine) and not nonlinear:
        raise SceneError("vessel.hull.type", 'a "mesh" hull is read by Capytaine or by the nonlinear hydrostatics: '
                                             'add [vessel.hydrodynamics] capytaine = true or [vessel.hydrostatics] '
                                             'model = "nonlinear" (or use a box)')
    if waves is None:
        return scene
    tables = hd is not None and (hd.capytaine or hd.excitation_amplitude is not None)
    box = ves.hull is not None and ves.hull.closed_form
    source = "auto" if hd is None else hd.excitation
    if source == "table" and not tables:
        raise SceneError("vessel.hydrodynamics.excitation", '"table" needs excitation_amplitude and excitation_phase '
                                                            "(or capytaine = true)")
    if source == "froude-krylov" and not box:
        raise SceneError("vessel.hydrodynamics.excitation", '"froude-krylov" needs a box [vessel.hull]')
    if not tables and not box and not nonlinear:
        raise SceneError("waves", "nothing turns the waves into forces: give a box [vessel.hull] (Froude-Krylov) "
                                  "or excitation tables in [vessel.hydrodynamics] (or capytaine = true)")
    if ves.forced is not None:
        warnings.append("waves: the vessel's motion is prescribed ([vessel.forced]): the wave forces act on nothing")
    uses_table = tables and source != "froude-krylov"
    if uses_table and waves.spreading > 0:   # the tables hold one heading or a few, the spread sea comes from all
        raise SceneError("waves.spreading", "a spread sea has components from every heading: its forces need "
                                            'Froude-Krylov on a box hull ([vessel.hydrodynamics] excitation = '
                                            '"froude-krylov")')
    if uses_table and hd.excitation_amplitude is not None:
        heads = hd.headings
        b = waves.heading
        if len(heads) == 1:
            if abs(b - heads[0]) > 1e-6:
                raise SceneError("waves.heading", f"{b:.6g} rad: the excitation tables hold heading {heads[0]:.6g} rad "
                                                  f"only")
        elif not heads[0] - 1e-6 <= b <= heads[-1] + 1e-6:
            raise SceneError("waves.heading", f"{b:.6g} rad lies outside the excitation tables' headings "
                                              f"[{heads[0]:.6g}, {heads[-1]:.6g}] rad")
        lo, hi = hd.frequencies[0], hd.frequencies[-1]
        wl, wh = waves.band
        if wl < lo - 1e-9 or wh > hi + 1e-9:
            if not waves.irregular:
                raise SceneError("waves.frequency", f"{waves.omega:.6g} rad/s lies outside the excitation tables' "
                                                    f"frequencies [{lo:.6g}, {hi:.6g}] rad/s")
            warnings.append(f"waves.frequency_range [{wl:.4g}, {wh:.4g}] rad/s reaches beyond the excitation tables' "
                            f"[{lo:.4g}, {hi:.4g}] rad/s: components outside them exert no force")
    if not box and not uses_table and not nonlinear:
        raise SceneError("waves", "no excitation source")
    return scene
