"""Response amplitude operators of the coupled vessel (docs/guide/frequency-domain.md): the linearised scene
(linear.py) in regular waves of unit amplitude,

    [K - w^2 (M - A_inf + A(w)) + i w (C + B(w))] X = F(w, beta),      x(t) = Re(X e^{i w t}),

with A(w), B(w) the hull's radiation tables interpolated linearly in w (not the time domain's
memory fit, whose error is the time domain's), A_inf the added mass the residual carries on the
vessel's rows, and F the wave excitation on them (the tables interpolated in w and heading, or
Froude-Krylov on the box hull) for eta = cos(w t) at the COG's rest position. X holds the vessel's
six dofs (m/m, rad/m; rotations about the COG in body axes, equal to roll, pitch, yaw at first
order) and every unknown of the liquid and structures; the probes' RAOs are their inertial
displacements (the result file's `displacement`) per unit amplitude.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np

from ..assemble.bodyhydro import frequency_terms
from ..assemble.hull import froude_krylov_hull, hull_pressure
from ..hydro.source import excitation_at, tables_of
from ..hydro.tables import interpolate_radiation
from ..physics.bodies import BAND, body_rest
from ..scene.types import Scene, SceneError
from ..run.simulate import is_traced
from .linear import Linearisation, linearise

#: the default frequencies without radiation tables (rad/s): the band of ship motions and of the
#: first sloshing modes of ship tanks
DEFAULT_BAND = (0.1, 4.0)
DEFAULT_COUNT = 200


class RAO(NamedTuple):
    frequency: np.ndarray      # (f,) rad/s
    heading: np.ndarray        # (h,) rad
    vessel: np.ndarray         # (f, h, 6) complex: surge, sway, heave (m/m), roll, pitch, yaw (rad/m)
    probes: dict               # name -> (f, h, 3) complex (m/m)
    scene_text: str = ""
    bodies: Optional[dict] = None   # [[bodies]]: name -> (f, h, 6) complex, as `vessel`


class Hydro(NamedTuple):
    """The hull's frequency-domain data for a scene: radiation tables (or None) and excitation."""
    tables: object
    radiation: bool


def hull_tables(scene: Scene, headings):
    """The scene's hydrodynamic tables (Capytaine's for these headings where it says so), or None."""
    hd, env = scene.vessel.hydrodynamics, scene.environment
    if hd is None:
        return None
    depth = scene.waves.depth if scene.waves is not None else None
    return tables_of(hd, scene.vessel.hull, env.water_density, env.gravity, depth, tuple(float(b) for b in headings))


def default_headings(scene: Scene, tables=None):
    if scene.waves is not None:
        return np.array([scene.waves.heading])
    if tables is not None and tables.headings is not None:
        return np.asarray(tables.headings, dtype=float)
    return np.array([0.0, np.pi / 2, np.pi])


def _check(scene: Scene, tables, radiation, w, heads):
    if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise SceneError("frequencies", "must be positive finite numbers (rad/s)")
    if radiation:
        lo, hi = tables.omega[0], tables.omega[-1]
        if w.min() < lo - 1e-9 or w.max() > hi + 1e-9:
            raise SceneError("frequencies", f"[{w.min():.6g}, {w.max():.6g}] rad/s reaches beyond the radiation "
                                            f"tables' [{lo:.6g}, {hi:.6g}] rad/s (vessel.hydrodynamics.frequencies)")
    hd = scene.vessel.hydrodynamics
    if tables is not None and tables.excitation is not None and (hd is None or hd.excitation != "froude-krylov"):
        th = np.asarray(tables.headings, dtype=float)
        for b in heads:
            if (th.size == 1 and abs(b - th[0]) > 1e-6) or not th[0] - 1e-6 <= b <= th[-1] + 1e-6:
                raise SceneError("headings", f"{b:.6g} rad lies outside the excitation tables' headings "
                                             f"{np.round(th, 6).tolist()} rad")
        lo, hi = tables.omega[0], tables.omega[-1]
        if w.min() < lo - 1e-9 or w.max() > hi + 1e-9:
            raise SceneError("frequencies", f"[{w.min():.6g}, {w.max():.6g}] rad/s reaches beyond the excitation "
                                            f"tables' [{lo:.6g}, {hi:.6g}] rad/s")


def across_tank_warnings(scene: Scene, headings) -> list:
    """One line per tank whose liquid leaves out what seas not along the ship drive, when some heading
    is not (sin(heading) not zero), as its form says it (scene/liquids.py `across_seas_warning`): a
    multimodal tank with `flow = "2d"` sloshes only along its length (the vessel's x), so the sway,
    roll and yaw those seas drive leave its liquid turning with the tank, without the transverse
    waves' free-surface effect; `flow = "3d"` (a box) holds waves across it too."""
    heads = np.atleast_1d(np.asarray(headings, dtype=float))
    across = heads[np.abs(np.sin(heads)) > 1e-9]
    if across.size == 0:
        return []
    shown = ", ".join(f"{np.degrees(b):.0f}" for b in across[:4]) + (", ..." if across.size > 4 else "")
    return [f"tanks[{i}] {t.name!r}: {why}" for i, t in enumerate(scene.tanks)
            if (why := t.form.across_seas_warning(shown))]


def contact_warnings(scene: Scene) -> list:
    """One line per hawser or fender that sits at rest within its contact's smoothing band
    (physics/bodies.py BAND, docs/guide/bodies-and-connections.md): the RAOs, linear about rest,
    see there the smoothing's stiffness, between none and the connection's own (3/8 of it at its
    length), where the rope is neither slack nor taut; a pretension or a gap beyond the band decides."""
    cog = scene.vessel.cog_height
    rest = {b.name: (body_rest(b, cog), b.heading) for b in scene.bodies}

    def at_rest(end, p):           # the vessel at rest: its COG the origin, level; a fixed point as given
        if end not in rest:
            return np.asarray(p, dtype=float)
        X, psi = rest[end]
        c, s = np.cos(psi), np.sin(psi)
        return X + np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.asarray(p, dtype=float)
    inside = []
    for i, c in enumerate(scene.connections):
        e = np.linalg.norm(at_rest(c.ends[1], c.points[1]) - at_rest(c.ends[0], c.points[0])) - c.length
        if c.kind != "spring" and abs(e) < 0.5 * BAND:
            inside.append(f"{c.name!r} ({c.kind}, {1e3 * e:+.3f} mm)")
    if not inside:
        return []
    return [f"{len(inside)} connection(s) at rest within their contact's smoothing band (+-{500 * BAND:g} mm from "
            f"their length): {', '.join(inside)}; the RAOs, linear about rest, see the smoothing's stiffness "
            "there (3/8 of their own at their length); a pretension or a gap beyond the band gives them their own "
            "stiffness or none"]


def default_frequencies(scene: Scene, tables=None, radiation=None, count: int = DEFAULT_COUNT):
    if radiation is None:
        radiation = scene.effects.radiation and tables is not None and tables.added_mass is not None
    if radiation or (tables is not None and tables.excitation is not None):
        return np.linspace(tables.omega[0], tables.omega[-1], count)
    return np.linspace(*DEFAULT_BAND, count)


def solve_equilibrated(Z, F):
    """Z X = F with rows and columns scaled to unit max norm first: the acoustic rows of the liquid
    are 1e10 times the vessel's, and the interface rows of structures carry no inertia. A traced Z
    (a gradient through the RAOs) is solved by JAX; the scaling, which leaves X as it is, carries
    no gradient."""
    if is_traced(Z):
        r = jax.lax.stop_gradient(1.0 / jnp.maximum(jnp.abs(Z).max(axis=1), 1e-300))
        Zr = Z * r[:, None]
        c = jax.lax.stop_gradient(1.0 / jnp.maximum(jnp.abs(Zr).max(axis=0), 1e-300))
        return c[:, None] * jnp.linalg.solve(Zr * c[None, :], F * r[:, None])
    r = 1.0 / np.maximum(np.abs(Z).max(axis=1), 1e-300)
    Zr = Z * r[:, None]
    c = 1.0 / np.maximum(np.abs(Zr).max(axis=0), 1e-300)
    return c[:, None] * np.linalg.solve(Zr * c[None, :], F * r[:, None])


def frequency_matrices(lin: Linearisation, tables, radiation: bool, w):
    """(M(w), C(w)) of the coupled system at frequency w: the radiation tables' A(w) in place of
    the A_inf the residual carries, B(w) added, on the vessel's rows and columns (new arrays)."""
    if not radiation:
        return lin.M.copy(), lin.C.copy()
    A, B = interpolate_radiation(tables, [w])
    dM, dC = np.zeros(lin.M.shape), np.zeros(lin.C.shape)
    dM[:6, :6] = A[0] - lin.added_mass_infinite
    dC[:6, :6] = B[0]
    return lin.M + dM, lin.C + dC


def rao(scene: Scene, frequencies=None, headings=None, *, params=None,
        linearisation: Optional[Linearisation] = None) -> RAO:
    """Complex RAOs of the vessel's six dofs and every probe over `frequencies` (rad/s; default:
    the radiation tables' range, else 0.1 to 4 rad/s) and `headings` (rad, the direction the waves
    travel to; default the scene's wave heading, else the excitation tables', else 0, pi/2, pi).
    Input the frequency domain cannot take raises SceneError naming it. With traced `params`
    (traceable scene keys, under jax.grad or jax.jit) the RAOs are JAX values: a function of them
    can be differentiated with respect to those params."""
    env, ves = scene.environment, scene.vessel
    heads = None if headings is None else np.atleast_1d(np.asarray(headings, dtype=float))
    tables = hull_tables(scene, heads if heads is not None else
                         (() if scene.waves is None else (scene.waves.heading,)))
    if heads is None:
        heads = default_headings(scene, tables)
    radiation = bool(scene.effects.radiation and tables is not None and tables.added_mass is not None)
    w = default_frequencies(scene, tables, radiation) if frequencies is None else \
        np.atleast_1d(np.asarray(frequencies, dtype=float))
    _check(scene, tables, radiation, w, heads)
    depth = scene.waves.depth if scene.waves is not None else None
    X = [excitation_at(ves.hydrodynamics, ves.hull, tables, w, b, env.water_density, env.gravity, depth)
         for b in heads]
    if X[0] is None and hull_pressure(scene):
        # Froude-Krylov on the wetted surface of a mesh hull: the small-wave limit of the incident
        # pressure that the nonlinear hydrostatics integrate (assemble/hull.py), as a run takes it
        X = [froude_krylov_hull(scene, w, np.full(w.shape, b)) for b in heads]
    if X[0] is None:
        raise SceneError("vessel.hull", "the RAO needs the wave forces: a box [vessel.hull] (Froude-Krylov) or "
                                        "excitation tables in [vessel.hydrodynamics] (or capytaine = true)")
    X = np.stack(X, axis=1)                                  # (f, h, 6)
    lin = linearisation if linearisation is not None else linearise(scene, params)
    n = lin.n
    F = np.zeros((w.size, n, heads.size), dtype=complex)
    F[:, :6] = X.transpose(0, 2, 1)
    N = 6 + 6 * len(scene.bodies)
    dA = dB = None
    if scene.bodies:           # the bodies' excitation and radiation (assemble/bodyhydro.py)
        dA, dB, Fb = frequency_terms(scene, w, heads)
        F[:, 6:N] += Fb[:, :, 6:].transpose(0, 2, 1)
    if is_traced((lin.M, lin.C, lin.K)):
        out, xp = _traced_solves(lin, tables, radiation, w, F, dA, dB), jnp
    else:
        out, xp = np.zeros((w.size, heads.size, n), dtype=complex), np
        for i, wi in enumerate(w):
            M, C = frequency_matrices(lin, tables, radiation, wi)
            if scene.bodies:
                M[:N, :N] += dA[i]
                C[:N, :N] += dB[i]
            out[i] = solve_equilibrated(lin.K - wi * wi * M + 1j * wi * C, F[i]).T
    probes = {name: xp.einsum("cn,fhn->fhc", lin.probes[k], out) for k, name in enumerate(lin.probe_names)}
    bodies = {b.name: out[:, :, 6 + 6 * s:12 + 6 * s] for s, b in enumerate(scene.bodies)}
    return RAO(w, heads, out[:, :, :6], probes, scene.text, bodies)


def _traced_solves(lin: Linearisation, tables, radiation: bool, w, F, bodies_A=None, bodies_B=None):
    """The RAOs (f, h, n) of a linearisation whose matrices are traced (a gradient through them):
    one solve per frequency in a lax.map, so that the compiled program does not grow with the
    number of frequencies. The frequency-dependent radiation is the concrete path's: the vessel's
    tables on its rows and the bodies' (`bodies_A`, `bodies_B`: frequency_terms', (f, N, N) over
    the N rigid dofs) added, from the scene's values."""
    N = 6 if bodies_A is None else bodies_A.shape[1]
    dA, dB = np.zeros((w.size, N, N)), np.zeros((w.size, N, N))
    if radiation:
        A, B = interpolate_radiation(tables, w)
        dA[:, :6, :6], dB[:, :6, :6] = np.asarray(A) - lin.added_mass_infinite[None], np.asarray(B)
    if bodies_A is not None:
        dA, dB = dA + bodies_A, dB + bodies_B

    def one(args):
        wi, dAi, dBi, Fi = args
        Z = lin.K - wi * wi * lin.M + 1j * wi * lin.C
        Z = Z.at[:N, :N].add(-wi * wi * dAi + 1j * wi * dBi)
        return solve_equilibrated(Z, Fi).T

    return jax.lax.map(one, (jnp.asarray(w), jnp.asarray(dA), jnp.asarray(dB), jnp.asarray(F)))
