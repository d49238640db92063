"""The three-dimensional multimodal tanks of a scene (liquid/multimodal/tank3d.py): which tanks are, their
liquid, the surface sample points that the validity watch reads and the probes' rows."""
from __future__ import annotations

import numpy as np

from .tank3d import ModalTank3D, base_tank3d
from .modes import DiskBase, RectangleBase
from ...scene.types import Tank


def three_dimensional(t: Tank) -> bool:
    return t.form.three_dimensional           # a cylinder's always (the loader's default, and it refuses "2d")


def _base(t: Tank):
    """The multimodal base of the tank's shape: a box's rectangle, an upright cylinder's disk."""
    return t.geometry.modal_base(RectangleBase, DiskBase)


def tank_3d(t: Tank, depth, density) -> ModalTank3D:
    return base_tank3d(_base(t), depth, density, t.origin, t.modes, D=t.size[2])


def sample_points(t: Tank, count: int):
    """(x, y) tank-local: count - 1 points around the walls (where the extremes are; a box's corners
    among them) and the centre."""
    x, y = _base(t).rim(count - 1)
    return np.append(x, 0.5 * t.size[0]), np.append(y, 0.5 * t.size[1])


def probe_row(tank: ModalTank3D, point) -> np.ndarray:
    """(N,): the free-surface elevation at a probe's tank-local (x, y) per unit beta."""
    return tank.surface_rows([point[0]], [point[1]])[0]
