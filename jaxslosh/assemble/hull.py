"""The large-angle hydrostatics of a scene (`vessel.hydrostatics.model = "nonlinear"`): the hull's
closed surface, its still water plane and, with `[waves]`, the incident components."""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax.numpy as jnp
import numpy as np

from ..hull.clip import MIDPOINT_RULE, area_vectors, clip_below
from ..hydro.spectra import components, wavenumber
from ..physics.about import About
from ..physics.hull import HullPressure, IncidentWaves
from ..physics.vessel import RESTORING_FORMS, AbstractRestoring, Weight
from ..staging import on_device
from .about import hull_about


def hull_pressure(scene, floating=None) -> bool:
    """Whether a floating body's restoring is the pressure on its wetted hull (`floating`: the
    vessel where None, or a body): its nonlinear hydrostatics with the buoyancy effect on."""
    hs = (scene.vessel if floating is None else floating).hydrostatics
    return hs is not None and hs.nonlinear and scene.effects.buoyancy


class Restoring(NamedTuple):
    """A floating body's restoring as its scene chooses it (`restoring`)."""
    terms: tuple          # its hull's pressure, its linear springs, or nothing
    weighs: bool          # its weight is a term (its hull's pressure carries it, or nothing does): not balanced at rest


def restoring(scene, floating, params: dict, g, key: str, place=None) -> Restoring:
    """The restoring of a floating body, the vessel's and every `[[bodies]]` body's by the same rule
    (`key`: its params' prefix, "vessel" or "bodies.<name>"; `place`: a body's rest (x, y), where
    the waves reach its hull): the pressure on its wetted hull with its nonlinear hydrostatics
    (`hull_term`; its weight then a term, `weighs`), the linear springs about its rest pose with
    linear ones (its weight balanced by the buoyancy at rest); with `[effects] buoyancy` off, none,
    its weight balanced as at rest (nothing holds it up nor pulls it down); without a hydrostatics
    table (the vessel only) none, and it falls under its weight."""
    hs = floating.hydrostatics
    if hs is None:
        return Restoring((), True)
    if not scene.effects.buoyancy:
        return Restoring((), False)
    if hull_pressure(scene, floating):
        return Restoring((hull_term(scene, floating.hull, params, g, f"{key}.hull", place),), True)
    P = params.get
    return Restoring((linear_hydrostatics(hs, P("environment.water_density", scene.environment.water_density), g,
                                          lambda k, v: P(f"{key}.hydrostatics.{k}", v)),), False)


def linear_hydrostatics(h, rho_w, g, value=lambda key, v: v) -> AbstractRestoring:
    """The linear restoring term of a `hydrostatics` table (the vessel's or a body's); `value(name,
    v)` may replace a value (traced params)."""
    f = lambda k, v: jnp.asarray(value(k, v), dtype=float)  # noqa: E731
    return RESTORING_FORMS[h.moment](rho_w=jnp.asarray(rho_w, dtype=float), gravity=g,
                waterplane_area=f("waterplane_area", h.waterplane_area),
                displaced_volume=f("displaced_volume", h.displaced_volume), gm_t=f("gm_t", h.gm_t),
                gm_l=f("gm_l", h.gm_l))


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


def body_restoring(scene, body, params: dict, g, liquid=None, mass=None, S=None) -> tuple:
    """A `[[bodies]]` body's restoring terms (`restoring`, the vessel's rule) with its weight where
    it weighs: the liquid of its tanks (`liquid`, elastic walls included) included; `mass` and `S`
    the hull's own mass and first moment where elastic walls carry theirs (default: the body's
    mass, none)."""
    key = f"bodies.{body.name}"
    r = restoring(scene, body, params, g, key, body.position)
    if not r.weighs:
        return r.terms
    mass = jnp.asarray(params.get(f"{key}.mass", body.mass) if mass is None else mass, dtype=float)
    weight = About(("gravity", f"the weight of the body {body.name!r} and its liquid, borne by its hull's pressure"))
    return r.terms + (weight_term(mass, S, liquid, g, weight),)


def weight_term(mass, S, liquid, g, about: About) -> Weight:
    """A floating body's weight with the liquid it carries (`liquid`, None: none), the vessel's and a
    body's alike: `mass` and `S` its hull's own (S None: its COG at the frame origin)."""
    if liquid is not None:
        S = liquid.rigid_first_moment() if S is None else S + liquid.rigid_first_moment()
        mass = mass + liquid.total_mass()
    return Weight(mass=mass, S=jnp.zeros(3) if S is None else S, gravity=g, about=about)


def restoring_words(scene, body) -> str:
    """A body's restoring in words (its line in `jaxslosh check`), as `restoring` chooses it."""
    h = body.hydrostatics
    if not scene.effects.buoyancy:
        return "no hydrostatics ([effects] buoyancy off)"
    if not h.nonlinear:
        return f"linear hydrostatics (A_w {h.waterplane_area:g} m^2, GM_T {h.gm_t:g} m, GM_L {h.gm_l:g} m)"
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
