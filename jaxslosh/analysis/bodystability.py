"""The righting levers of rigid bodies with linear hydrostatics (docs/guide/stability.md#bodies):
each `[[bodies]]` body's, and the vessel's where it has no hull to heel. A body's restoring is its
linear hydrostatic term (the one its run uses: assemble/hull.py `linear_hydrostatics`), so its
GZ at a heel phi is the term's moment about the heel axis over its weight rho g V: GM sin(phi)
for the conservative form (GM_T about roll, GM_L about pitch). The heave force of the linear
term does not depend on the attitude, so a body free to sink does not sink at a heel, and a pure
heel's moment has no part about the other axis (it does not trim)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import jax
import jax.numpy as jnp
import numpy as np

from ..assemble.hull import linear_hydrostatics
from ..hull.hydrostatics import first_vanishing

#: rad: the half step of GM0's central difference of the linear GZ
GM0_STEP = 1e-4


@dataclass(frozen=True)
class LinearStability:
    """One body's righting lever from its linear hydrostatics: heels `angle` (rad) about `axis`,
    GZ (m), GM0 (its slope upright: GM_T about roll, GM_L about pitch), GM_T and GM_L as given,
    the angle of vanishing stability (None beyond the heels asked for)."""
    name: str
    angle: np.ndarray
    gz: np.ndarray
    gm0: float
    gm_t: float
    gm_l: float
    vanishing_angle: Optional[float]
    axis: str = "roll"

    def as_dict(self):
        """Its entry in `jaxslosh stability --json`'s "bodies" (docs/guide/stability.md#bodies)."""
        return {"model": "linear", "angle": [float(a) for a in self.angle], "gz": [float(g) for g in self.gz],
                "gm0": float(self.gm0), "gm_t": float(self.gm_t), "gm_l": float(self.gm_l),
                "vanishing_angle": None if self.vanishing_angle is None else float(self.vanishing_angle)}

    def __getitem__(self, key):
        return self.as_dict()[key]


def heel_quaternions(angles, axis: str):
    """(n, 4) Euler parameters, scalar first, of pure heels `angles` (rad) about the body's x (roll)
    or y (pitch) axis."""
    half = 0.5 * jnp.asarray(angles, dtype=float)
    s, zero = jnp.sin(half), jnp.zeros_like(half)
    return jnp.stack([jnp.cos(half), s if axis == "roll" else zero, s if axis == "pitch" else zero, zero], axis=-1)


def linear_levers(hydrostatics, rho_w: float, gravity: float, angles, axis: str) -> np.ndarray:
    """GZ (m) of a `hydrostatics` table's linear restoring at the heels `angles` (rad) about `axis`:
    minus the term's moment about that axis over rho g V."""
    term = linear_hydrostatics(hydrostatics, rho_w, gravity)
    moments = jax.vmap(term.moment)(heel_quaternions(angles, axis))
    weight = rho_w * gravity * hydrostatics.displaced_volume
    return -np.asarray(moments[:, 0 if axis == "roll" else 1]) / weight + 0.0      # + 0.0: no -0.0 upright


def linear_stability(name: str, hydrostatics, rho_w: float, gravity: float, angles, axis: str) -> LinearStability:
    """A body's LinearStability at the heels `angles` (rad) about `axis` ("roll" or "pitch")."""
    angles = np.asarray(angles, dtype=float)
    gz = linear_levers(hydrostatics, rho_w, gravity, angles, axis)
    minus, plus = linear_levers(hydrostatics, rho_w, gravity, np.array([-GM0_STEP, GM0_STEP]), axis)
    return LinearStability(name=name, angle=angles, gz=gz, gm0=float((plus - minus) / (2.0 * GM0_STEP)),
                           gm_t=float(hydrostatics.gm_t), gm_l=float(hydrostatics.gm_l),
                           vanishing_angle=first_vanishing(angles, gz), axis=axis)


def bodies_stability(scene, angles, axis: str) -> dict:
    """{name: LinearStability} of the scene's `[[bodies]]`, in its order."""
    env = scene.environment
    return {b.name: linear_stability(b.name, b.hydrostatics, env.water_density, env.gravity, angles, axis)
            for b in scene.bodies}
