"""The traced seakeeping of a scene: its wave excitation and the hull's radiation, from the host-side
tables (hydro/)."""
from __future__ import annotations

from typing import Optional

import jax.numpy as jnp
import numpy as np

from ..hydro.radiation import RadiationFit
from ..hydro.source import excitation_rao, excitation_source, radiation_fit
from .hull import froude_krylov_hull
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


def build_seakeeping(scene, params: dict) -> tuple:
    """(terms, memory): the wave and radiation terms of a scene, with what its effects switch on,
    and the radiation memory whose states the integrator carries (None without). Host-side tables
    use the scene's water density and gravity (params overrides of those do not reach the
    hydrodynamic coefficients); `waves.amplitude` / `waves.hs` may be traced."""
    eff, ves, waves = scene.effects, scene.vessel, scene.waves
    terms, memory = [], None
    hs = ves.hydrostatics
    # the nonlinear hydrostatics integrate the incident pressure on the wetted hull (physics/hull.py):
    # the linear excitation keeps only what that does not hold (diffraction, from the tables)
    on_hull = hs is not None and hs.nonlinear and eff.buoyancy
    if waves is not None and eff.waves and not (on_hull and excitation_source(scene) == "froude-krylov"):
        key = "waves.amplitude" if waves.type == "regular" else "waves.hs"
        c = components(waves)
        X = excitation_rao(scene, c.omega, c.headings)
        if on_hull:
            X = X - froude_krylov_hull(scene, c.omega, c.headings)
        terms.append(WaveExcitation(make_excitation(waves, X, params.get(key, waves.height))))
    hd = ves.hydrodynamics
    if hd is not None and eff.radiation:
        fit = radiation_fit(scene)
        if fit is not None:
            terms.append(AddedMass(jnp.asarray(fit.added_mass_infinite)))
            memory = memory_module(fit)
            if memory is not None:
                terms.append(RadiationMemory())
        if hd.viscous_damping is not None:
            terms.append(LinearDamping(jnp.asarray(matrix6(hd.viscous_damping))))
    return tuple(terms), memory
