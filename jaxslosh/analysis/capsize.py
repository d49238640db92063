"""The angle of vanishing stability of a hull with the nonlinear hydrostatics, for the capsize check
of a run (run/validity.py): the righting lever GZ at fixed heels about the roll (or pitch) axis, the
vessel free to sink to its displacement (ship and tank liquid, the liquid frozen at rest), and the
first heel past which GZ turns from righting to capsizing."""
from __future__ import annotations

from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..physics.hull import HullPressure
from ..physics.kinematics import quat_exp, rotation_matrix
from ..physics.vessel import Weight

#: bisection steps of the sinkage: the bracket (the hull's size) shrinks below round-off
BISECTIONS = 80
#: heels at which GZ is evaluated before the crossing is interpolated, 0 to 180 degrees
HEELS = 361


@eqx.filter_jit
def gz_curve(term: HullPressure, weight: Weight, angles, axis: int = 0):
    """GZ (m) at each heel of `angles` about body axis `axis` (0 roll, 1 pitch), the sinkage found
    for the weight's mass; positive where the moment rights the vessel."""
    mass, S, g = weight.mass, weight.S, weight.gravity
    volume = mass / term.rho_w
    reach = jnp.max(jnp.abs(term.tris)) + jnp.abs(term.z_water) + 1.0

    def one(phi):
        A = rotation_matrix(quat_exp(jnp.zeros(3).at[axis].set(phi)))

        def halve(_, bracket):
            lo, hi = bracket
            mid = 0.5 * (lo + hi)
            V, _m = term.buoyancy(jnp.array([0.0, 0.0, mid]), A)
            return jnp.where(V > volume, mid, lo), jnp.where(V > volume, hi, mid)
        lo, hi = jax.lax.fori_loop(0, BISECTIONS, halve, (-reach, reach))
        _, M = term.still_force_moment(jnp.array([0.0, 0.0, 0.5 * (lo + hi)]), A)
        M = M + jnp.cross(S, A[2] * -g)                      # the weight's moment about the frame origin
        return -M[axis] / (mass * g)
    return jax.vmap(one)(angles)


def vanishing_angle(angles, gz) -> Optional[float]:
    """The first heel where GZ turns from positive to non-positive (linear between the samples), or None."""
    gz = np.asarray(gz)
    down = np.flatnonzero((gz[:-1] > 0) & (gz[1:] <= 0))
    if down.size == 0:
        return None
    i = int(down[0])
    return float(angles[i] + (angles[i + 1] - angles[i]) * gz[i] / (gz[i] - gz[i + 1]))


def vanishing_angles(system) -> Optional[tuple]:
    """(roll, pitch) angles of vanishing stability (rad, None where GZ never turns) of a built
    System with the nonlinear hydrostatics; None for other systems."""
    hull = [t for t in system.terms if isinstance(t, HullPressure)]
    weight = [t for t in system.terms if isinstance(t, Weight)]
    if not hull or not weight:
        return None
    still = HullPressure(hull[0].tris, hull[0].rho_w, hull[0].gravity, hull[0].z_water)
    angles = np.linspace(0.0, np.pi, HEELS)
    return tuple(vanishing_angle(angles, gz_curve(still, weight[0], jnp.asarray(angles), axis)) for axis in (0, 1))
