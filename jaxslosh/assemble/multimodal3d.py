"""The three-dimensional multimodal tanks of a scene (physics/multimodal3d.py): which tanks are, their
liquid, the surface sample points that the validity watch reads and the probes' rows."""
from __future__ import annotations

import numpy as np

from ..physics.multimodal3d import ModalTank3D, box_tank3d, cylinder_tank
from ..scene.types import Tank


def three_dimensional(t: Tank) -> bool:
    return t.shape == "cylinder" or t.flow == "3d"


def tank_3d(t: Tank, depth, density) -> ModalTank3D:
    if t.shape == "cylinder":
        return cylinder_tank(0.5 * t.size[0], depth, density, t.origin, t.modes, D=t.size[2])
    return box_tank3d(t.size[0], t.size[1], depth, density, t.origin, t.modes, D=t.size[2])


def sample_points(t: Tank, count: int):
    """(x, y) tank-local: count - 1 points around the walls (where the extremes are; a box's corners
    among them) and the centre."""
    n = count - 1
    if t.shape == "cylinder":
        R = 0.5 * t.size[0]
        th = 2.0 * np.pi * np.arange(n) / n
        x, y = R + R * np.cos(th), R + R * np.sin(th)
    else:
        L, B = t.size[0], t.size[1]
        q = n // 4
        s = np.arange(q) / q
        x = np.concatenate([L * s, np.full(q, L), L * (1 - s), np.zeros(n - 3 * q)])
        y = np.concatenate([np.zeros(q), B * s, np.full(q, B), B * (1 - np.arange(n - 3 * q) / (n - 3 * q))])
    return np.append(x, 0.5 * t.size[0]), np.append(y, 0.5 * t.size[1])


def probe_row(tank: ModalTank3D, point) -> np.ndarray:
    """(N,): the free-surface elevation at a probe's tank-local (x, y) per unit beta."""
    return tank.surface_rows([point[0]], [point[1]])[0]
