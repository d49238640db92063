"""Where a scene's hydrodynamics come from: its tables or Capytaine, the source of its wave forces,
and the radiation memory fitted to its tables (cached per table)."""
from __future__ import annotations

import dataclasses
import functools
from typing import Optional

import numpy as np

from .capytaine import capytaine_tables
from .radiation import RadiationFit, fit_tables
from .tables import Tables, interpolate_excitation, scene_tables


def excitation_source(scene) -> Optional[str]:
    """"table" or "froude-krylov": where the wave forces of a scene come from (None without waves)."""
    if scene.waves is None:
        return None
    hd = scene.vessel.hydrodynamics
    tables = hd is not None and (hd.capytaine or hd.excitation_amplitude is not None)
    if hd is not None and hd.excitation != "auto":
        return hd.excitation
    return "table" if tables else "froude-krylov"


def tables_of(hd, hull, rho, g, depth=None, headings=()) -> Tables:
    """The tables of a `[vessel.hydrodynamics]`: as written, or Capytaine's for the hull (cached per
    hull and settings) when it says `capytaine = true`."""
    if hd.capytaine:
        return capytaine_tables(hull, rho, g, depth, hd.frequencies or None, headings, hd.panel_size, hd.base_dir)
    return scene_tables(hd)


def scene_hydro_tables(scene) -> Tables:
    """The tables of a scene, with the excitation for its wave heading."""
    env, ves, waves = scene.environment, scene.vessel, scene.waves
    return tables_of(ves.hydrodynamics, ves.hull, env.water_density, env.gravity,
                     None if waves is None else waves.depth, () if waves is None else (float(waves.heading),))


@functools.lru_cache(maxsize=32)
def _radiation_fit_cached(hd, hull, rho, g, depth, heading):
    return fit_tables(tables_of(hd, hull, rho, g, depth, () if heading is None else (heading,)), order=hd.memory_order)


def radiation_fit(scene) -> Optional[RadiationFit]:
    """The memory fit of a scene's hydrodynamic tables (cached), or None without added mass and damping."""
    hd = scene.vessel.hydrodynamics
    if hd is None or not (hd.capytaine or hd.added_mass is not None):
        return None
    w = scene.waves
    # Capytaine's solve holds the diffraction of the wave heading too: the same cached solve serves both
    return _radiation_fit_cached(hd, scene.vessel.hull, scene.environment.water_density, scene.environment.gravity,
                                 None if w is None else w.depth, None if w is None or not hd.capytaine else w.heading)


def excitation_rao(scene, omega, headings=None):
    """X (N, 6) complex: the scene's wave forces per unit amplitude at frequencies omega, for its
    wave heading (or each component's, `headings` (N,): a spread sea), from its source (tables or
    Froude-Krylov on the box hull)."""
    waves, ves, env = scene.waves, scene.vessel, scene.environment
    if headings is not None:
        omega, headings = np.asarray(omega, dtype=float), np.asarray(headings, dtype=float)
        X = np.zeros((omega.size, 6), dtype=complex)
        for b in np.unique(headings):
            sel = headings == b
            X[sel] = excitation_rao(dataclasses.replace(scene, waves=dataclasses.replace(waves, heading=float(b))),
                                    omega[sel])
        return X
    if excitation_source(scene) == "table":
        return interpolate_excitation(scene_hydro_tables(scene), omega, waves.heading)
    return ves.hull.froude_krylov(omega, waves.heading, env.water_density, env.gravity, waves.depth)


def excitation_at(hd, hull, tables: Optional[Tables], omega, heading, rho, g, depth=None):
    """X (N, 6) complex per unit wave amplitude at frequencies omega for one heading, our phase
    convention (F = a |X| cos(w t + arg X) for eta = a cos(w t) at the COG): the excitation tables
    (interpolated in w and heading) where the scene has them and `excitation` does not say
    "froude-krylov", else Froude-Krylov on the box hull; None when the scene has neither."""
    source = "auto" if hd is None else hd.excitation
    has_table = tables is not None and tables.excitation is not None
    if has_table and source != "froude-krylov":
        return interpolate_excitation(tables, omega, heading)
    if hull is not None and source != "table":
        return hull.froude_krylov(omega, heading, rho, g, depth)    # None where it has no closed form
    return None
