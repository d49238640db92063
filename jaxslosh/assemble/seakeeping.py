"""The traced seakeeping of a scene: its wave excitation and the hull's radiation, from the host-side
tables (hydro/)."""
from __future__ import annotations

from typing import Optional

import jax.numpy as jnp
import numpy as np

from ..hydro.radiation import RadiationFit
from ..hydro.source import excitation_rao, excitation_source, radiation_fit
from .hull import froude_krylov_hull, hull_pressure
from ..hydro.spectra import components
from ..hydro.tables import matrix6
from ..physics.seakeeping import AddedMass, Excitation, LinearDamping, Memory, RadiationMemory, WaveExcitation


def memory_module(fit: RadiationFit) -> Optional[Memory]:
    if fit.p.size == 0:
        return None
    sel = np.zeros((fit.p.size, 6))
    sel[np.arange(fit.p.size), fit.inp] = 1.0
    return Memory(jnp.asarray(fit.p.real), jnp.asarray(fit.p.imag), jnp.asarray(sel),
                  jnp.asarray(fit.c.real), jnp.asarray(fit.c.imag))


def make_excitation(waves, X, height) -> Excitation:
    """From the components of `waves` and X (N, 6): the force of each component per unit `height`."""
    c = components(waves)
    h0 = waves.amplitude if waves.type == "regular" else waves.hs
    a = c.amplitude / h0
    amp = (np.abs(X) * a[:, None]).T
    phase = (np.angle(X) + c.phase[:, None]).T
    return Excitation(jnp.asarray(c.omega), jnp.asarray(amp), jnp.asarray(phase), jnp.asarray(height, dtype=float),
                      ramp=float(waves.ramp))


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
            key = "waves.amplitude" if waves.type == "regular" else "waves.hs"
            terms.append(WaveExcitation(make_excitation(waves, X, params.get(key, waves.height))))
    hd = ves.hydrodynamics
    if hd is not None and eff.radiation:
        fit = radiation_fit(scene)
        if fit is not None:
            terms.append(AddedMass(jnp.asarray(fit.added_mass_infinite)))
            memory = memory_module(fit)
            if memory is not None:
                terms.append(RadiationMemory(memory))
        if hd.viscous_damping is not None:
            terms.append(LinearDamping(jnp.asarray(matrix6(hd.viscous_damping))))
    return tuple(terms)
