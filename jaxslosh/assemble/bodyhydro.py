"""The hydrodynamics of `[[bodies]]` (docs/guide/bodies-and-connections.md): each body's tables or
file (the vessel's keys, read by the vessel's reader), and a multibody file that couples the
bodies' radiation and diffraction, as host-side sources over the rigid dofs of the vessel and the
bodies (6 + 6 S: the vessel's six, then six per body, the step's order).

A source is a set of tables over d of those dofs, in the axes they were computed in:

* one body's own tables (`axes = "body"`): its dofs along its own axes about its COG, the wave
  heading relative to its x axis, phases from its COG. The rows of the step hold translations in
  inertial axes and rotations in body axes, so with T = diag(R^T, I) (R its heading's rotation)
  the step's A is T^T A T, its X T^T X(beta - heading) e^{-i k (x cos beta + y sin beta)}, (x, y)
  its COG at rest from the vessel's;
* a multibody file (`axes = "global"`): every body's dofs along the file's (the scene's inertial)
  axes about its own COG, phases from the file's origin (the vessel's COG), so T = diag(I, R) (the
  rotations' body axes from the inertial ones). The vessel's own 6 x 6 block stays with its own
  terms (assemble/seakeeping.py reads it from the same file): the source skips it.

The same functions then serve the time domain (A_inf and the memory fitted by hydro/radiation.py
over all the source's dofs: the memory kernels between bodies are its off-diagonal columns) and
the frequency domain (A(w) - A_inf and B(w) interpolated, analysis/rao.py).
"""
from __future__ import annotations

import os
from typing import NamedTuple, Optional

import numpy as np

from ..hydro.multibody import read_multibody
from ..scene.bodies import coupled_file, resolve
from ..hydro.radiation import fit_radiation
from ..hydro.source import tables_of
from ..hydro.spectra import components, wavenumber
from ..hydro.tables import Tables, interpolate_excitation, interpolate_radiation
from ..physics.seakeeping import Memory
from .hull import froude_krylov_surface
from ..scene.types import SceneError
from ..staging import on_device


class Source(NamedTuple):
    index: tuple            # (d,) the rigid dofs (of 6 + 6 S) the tables' rows and columns are
    tables: Tables
    T: np.ndarray           # (d, d) the step's dofs -> the tables'
    origin: tuple           # (x, y) m, the tables' phase origin from the vessel's COG at rest
    headings: tuple         # per body of the source, rad (its x axis from the inertial X)
    axes: str               # "body" | "global"
    skip: np.ndarray        # (d, d) bool: entries the vessel's own terms carry
    key: tuple              # hashable: what the fit's cache is keyed on
    warnings: tuple = ()


def _rz(psi):
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def transform(headings, axes: str) -> np.ndarray:
    """T (6 n, 6 n): the step's dofs (translations inertial, rotations body) -> the tables'."""
    n = len(headings)
    T = np.eye(6 * n)
    for k, psi in enumerate(headings):
        R = _rz(psi)
        if axes == "body":
            T[6 * k:6 * k + 3, 6 * k:6 * k + 3] = R.T
        else:
            T[6 * k + 3:6 * k + 6, 6 * k + 3:6 * k + 6] = R
    return T


def sources(scene) -> list:
    """The hydrodynamic sources of the scene's bodies (not the vessel's own tables)."""
    env = scene.environment
    names = [scene.vessel.name] + [b.name for b in scene.bodies]
    heading = [0.0] + [b.heading for b in scene.bodies]
    out = []
    coupled = coupled_file(scene.vessel, scene.bodies)
    members = set()
    if coupled is not None:
        path, inside, key = coupled
        for i, b in enumerate(scene.bodies):
            hd = b.hydrodynamics
            if b.name in inside and hd is not None and hd.file and os.path.abspath(resolve(hd)) != os.path.abspath(path):
                raise SceneError(f"bodies[{i}].hydrodynamics.file", f"{b.name!r} is in {path} (coupled); name that "
                                                                    "file or leave `file` out")
        mb = read_multibody(path, inside, env.water_density, env.gravity)
        index = tuple(6 * names.index(n) + k for n in inside for k in range(6))
        skip = np.zeros((len(index),) * 2, dtype=bool)
        if scene.vessel.name in inside and scene.vessel.hydrodynamics is not None \
                and scene.vessel.hydrodynamics.file:
            v = 6 * inside.index(scene.vessel.name)
            skip[v:v + 6, v:v + 6] = True
        heads = tuple(heading[names.index(n)] for n in inside)
        out.append(Source(index, mb.tables, transform(heads, "global"), (0.0, 0.0), heads, "global", skip,
                          (path, inside, heads, bool(skip.any())), mb.warnings))
        members = set(inside)
    for s, b in enumerate(scene.bodies):
        hd = b.hydrodynamics
        if b.name in members or hd is None or not (hd.added_mass is not None or hd.excitation_amplitude is not None):
            continue
        t = tables_of(hd, None, env.water_density, env.gravity)
        out.append(Source(tuple(range(6 + 6 * s, 12 + 6 * s)), t, transform((b.heading,), "body"), b.position,
                          (b.heading,), "body", np.zeros((6, 6), dtype=bool), (hd, b.heading)))
    return out


def _rotate(T, A):
    return np.einsum("ki,...kl,lj->...ij", T, A, T)


#: fits by source key (a file's path, bodies and headings; a body's tables and heading): a fit is
#: seconds, and every build, linearisation and RAO of a scene asks for it
_FITS: dict = {}


def source_fit(src: Source):
    """The source's radiation memory fit in the step's dofs (cached per source), or None without
    radiation tables."""
    t = src.tables
    if t.added_mass is None:
        return None
    if src.key not in _FITS:
        if len(_FITS) > 32:
            _FITS.clear()
        _FITS[src.key] = fit_radiation(t.omega, _rotate(src.T, t.added_mass), _rotate(src.T, t.damping),
                                       None if t.added_mass_infinite is None else _rotate(src.T, t.added_mass_infinite),
                                       skip=src.skip)
    return _FITS[src.key]


def hull_share(scene, body, omega, heads) -> np.ndarray:
    """X (n, 6) in the step's axes, phases from the vessel's COG at rest: the linear Froude-Krylov
    force of the waves (frequencies `omega`, headings `heads`, (n,) each) on a body's wetted hull at
    rest, which its nonlinear hydrostatics integrate themselves (physics/hull.py): a run's tables
    keep only the rest (diffraction), as the vessel's do (assemble/seakeeping.py
    linear_excitation_rao), and a body without tables gets it in the frequency domain."""
    waves, env, hull = scene.waves, scene.environment, body.hull
    depth = None if waves is None else waves.depth
    heads = np.broadcast_to(np.asarray(heads, dtype=float), np.shape(omega))
    Xb = froude_krylov_surface(hull.triangles(hull.divisions(waves)), hull.water_height(), omega,
                               heads - body.heading, env.water_density, env.gravity, depth)
    return _placed(scene, body, Xb, omega, heads)


def _placed(scene, body, Xb, omega, heads) -> np.ndarray:
    """X (n, 6) of a body's own axes and COG -> the step's axes, phases from the vessel's COG at rest."""
    Xs = np.concatenate([Xb[:, :3] @ _rz(body.heading).T, Xb[:, 3:]], axis=1)    # forces in inertial axes
    k = wavenumber(np.asarray(omega, dtype=float), scene.environment.gravity,
                   None if scene.waves is None else scene.waves.depth)
    x, y = body.position
    return Xs * np.exp(-1j * k * (x * np.cos(heads) + y * np.sin(heads)))[:, None]


def on_hull(scene, body) -> bool:
    """Whether the waves act on a body's wetted hull (its nonlinear hydrostatics, buoyancy and waves on)."""
    return body.hydrostatics.nonlinear and scene.effects.buoyancy and scene.effects.waves


def box_waves(body) -> Optional[str]:
    """How the closed-form Froude-Krylov force of a body's box hull makes its wave force, as the
    vessel's does (hydro/source.py excitation_at): "only" where its `[bodies.hydrodynamics]
    excitation` says "froude-krylov", "unless tabled" by default (where no table, its own or a
    multibody file's, gives it an excitation); None where it does not: no box hull, `excitation =
    "table"`, or its nonlinear hydrostatics, which integrate the incident pressure on the hull
    themselves (hull_share)."""
    if body.hull is None or not body.hull.closed_form or body.hydrostatics.nonlinear:
        return None
    source = "auto" if body.hydrodynamics is None else body.hydrodynamics.excitation
    return {"froude-krylov": "only", "auto": "unless tabled"}.get(source)


def box_share(scene, body, omega, heads) -> np.ndarray:
    """X (n, 6) in the step's axes, phases from the vessel's COG at rest: the Froude-Krylov force of
    the waves (frequencies `omega`, headings `heads`, (n,) each) on a body's box hull, in closed form
    (hydro/box.py), the vessel's with a box hull and linear hydrostatics."""
    env, depth = scene.environment, None if scene.waves is None else scene.waves.depth
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    heads = np.broadcast_to(np.asarray(heads, dtype=float), w.shape)
    Xb = np.zeros((w.size, 6), dtype=complex)
    for beta in np.unique(heads):
        m = heads == beta
        Xb[m] = body.hull.froude_krylov(w[m], float(beta) - body.heading, env.water_density, env.gravity, depth)
    return _placed(scene, body, Xb, w, heads)


def _with_box(scene, body, X, omega, heads):
    """A body's X (n, 6) from the sources, with its box hull's Froude-Krylov force where box_waves says so."""
    how = box_waves(body)
    if how == "only" or (how == "unless tabled" and not np.abs(X).max(initial=0.0) > 0):
        return box_share(scene, body, omega, heads)
    return X


def excitation(src: Source, omega, beta, g, depth=None) -> np.ndarray:
    """X (n, d) in the step's dofs per unit wave amplitude at the vessel's COG, waves heading beta."""
    t = src.tables
    d = len(src.index)
    if t.excitation is None:
        return np.zeros((np.size(omega), d), dtype=complex)
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    rel = beta - src.headings[0] if src.axes == "body" else beta
    heads = np.asarray(t.headings, dtype=float)
    near = [r for r in (rel - 2 * np.pi, rel, rel + 2 * np.pi) if heads[0] - 1e-6 <= r <= heads[-1] + 1e-6]
    if not near:
        raise SceneError("headings", f"{beta:.6g} rad is {rel:.6g} rad in the axes of a body's excitation tables, "
                                     f"outside their headings {np.round(heads, 6).tolist()} rad")
    X = interpolate_excitation(t, w, near[0])
    k = wavenumber(w, g, depth)
    shift = np.exp(-1j * k * (src.origin[0] * np.cos(beta) + src.origin[1] * np.sin(beta)))
    return (X @ src.T) * shift[:, None]


def radiation(src: Source, omega):
    """(A(w) - A_inf of the fit, B(w)) (n, d, d) in the step's dofs, the skipped entries zero."""
    A, B = interpolate_radiation(src.tables, omega)
    A, B = _rotate(src.T, A), _rotate(src.T, B)
    fit = source_fit(src)
    A = A - fit.added_mass_infinite[None]
    A[:, src.skip], B[:, src.skip] = 0.0, 0.0
    return A, B


def radiating_bodies(scene) -> Optional[tuple]:
    """(lowest, highest) frequency of the bodies' radiation tables, or None without any."""
    if not scene.effects.radiation or not scene.bodies:
        return None
    w = [src.tables.omega for src in sources(scene) if src.tables.added_mass is not None]
    return (max(x[0] for x in w), min(x[-1] for x in w)) if w else None


def rigid_size(scene) -> int:
    return 6 + 6 * len(scene.bodies)


def frequency_terms(scene, omega, headings):
    """(dA (f, N, N), B (f, N, N), F (f, h, N)) of the bodies' sources over the N rigid dofs: what the
    frequency domain adds to the linearised scene (its M holds each fit's A_inf)."""
    N, w = rigid_size(scene), np.atleast_1d(np.asarray(omega, dtype=float))
    dA, B = np.zeros((w.size, N, N)), np.zeros((w.size, N, N))
    F = np.zeros((w.size, len(headings), N), dtype=complex)
    depth = scene.waves.depth if scene.waves is not None else None
    for src in sources(scene):
        ix = np.asarray(src.index)
        if src.tables.added_mass is not None and scene.effects.radiation:
            a, b = radiation(src, w)
            dA[:, ix[:, None], ix[None, :]] += a
            B[:, ix[:, None], ix[None, :]] += b
        for h, beta in enumerate(headings):
            X = excitation(src, w, float(beta), scene.environment.gravity, depth)
            X[:, ix < 6] = 0.0             # the vessel's own columns: its own terms' (rao.py)
            F[:, h, ix] += X
    for s, b in enumerate(scene.bodies):
        # a body without tables whose hull takes the waves: the small-wave limit of that pressure, as a run has it
        if on_hull(scene, b) and not np.abs(F[:, :, 6 + 6 * s:12 + 6 * s]).max(initial=0.0) > 0:
            for h, beta in enumerate(headings):
                F[:, h, 6 + 6 * s:12 + 6 * s] = hull_share(scene, b, w, np.full(w.shape, float(beta)))
        for h, beta in enumerate(headings):      # a box hull on linear springs: its Froude-Krylov force
            F[:, h, 6 + 6 * s:12 + 6 * s] = _with_box(scene, b, F[:, h, 6 + 6 * s:12 + 6 * s], w, float(beta))
    return dA, B, F


def time_terms(scene, params: dict):
    """(A_inf (N, N), Memory over the N rigid dofs or None, per-body X at the sea's components
    (S, n_c, 6) or None) of the bodies' sources, for physics/bodies.py."""
    N, S = rigid_size(scene), len(scene.bodies)
    Ainf = np.zeros((N, N))
    poles, sel, cs = [], [], []
    waves, eff = scene.waves, scene.effects
    X = None
    if waves is not None and eff.waves:
        c = components(waves)
        X = np.zeros((S, c.omega.size, 6), dtype=complex)
    for src in sources(scene):
        ix = np.asarray(src.index)
        fit = source_fit(src) if eff.radiation else None
        if fit is not None:
            Ainf[ix[:, None], ix[None, :]] += fit.added_mass_infinite
            poles.append(fit.p)
            sel.append(ix[fit.inp])
            cs.append(np.zeros((N, fit.p.size), dtype=complex))
            cs[-1][ix] = fit.c
        if X is not None:
            heads = np.full(c.omega.shape, waves.heading) if c.headings is None else np.asarray(c.headings)
            for beta in np.unique(heads):
                m = heads == beta
                Xs = excitation(src, c.omega[m], float(beta), scene.environment.gravity, waves.depth)
                for k, i in enumerate(src.index[::6]):
                    if i >= 6:                   # the vessel's own columns are its own terms'
                        X[i // 6 - 1, m] += Xs[:, 6 * k:6 * k + 6]
    if X is not None:
        for s, b in enumerate(scene.bodies):
            heads = waves.heading if c.headings is None else c.headings
            if np.abs(X[s]).max() > 0 and on_hull(scene, b):
                X[s] -= hull_share(scene, b, c.omega, heads)
            X[s] = _with_box(scene, b, X[s], c.omega, heads)     # a box hull on linear springs
    memory = None
    if poles and sum(p.size for p in poles):
        p = np.concatenate(poles)
        s = np.zeros((p.size, N))
        s[np.arange(p.size), np.concatenate(sel)] = 1.0
        c_all = np.concatenate(cs, axis=1)
        memory = Memory(on_device(p.real), on_device(p.imag), on_device(s), on_device(c_all.real),
                        on_device(c_all.imag))
    return Ainf, memory, X
