"""The large-angle hydrostatics of a scene (`vessel.hydrostatics.model = "nonlinear"`): the hull's
closed surface, its still water plane and, with `[waves]`, the incident components."""
from __future__ import annotations

from typing import Optional

import jax.numpy as jnp
import numpy as np

from ..hull.clip import MIDPOINT_RULE, area_vectors, clip_below
from ..hydro.spectra import components, wavenumber
from ..physics.hull import HullPressure, IncidentWaves
from .about import hull_about

def hull_pressure(scene) -> bool:
    """Whether the scene's restoring is the pressure on its wetted hull: the nonlinear
    hydrostatics with the buoyancy effect on."""
    hs = scene.vessel.hydrostatics
    return hs is not None and hs.nonlinear and scene.effects.buoyancy


def hull_waves(scene) -> bool:
    """Whether the scene's incident waves act on its wetted hull: `hull_pressure` with [waves] and
    the waves effect on."""
    return hull_pressure(scene) and scene.waves is not None and scene.effects.waves


def incident_waves(scene, params: dict) -> IncidentWaves:
    w, g = scene.waves, scene.environment.gravity
    c = components(w)
    b = c.each_heading()
    key = w.height_key
    return IncidentWaves(jnp.asarray(c.omega), jnp.asarray(wavenumber(c.omega, g, w.depth)),
                         jnp.asarray(c.amplitude / w.height), jnp.asarray(c.phase), jnp.asarray(np.cos(b)),
                         jnp.asarray(np.sin(b)), jnp.asarray(params.get(key, w.height), dtype=float),
                         depth=None if w.depth is None else float(w.depth), ramp=float(w.ramp))


def build_hull_pressure(scene, params: dict, g) -> HullPressure:
    """The term: still water, and the incident waves where the scene has them and `[effects] waves` is on.

    A traced `vessel.hull.kg` moves the COG against the hull: in the vessel frame (origin at the
    COG) the surface shifts by kg0 - kg along z and the still water plane, `draft` above the keel,
    lies at draft - kg; a mesh's traced `vessel.hull.cog` shifts it by cog0 - cog, the water at
    -cog_z (the file's z = 0). The triangles stay the scene's (constants) and carry the shift as a vector
    (HullPressure.shift), so the clipping's tangent stays the water plane's. The vessel's mass and
    inertia about the COG are the scene's (`vessel.mass`, `vessel.inertia`): KG moves the hull
    against them, not their distribution."""
    hull, env = scene.vessel.hull, scene.environment
    waves = scene.waves if scene.waves is not None and scene.effects.waves else None
    tris = hull.triangles(hull.divisions(waves))
    rho = jnp.asarray(params.get("environment.water_density", env.water_density), dtype=float)
    inc: Optional[IncidentWaves] = incident_waves(scene, params) if waves is not None else None
    z_water, shift = jnp.asarray(hull.water_height(), dtype=float), None
    if "vessel.hull.kg" in params:
        kg = jnp.asarray(params["vessel.hull.kg"], dtype=float)
        z_water = jnp.asarray(hull.draft, dtype=float) - kg
        shift = jnp.stack([jnp.zeros_like(kg), jnp.zeros_like(kg), hull.kg - kg])
    elif "vessel.hull.cog" in params:       # a mesh: its waterline is z = 0 of the file's coordinates
        cog = jnp.asarray(params["vessel.hull.cog"], dtype=float)
        z_water = -cog[2]
        shift = jnp.asarray(hull.cog, dtype=float) - cog
    return HullPressure(jnp.asarray(tris), rho, g, z_water, inc, shift, about=hull_about(scene, waves is not None))


def froude_krylov_surface(tris, z_water, omega, headings, rho=1025.0, g=9.81, depth=None):
    """X (N, 6) complex: the linear Froude-Krylov force and moment (about the COG) per unit wave
    amplitude on the hull's wetted surface at rest, by the quadrature of the clipped pieces
    (hydro/spectra.py's conventions; hydro/box.py has the box in closed form, which a test
    compares): the small-wave limit of the incident pressure the nonlinear model integrates."""
    pieces = np.asarray(clip_below(jnp.asarray(tris), jnp.array([0.0, 0.0, 1.0]), z_water)).reshape(-1, 3, 3)
    a = np.asarray(area_vectors(jnp.asarray(pieces)))                       # (m, 3)
    lam, w = (np.asarray(x) for x in MIDPOINT_RULE)
    x = np.einsum("qk,mkx->mqx", lam, pieces)                                # (m, q, 3)
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    b = np.broadcast_to(np.asarray(headings, dtype=float), omega.shape)
    k = wavenumber(omega, g, depth)[:, None, None]
    zeta = np.minimum(x[None, ..., 2] - z_water, 0.0)
    if depth is None:
        f = np.exp(k * zeta)
    else:
        f = (np.exp(k * zeta) + np.exp(-k * (zeta + 2.0 * depth))) / (1.0 + np.exp(-2.0 * k * depth))
    p = rho * g * f * np.exp(-1j * k * (x[None, ..., 0] * np.cos(b)[:, None, None] + x[None, ..., 1] * np.sin(b)[:, None, None]))
    pw = p * w                                                               # (N, m, q)
    F = -np.einsum("nmq,mx->nx", pw, a)
    M = -np.einsum("nmqx->nx", np.cross(x[None], a[None, :, None, :]) * pw[..., None])
    return np.concatenate([F, M], axis=1)


def froude_krylov_hull(scene, omega, headings=None):
    """`froude_krylov_surface` of the scene's hull at the wave components (the scene's heading
    where `headings` is None), with the surface the nonlinear model integrates on (the scene's
    water depth; deep water without [waves])."""
    hull, env, w = scene.vessel.hull, scene.environment, scene.waves
    return froude_krylov_surface(hull.triangles(hull.divisions(w)), hull.water_height(), omega,
                                 w.heading if headings is None else headings, env.water_density, env.gravity,
                                 None if w is None else w.depth)
