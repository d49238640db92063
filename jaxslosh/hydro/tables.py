"""Hydrodynamic tables about the COG, as a scene writes them (`[vessel.hydrodynamics]`)."""
from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np


class Tables(NamedTuple):
    """Hydrodynamic tables about the COG: frequencies (n,), added mass and damping (n, 6, 6),
    A_inf (6, 6) or None, headings (h,), excitation X (n, h, 6) complex (our convention, see
    waves.py) or None."""
    omega: np.ndarray
    added_mass: Optional[np.ndarray]
    damping: Optional[np.ndarray]
    added_mass_infinite: Optional[np.ndarray]
    headings: Optional[np.ndarray]
    excitation: Optional[np.ndarray]


def _full(x, n):
    """A table given per frequency as 6 values (diagonal) or 6 x 6 -> (n, 6, 6)."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 2:
        out = np.zeros((n, 6, 6))
        out[:, range(6), range(6)] = a
        return out
    return a


def matrix6(x):
    a = np.asarray(x, dtype=float)
    return np.diag(a) if a.ndim == 1 else a


def scene_tables(hd) -> Tables:
    """The tables of a `[vessel.hydrodynamics]` (scene.types.Hydrodynamics) as written (for
    `capytaine = true`, see `source.tables_of`)."""
    n = len(hd.frequencies)
    w = np.asarray(hd.frequencies, dtype=float)
    A = _full(hd.added_mass, n) if hd.added_mass is not None else None
    B = _full(hd.damping, n) if hd.damping is not None else None
    Ainf = matrix6(hd.added_mass_infinite) if hd.added_mass_infinite is not None else None
    X = None
    heads = None
    if hd.excitation_amplitude is not None:
        amp = np.asarray(hd.excitation_amplitude, dtype=float)
        ph = np.asarray(hd.excitation_phase, dtype=float)
        if amp.ndim == 2:
            amp, ph = amp[:, None, :], ph[:, None, :]
        X = amp * np.exp(1j * ph)
        heads = np.atleast_1d(np.asarray(hd.headings, dtype=float))
    return Tables(w, A, B, Ainf, heads, X)


def interpolate_excitation(tables: Tables, omega, heading):
    """X (N, 6) at the components' frequencies and the wave heading: linear in w and in heading on
    the complex values; zero outside the tabulated frequencies."""
    w = np.asarray(omega, dtype=float)
    X = tables.excitation
    heads = tables.headings
    if heads.size == 1:
        Xh = X[:, 0, :]
    else:
        Xh = np.zeros(X.shape[:1] + X.shape[2:], dtype=complex)
        for j in range(X.shape[2]):
            for i in range(X.shape[0]):
                Xh[i, j] = np.interp(heading, heads, X[i, :, j].real) + 1j * np.interp(heading, heads, X[i, :, j].imag)
    out = np.zeros((w.size, X.shape[2]), dtype=complex)
    inside = (w >= tables.omega[0] - 1e-12) & (w <= tables.omega[-1] + 1e-12)
    for j in range(X.shape[2]):
        out[:, j] = (np.interp(w, tables.omega, Xh[:, j].real) + 1j * np.interp(w, tables.omega, Xh[:, j].imag))
    return out * inside[:, None]


def interpolate_radiation(tables: Tables, omega):
    """A(w), B(w) (N, 6, 6) at frequencies omega, linear in w between the tabulated ones (inside
    their range only: the caller checks it)."""
    w = np.asarray(omega, dtype=float)
    d = tables.added_mass.shape[1]
    A = np.zeros((w.size, d, d))
    B = np.zeros((w.size, d, d))
    for i in range(d):
        for j in range(d):
            A[:, i, j] = np.interp(w, tables.omega, tables.added_mass[:, i, j])
            B[:, i, j] = np.interp(w, tables.omega, tables.damping[:, i, j])
    return A, B
