"""Capytaine (an optional extra: pip install "jaxslosh[hydro]"): the hydrostatics of a hull and
its hydrodynamic tables about the COG, and the TOML tables a scene can hold instead.

Capytaine is imported inside the functions that need it: it is optional, and a scene without
`capytaine = true` never loads it."""
from __future__ import annotations

import importlib.util
import inspect
import logging

import numpy as np

from .database import save_netcdf, tables_from_dataset
from .tables import Tables


CAPYTAINE_MISSING = "needs Capytaine, an optional extra: pip install 'jaxslosh[hydro]' (or pip install capytaine)"


def have_capytaine() -> bool:
    try:
        return importlib.util.find_spec("capytaine") is not None
    except (ImportError, ValueError):
        return False


def capytaine_version() -> str:
    return _import_capytaine().__version__


def _import_capytaine():
    try:
        import capytaine as cpt
    except ImportError as e:
        raise ImportError(CAPYTAINE_MISSING) from e
    logging.getLogger("capytaine").setLevel(logging.ERROR)
    return cpt


def default_frequencies(n: int = 40, lo: float = 0.1, hi: float = 4.0):
    return tuple(np.linspace(lo, hi, n))


def _hull_body(cpt, hull, panel_size, base_dir="", resolution=None, lid=True, omega_max=None):
    """The wetted part of a hull (scene/hulls.py: the box's mesh or the file's; the COG at the
    origin), with a lid inside the waterplane against irregular frequencies (see `_lid_depth`),
    and the six rigid dofs about the COG."""
    mesh, z_wl = hull.capytaine_mesh(cpt, panel_size, resolution, base_dir)
    return _body_from_mesh(cpt, mesh, z_wl, lid, omega_max)


def _lid_depth(hull, omega_max):
    """Where the lid goes: a lid closer to the free surface pushes the irregular frequencies of
    the lidded interior problem higher, but one a millimetre below it (as this module had) sits
    against the waterline's panels and left spikes in the box tables (B_33 < 0 at 2.3 rad/s for a
    16 x 10 x 2.5 m box): the lid goes as deep as keeps the irregular frequencies above
    `omega_max` (Capytaine's `lowest_lid_position`), and no deeper than a quarter of the draft
    (where a hull that is not wall-sided could narrow)."""
    depth = -float(np.min(hull.vertices[:, 2]))
    z = -0.25 * depth
    if omega_max is not None and hasattr(hull, "lowest_lid_position"):
        with np.errstate(invalid="ignore"):
            lowest = float(hull.lowest_lid_position(float(omega_max)))
        if np.isfinite(lowest):            # nan: no irregular frequency below omega_max at all
            z = max(z, lowest)
    return min(z, -1e-3 * max(1.0, depth))


def _body_from_mesh(cpt, mesh, z_wl, lid=True, omega_max=None):
    # Capytaine puts the free surface at z = 0: the mesh goes down by the waterline height; the COG
    # (our origin) then sits at z = -z_wl.
    mesh = mesh.translated((0.0, 0.0, -z_wl))
    hull = mesh.immersed_part()
    cog = (0.0, 0.0, -z_wl)
    try:
        if not lid:
            raise TypeError
        lid = hull.generate_lid(z=_lid_depth(hull, omega_max))
        body = cpt.FloatingBody(mesh=hull, lid_mesh=lid, dofs=cpt.rigid_body_dofs(rotation_center=cog),
                                center_of_mass=cog, name="hull")
    except (AttributeError, TypeError):    # Capytaine without lids
        body = cpt.FloatingBody(mesh=hull, dofs=cpt.rigid_body_dofs(rotation_center=cog), center_of_mass=cog,
                                name="hull")
    return body


def capytaine_hydrostatics(hull, rho=1025.0, g=9.81, panel_size=None, base_dir=""):
    """Hydrostatics of a hull from Capytaine: displaced volume, waterplane area, BM_T, BM_L, KB
    (the centre of buoyancy's height above the keel for a box), GM_T and GM_L about the COG."""
    cpt = _import_capytaine()
    # Capytaine integrates the waterplane's second moments at panel centres: with n panels across,
    # BM is low by 1/n^2, so a box's hydrostatics (cheap: no BEM) take 40 along and across (BM -0.06 %);
    # no lid: Capytaine's hydrostatics integrate over the hull's mesh alone
    body = _hull_body(cpt, hull, panel_size, base_dir, resolution=None if panel_size else (40, 40, 4), lid=False)
    V = float(body.disp_volume)
    zb = float(body.center_of_buoyancy[2])
    zg = float(body.center_of_mass[2])
    bmt = float(body.transversal_metacentric_radius)
    bml = float(body.longitudinal_metacentric_radius)
    return {"displaced_volume": V, "waterplane_area": float(body.waterplane_area), "bm_t": bmt, "bm_l": bml,
            "gm_t": bmt + zb - zg, "gm_l": bml + zb - zg, "z_b": zb - zg}


#: Capytaine's datasets solved in this process, by hull and settings (the most recent CACHE_SIZE)
_CACHE: dict = {}
CACHE_SIZE = 16


def _capytaine_solve(hull, rho, g, depth, frequencies, headings, panel_size, base_dir, progress=None):
    """Capytaine's dataset (assemble_dataset) of the hull's radiation at the frequencies and at
    infinite frequency (A_inf), and its diffraction for the headings, about the COG. Solved one
    frequency at a time (all of its radiation and diffraction problems together, as Capytaine
    groups them to reuse its matrices), so that `progress` (run/progress.Progress) counts them."""
    cpt = _import_capytaine()
    w = np.asarray(frequencies if frequencies else default_frequencies(), dtype=float)
    body = _hull_body(cpt, hull, panel_size, base_dir, omega_max=w.max())
    kw = {"rho": rho, "g": g}
    if depth is not None:
        kw["water_depth"] = depth
    solver = cpt.BEMSolver()
    dofs = list(body.dofs)
    solve = (lambda ps: solver.solve_all(ps, progress_bar=False)) if _accepts(solver.solve_all, "progress_bar") \
        else solver.solve_all
    if progress is not None:
        progress.phase("bem", f"Capytaine: {len(dofs) + len(headings)} problems per frequency",
                       total=w.size + 1, unit="frequency")
    results = []
    for m, x in enumerate(w):
        probs = [cpt.RadiationProblem(body=body, radiating_dof=d, omega=float(x), **kw) for d in dofs]
        probs += [cpt.DiffractionProblem(body=body, wave_direction=float(b), omega=float(x), **kw) for b in headings]
        results += solve(probs)
        if progress is not None:
            progress.update(m + 1)
    try:
        results += solve([cpt.RadiationProblem(body=body, radiating_dof=d, omega=np.inf, **kw) for d in dofs])
    except Exception:   # noqa: BLE001 - an older Capytaine without infinite frequency: A_inf fitted instead
        pass
    if progress is not None:
        progress.update(w.size + 1)
    return cpt.assemble_dataset(results)


def capytaine_dataset(hull, rho=1025.0, g=9.81, depth=None, frequencies=None, headings=(), panel_size=None,
                      base_dir="", progress=None):
    """Capytaine's own dataset of the hull (what `capytaine.io.xarray.save_dataset_as_netcdf` saves):
    cached, one solve per hull and settings in a process. `progress`: a run/progress.Progress whose
    phase counts the frequencies solved (nothing is drawn for a dataset already solved)."""
    key = (hull, float(rho), float(g), None if depth is None else float(depth),
           tuple(float(x) for x in frequencies) if frequencies else None, tuple(float(x) for x in headings),
           panel_size, base_dir)
    if key not in _CACHE:
        ds = _capytaine_solve(*key, progress=progress)
        while len(_CACHE) >= CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = ds
    return _CACHE[key]


def save_capytaine_dataset(ds, path: str) -> None:
    """The dataset as Capytaine exports it (complex values split along `complex`), to NetCDF."""
    from capytaine.io.xarray import separate_complex_values
    ds = separate_complex_values(ds)
    for k in ("radiating_dof", "influenced_dof"):      # Capytaine's own workaround (its issue 683)
        ds[k] = ds[k].astype("str")
    save_netcdf(ds, path)


def _accepts(fn, name):
    try:
        return name in inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False


def capytaine_tables(hull, rho=1025.0, g=9.81, depth=None, frequencies=None, headings=(), panel_size=None,
                     base_dir="", progress=None) -> Tables:
    """Added mass, damping (n, 6, 6), A_inf and excitation (FK + diffraction) for the headings, from a
    Capytaine BEM solve of the hull's wetted surface (with a lid against irregular frequencies),
    about the COG. Cached: one solve per hull and settings in a process."""
    return tables_from_dataset(capytaine_dataset(hull, rho, g, depth, frequencies, headings, panel_size, base_dir,
                                                 progress))


def hull_hydrodynamics(hull, *, rho=1025.0, g=9.81, depth=None, frequencies=None, headings=(0.0,),
                       panel_size=None, base_dir="", progress=None):
    """Hydrostatics and hydrodynamic tables of a hull (scene_types.Hull) from Capytaine, as a dict
    in the form of a scene's `[vessel.hydrostatics]` and `[vessel.hydrodynamics]` tables (see
    `to_toml`): the way to feed a scene without Capytaine at run time."""
    if progress is not None:
        progress.phase("hydrostatics", "Capytaine: hydrostatics")
    hs = capytaine_hydrostatics(hull, rho, g, None, base_dir)     # its own fine mesh (no BEM)
    t = capytaine_tables(hull, rho, g, depth, frequencies, headings, panel_size, base_dir, progress)
    hydro = {"frequencies": t.omega.tolist(), "added_mass": t.added_mass.tolist(), "damping": t.damping.tolist()}
    if t.added_mass_infinite is not None:
        hydro["added_mass_infinite"] = t.added_mass_infinite.tolist()
    if t.excitation is not None:
        hydro["headings"] = t.headings.tolist()
        hydro["excitation_amplitude"] = np.abs(t.excitation).tolist()
        hydro["excitation_phase"] = np.angle(t.excitation).tolist()
    return {"hydrostatics": {k: hs[k] for k in ("waterplane_area", "displaced_volume", "gm_t", "gm_l")},
            "hydrodynamics": hydro, "bm_t": hs["bm_t"], "bm_l": hs["bm_l"]}


def _toml_value(x, digits=10):
    if isinstance(x, (list, tuple)):
        if x and isinstance(x[0], (list, tuple)):
            return "[\n" + ",\n".join("  " + _toml_value(r, digits) for r in x) + ",\n]"
        return "[" + ", ".join(_toml_value(v, digits) for v in x) + "]"
    v = float(x)
    if v == 0.0:
        return "0.0"
    return f"{v:.{digits}g}" if ("e" in f"{v:.{digits}g}" or "." in f"{v:.{digits}g}") else f"{v:.{digits}g}.0"


def to_toml(data: dict) -> str:
    """The `[vessel.hydrostatics]` and `[vessel.hydrodynamics]` tables of `hull_hydrodynamics` as TOML."""
    lines = ["[vessel.hydrostatics]"]
    lines += [f"{k} = {_toml_value(v)}" for k, v in data["hydrostatics"].items()]
    lines += ["", "[vessel.hydrodynamics]"]
    for k, v in data["hydrodynamics"].items():
        if k in ("excitation_amplitude", "excitation_phase"):
            v = [[list(map(float, h)) for h in f] for f in v]
        lines.append(f"{k} = {_toml_value(v)}")
    return "\n".join(lines) + "\n"
