"""The large-angle hydrostatics of a scene (`vessel.hydrostatics.model = "nonlinear"`): the hull's
closed surface, its still water plane and, with `[waves]`, the incident components."""
from __future__ import annotations

from typing import Optional

import jax.numpy as jnp
import numpy as np

from ..hull.clip import MIDPOINT_RULE, area_vectors, clip_below
from ..hydro.spectra import components, wavenumber
from ..physics.about import About
from ..physics.hull import HullPressure, IncidentWaves
from ..physics.vessel import Weight
from ..staging import on_device
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
    return IncidentWaves(on_device(c.omega), on_device(wavenumber(c.omega, g, w.depth)),
                         on_device(c.amplitude / w.height), on_device(c.phase), on_device(np.cos(b)),
                         on_device(np.sin(b)), jnp.asarray(params.get(key, w.height), dtype=float),
                         depth=None if w.depth is None else float(w.depth), ramp=float(w.ramp))


def build_hull_pressure(scene, params: dict, g) -> HullPressure:
    """The vessel's term: still water, and the incident waves where the scene has them and
    `[effects] waves` is on (`hull_term` of `[vessel.hull]`)."""
    return hull_term(scene, scene.vessel.hull, params, g)


def hull_term(scene, hull, params: dict, g, key: str = "vessel.hull", place=None) -> HullPressure:
    """The pressure term of `hull` (the vessel's, or a body's: `key` its params' prefix, `place` its
    rest COG's (x, y) from the vessel's, where the waves reach it): one builder for every floating
    body's wetted hull.

    A traced `<key>.kg` moves the COG against the hull: in the body's frame (origin at the
    COG) the surface shifts by kg0 - kg along z and the still water plane, `draft` above the keel,
    lies at draft - kg; a mesh's traced `<key>.cog` shifts it by cog0 - cog, the water at
    -cog_z (the file's z = 0). The triangles stay the scene's (constants) and carry the shift as a vector
    (HullPressure.shift), so the clipping's tangent stays the water plane's. The mass and
    inertia about the COG are the scene's (`vessel.mass`, `vessel.inertia`): KG moves the hull
    against them, not their distribution."""
    env = scene.environment
    waves = scene.waves if scene.waves is not None and scene.effects.waves else None
    tris = hull.triangles(hull.divisions(waves))
    rho = jnp.asarray(params.get("environment.water_density", env.water_density), dtype=float)
    inc: Optional[IncidentWaves] = incident_waves(scene, params) if waves is not None else None
    z_water, shift = jnp.asarray(hull.water_height(), dtype=float), None
    if f"{key}.kg" in params:
        kg = jnp.asarray(params[f"{key}.kg"], dtype=float)
        z_water = jnp.asarray(hull.draft, dtype=float) - kg
        shift = jnp.stack([jnp.zeros_like(kg), jnp.zeros_like(kg), hull.kg - kg])
    elif f"{key}.cog" in params:       # a mesh: its waterline is z = 0 of the file's coordinates
        cog = jnp.asarray(params[f"{key}.cog"], dtype=float)
        z_water = -cog[2]
        shift = jnp.asarray(hull.cog, dtype=float) - cog
    at = None if place is None else jnp.asarray([place[0], place[1], 0.0], dtype=float)
    return HullPressure(on_device(tris), rho, g, z_water, inc, shift,
                        about=hull_about(scene, waves is not None, hull), place=at)


def body_restoring(scene, body, params: dict, g, liquid=None, mass=None, S=None) -> Optional[tuple]:
    """The restoring terms of a `[[bodies]]` body with nonlinear hydrostatics, as the vessel's
    (assemble/system.py): its hull's pressure (`hull_term`, the waves at its place) and its weight,
    the liquid of its tanks (`liquid`, elastic walls included) included; `mass` and `S` the hull's
    own mass and first moment where elastic walls carry theirs (default: the body's mass, none);
    () with `[effects] buoyancy` off (nothing holds it up nor pulls it down, as the vessel); None
    for linear hydrostatics (assemble/bodies.py's term)."""
    if not body.hydrostatics.nonlinear:
        return None
    if not scene.effects.buoyancy:
        return ()
    key = f"bodies.{body.name}"
    mass = jnp.asarray(params.get(f"{key}.mass", body.mass) if mass is None else mass, dtype=float)
    weight = About(("gravity", f"the weight of the body {body.name!r} and its liquid, borne by its hull's pressure"))
    return (hull_term(scene, body.hull, params, g, f"{key}.hull", body.position),
            weight_term(mass, S, liquid, g, weight))


def weight_term(mass, S, liquid, g, about: About) -> Weight:
    """A floating body's weight with the liquid it carries (`liquid`, None: none), the vessel's and a
    body's alike: `mass` and `S` its hull's own (S None: its COG at the frame origin)."""
    if liquid is not None:
        S = liquid.rigid_first_moment() if S is None else S + liquid.rigid_first_moment()
        mass = mass + liquid.total_mass()
    return Weight(mass=mass, S=jnp.zeros(3) if S is None else S, gravity=g, about=about)


def restoring_words(scene, body) -> str:
    """A body's nonlinear restoring in words (its line in `jaxslosh check`)."""
    if not scene.effects.buoyancy:
        return "no hydrostatics ([effects] buoyancy off)"
    waves = scene.waves is not None and scene.effects.waves
    return (f"nonlinear hydrostatics: the still-water pressure on the instantaneous wetted surface of its "
            f"{body.hull.describe()}" + (" and the waves' Froude-Krylov pressure there, at its place" if waves else "")
            + ", and its weight")


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
