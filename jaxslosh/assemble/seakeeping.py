"""The traced seakeeping of a scene: its wave excitation and the hull's radiation, from the host-side
tables (hydro/)."""
from __future__ import annotations

from typing import Optional

import jax.numpy as jnp
import numpy as np

from ..hydro.radiation import RadiationFit
from ..hydro.source import excitation_rao, excitation_source, radiation_fit
from .about import added_mass_about, memory_about, viscous_about, waves_about
from .hull import froude_krylov_hull, hull_pressure
from ..hydro.spectra import components
from ..hydro.tables import matrix6
from ..physics.seakeeping import AddedMass, Excitation, LinearDamping, Memory, RadiationMemory, WaveExcitation
from ..staging import on_device


def memory_module(fit: RadiationFit) -> Optional[Memory]:
    """The vessel's own radiation memory, over its six dofs (`memory_of`)."""
    return memory_of([(fit, np.arange(6))], 6)


def memory_of(fits, N: int) -> Optional[Memory]:
    """The radiation memory over N rigid dofs of fits, each (RadiationFit, the dofs (d,) of the N its
    tables are over): one builder for the vessel's own fit (over its six) and the bodies' sources
    (over the 6 + 6 S dofs of the vessel and the bodies, assemble/bodyhydro.py); None without poles."""
    if not sum(f.p.size for f, _ in fits):
        return None
    p = np.concatenate([f.p for f, _ in fits])
    sel = np.zeros((p.size, N))
    sel[np.arange(p.size), np.concatenate([np.asarray(ix)[f.inp] for f, ix in fits])] = 1.0
    c = np.zeros((N, p.size), dtype=complex)
    k = 0
    for f, ix in fits:
        c[np.asarray(ix), k:k + f.p.size] = f.c
        k += f.p.size
    return Memory(on_device(p.real), on_device(p.imag), on_device(sel), on_device(c.real), on_device(c.imag))


def make_excitation(waves, X, height) -> Excitation:
    """From the components of `waves` and X (N, 6): the force of each component per unit `height`."""
    omega, amp, phase = excitation_arrays(waves, components(waves), X)
    return Excitation(on_device(omega), on_device(amp), on_device(phase), jnp.asarray(height, dtype=float),
                      ramp=float(waves.ramp))


def excitation_arrays(waves, c, X) -> tuple:
    """(omega (N,), amp (6, N) per unit height, phase (6, N)) of make_excitation, as NumPy arrays,
    from the components `c` of `waves` (hydro/spectra.components) and X (N, 6): what a campaign's
    batch of seas runs on (campaign/cases.sea_arrays), drawn on the host once per case."""
    a = c.amplitude / waves.height
    return c.omega, (np.abs(X) * a[:, None]).T, (np.angle(X) + c.phase[:, None]).T


def linear_excitation_rao(scene, c) -> Optional[np.ndarray]:
    """X (N, 6) of the scene's linear wave excitation term at the components `c` (hydro/spectra.
    components), None where it has none: the nonlinear hydrostatics integrate the incident
    pressure on the wetted hull (physics/hull.py), so the linear term keeps only what that does
    not hold (diffraction, from the tables), and nothing at all with Froude-Krylov forces alone."""
    on_hull = hull_pressure(scene)
    if on_hull and excitation_source(scene) == "froude-krylov":
        return None
    X = excitation_rao(scene, c.omega, c.headings)
    return X - froude_krylov_hull(scene, c.omega, c.headings) if on_hull else X


def build_seakeeping(scene, params: dict) -> tuple:
    """The wave and radiation terms of a scene, with what its effects switch on (the radiation
    memory among them, a term with integrator states). Host-side tables
    use the scene's water density and gravity (params overrides of those do not reach the
    hydrodynamic coefficients); `waves.amplitude` / `waves.hs` may be traced."""
    eff, ves, waves = scene.effects, scene.vessel, scene.waves
    terms = []
    if waves is not None and eff.waves:
        X = linear_excitation_rao(scene, components(waves))
        if X is not None:
            key = waves.height_key
            terms.append(WaveExcitation(make_excitation(waves, X, params.get(key, waves.height)),
                                        about=waves_about(scene, hull_pressure(scene))))
    hd = ves.hydrodynamics
    if hd is not None and eff.radiation:
        fit = radiation_fit(scene)
        if fit is not None:
            terms.append(AddedMass(jnp.asarray(fit.added_mass_infinite), about=added_mass_about(scene)))
            memory = memory_module(fit)
            if memory is not None:
                terms.append(RadiationMemory(memory, about=memory_about(scene)))
        if hd.viscous_damping is not None:
            terms.append(LinearDamping(jnp.asarray(matrix6(hd.viscous_damping)), about=viscous_about()))
    return tuple(terms)


def outline_seakeeping(scene) -> tuple:
    """`build_seakeeping`'s terms without their arrays (None), for `jaxslosh check`
    (assemble/check.py): no excitation tables interpolated, no radiation fitted. The memory term is
    there where the tables have radiation, as the build's fit of them finds poles (tables of zero
    damping would give none)."""
    eff, ves, waves = scene.effects, scene.vessel, scene.waves
    terms = []
    if waves is not None and eff.waves and not (hull_pressure(scene) and excitation_source(scene) == "froude-krylov"):
        terms.append(WaveExcitation(None, about=waves_about(scene, hull_pressure(scene))))
    hd = ves.hydrodynamics
    if hd is not None and eff.radiation:
        if hd.capytaine or hd.added_mass is not None:          # hydro/source.radiation_fit has a fit
            terms += [AddedMass(None, about=added_mass_about(scene)), RadiationMemory(None, about=memory_about(scene))]
        if hd.viscous_damping is not None:
            terms.append(LinearDamping(None, about=viscous_about()))
    return tuple(terms)
