"""What the run's validity watch (run/validity.py) reads of a multimodal tank's free surface: its
slope, its crest index and its round-off floor (steep.py), at the points and weights the liquid
uses; and the tank in `jaxslosh check`'s words (liquid.py MultimodalLiquid's lines)."""
from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np

from ..words import TankWords, shape_words
from .build3d import tank_3d, three_dimensional
from .modes import modal_modes
from .steep import STEEP_MODES
from .term import NX

#: points per two-dimensional tank where the slope is read (walls included)
SLOPE_SAMPLES = 65


class SurfaceTable(NamedTuple):
    """One multimodal tank's tables for the validity watch."""
    slope: tuple          # the slope's rows (P, modes), or its x and y rows for a three-dimensional tank
    Z: np.ndarray         # (Q, modes) the elevation's rows at the liquid's quadrature points
    w: np.ndarray         # (Q,) their weights
    kN: float             # the highest mode's wavenumber
    omega2: float         # its omega^2 = g k tanh(k h)
    # the steepness cut: (modes, k, omega^2) of the highest mode whose rows a two-dimensional tank on
    # more than STEEP_MODES modes keeps past STEEP_FULL (steep.steep_rows; its round-off floor is then
    # that mode's, steep.roundoff_floor); None where its rows keep every mode
    cut: Optional[tuple] = None


def omega2(g: float, t, k) -> float:
    """omega^2 = g k tanh(k h) of a wave of wavenumber k in the tank's depth."""
    return float(g * k * np.tanh(k * t.fill_depth))


def surface_table(t, g: float) -> SurfaceTable:
    """The tank's tables, at the points and weights the liquid uses (tank3d.py's, or term.py's NX)."""
    if three_dimensional(t):
        mt = tank_3d(t, t.fill_depth, t.fluid.density)
        F, Fx, Fy = (np.asarray(a) for a in (mt.F, mt.Fx, mt.Fy))
        kN = float(np.max(np.asarray(mt.k)))
        return SurfaceTable((Fx, Fy), F, np.asarray(mt.wq), kN, omega2(g, t, kN))
    k = np.arange(1, t.modes + 1) * np.pi / t.size[0]
    xg, wg = np.polynomial.legendre.leggauss(max(NX, 8 * t.modes))
    xq = 0.5 * t.size[0] * (xg + 1.0)
    kc = STEEP_MODES * np.pi / t.size[0]
    cut = (STEEP_MODES, kc, omega2(g, t, kc)) if t.modes > STEEP_MODES else None
    return SurfaceTable((-k * np.sin(np.outer(np.linspace(0.0, t.size[0], SLOPE_SAMPLES), k)),),
                        np.cos(np.outer(xq, k)), 0.5 * t.size[0] * wg, float(k[-1]), omega2(g, t, k[-1]), cut)


def modal_words(t) -> str:
    """What a multimodal tank is instead of a mesh: its free-surface modes."""
    n = len(modal_modes(t))
    if not t.form.three_dimensional:
        return f"{n} free-surface modes cos(i pi x / L), i = 1..{n} (multimodal, two-dimensional along x), no mesh"
    done = f", {t.modes} asked and completed to whole degenerate pairs" if n != t.modes else ""
    return (f"{n} free-surface modes of its {'disk' if t.geometry.name == 'cylinder' else 'rectangular'} base "
            f"(multimodal, three-dimensional{done}), no mesh")


def multimodal_words(t) -> TankWords:
    """The tank's liquid in words (liquid/words.py TankWords): its modes; its walls are rigid."""
    flow = "three-dimensional" if t.form.three_dimensional else "two-dimensional along x"
    system = "its third-order system" if t.form.third_order else "exact integrals"
    line = (f"liquid in tank {t.name!r}", f"{shape_words(t)}multimodal ({flow}), {len(modal_modes(t))} free-surface "
                                          f"modes, {system}, {t.liquid_mass:.6g} kg; its inertial loads (Coriolis and "
                                          "centrifugal among them) are the modal Lagrangian's, not switched by "
                                          "[effects]")
    return TankWords(line, (), modal_words(t), "the multimodal tank's linear modes", "the multimodal liquid")
