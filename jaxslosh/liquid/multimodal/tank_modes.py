"""One multimodal tank held fixed: its unknowns (modal coordinates) and its linear modes, the
multimodal model's share of the liquid contract (liquid/base.py `AbstractLiquid.tank_unknowns`,
`sloshing_modes`)."""
from __future__ import annotations

import numpy as np

from ..modes import Modes
from .build3d import sample_points
from .modes import DiskBase, RectangleBase, modal_modes


def multimodal_unknowns(tank) -> int:
    """Its modal coordinates: the lowest modes, completed to whole degenerate groups."""
    return len(modal_modes(tank))


def multimodal_sloshing_modes(tank, g: float, n: int) -> Modes:
    """A multimodal tank's own linear modes, at most as many as it runs on, omega^2 = g k tanh(k h),
    each a free-surface mode, in frequency order: a two-dimensional box's standing waves along its
    length, k_i = i pi / L (liquid/multimodal/term.py); a three-dimensional box's k = pi sqrt((i / L)^2 +
    (j / B)^2), an upright cylinder's k = j'_{m,s} / R (the zeros of the Bessel functions' derivatives),
    the base's lowest modes completed to whole degenerate pairs (liquid/multimodal/modes.py). The
    shapes are the surface elevation at sample points: along x in two dimensions; round the walls and
    at the centre in three (liquid/multimodal/build3d.py)."""
    modes = modal_modes(tank)
    if tank.form.three_dimensional:
        base = tank.geometry.modal_base(RectangleBase, DiskBase)
        k = base.wavenumbers(modes)
        order = np.argsort(k, kind="stable")[:n]
        x, y = sample_points(tank, 33)
        k, shapes = k[order], base.values([modes[i] for i in order], x, y)[0].T
    else:
        k = np.array([i for i, _ in modes[:n]]) * np.pi / tank.size[0]
        shapes = np.cos(np.outer(k, np.linspace(0.0, tank.size[0], 33)))
    n = len(k)
    return Modes(omega=np.sqrt(g * k * np.tanh(k * tank.fill_depth)), kind=("sloshing",) * n,
                 free_surface_share=np.ones(n), shapes=shapes)
