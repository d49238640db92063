"""The still-water pressure on a closed hull (n, 3, 3) in its own frame (origin at the COG), the
sea below Z = z_water in the inertial frame: its resultant, the linear model of the same hull at
rest, and the righting lever at fixed heels (for the capsize check of a run). PHYSICS.md section 5."""
from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from ..physics.kinematics import quat_exp, rotation_matrix
from .clip import submerged

#: bisection steps of the sinkage at a fixed heel: the bracket (the hull's size) shrinks below round-off
BISECTIONS = 80


def buoyancy(tris, z_water, X0, A):
    """(V, m): the displaced volume and its first moment about the COG (body frame) for the pose
    (X0 inertial, A body to inertial): the body's part below n_b . r = z_water - Z0, n_b = A^T e_z."""
    return submerged(tris, A[2], z_water - X0[2])


def still_force_moment(tris, z_water, rho_g, X0, A):
    """F (inertial) and M (body, about the COG) of the still-water pressure: by the divergence
    theorem rho g V e_z, and m x rho g n_b for the first moment m of the displaced volume."""
    V, m = buoyancy(tris, z_water, X0, A)
    return jnp.array([0.0, 0.0, rho_g * V]), jnp.cross(m, rho_g * A[2])


@jax.jit
def _rest(tris, z_water, rho_g):
    def rows(x):
        F, M = still_force_moment(tris, z_water, rho_g, x[:3], rotation_matrix(quat_exp(x[3:])))
        return jnp.concatenate([F, M])
    V, m = buoyancy(tris, z_water, jnp.zeros(3), jnp.eye(3))
    return V, m, -jax.jacfwd(rows)(jnp.zeros(6))


def rest_hydrostatics(tris, z_water, rho=1025.0, g=9.81) -> dict:
    """The linear model of the same hull (eqs. 33-38) from the still-water stiffness K at rest
    (K33 = rho g A_w, K44 = rho g V GM_T, K55 = rho g V GM_L; the weight adds nothing there, the
    frame being at the COG), and the centre of buoyancy (body frame). Host-side floats."""
    V, m, K = _rest(jnp.asarray(tris, dtype=float), jnp.asarray(z_water, dtype=float), jnp.asarray(rho * g))
    V, rg = float(V), rho * g
    safe = V if V > 0 else 1.0
    return {"waterplane_area": float(K[2, 2]) / rg, "displaced_volume": V,
            "gm_t": float(K[3, 3]) / (rg * safe), "gm_l": float(K[4, 4]) / (rg * safe),
            "centre_of_buoyancy": tuple(float(x) / safe for x in m)}


@functools.partial(jax.jit, static_argnames="axis")
def gz_curve(tris, z_water, volume, S_over_mass, angles, axis: int = 0):
    """GZ (m) at each heel of `angles` (rad) about body axis `axis` (0 roll, 1 pitch), the hull free
    to sink to the displaced `volume`, its trim (or heel) held; positive where the moment rights the
    vessel. `S_over_mass`: the centre of gravity in the frame (the liquid's weight moves it)."""
    reach = jnp.max(jnp.abs(tris)) + jnp.abs(z_water) + 1.0

    def one(phi):
        A = rotation_matrix(quat_exp(jnp.zeros(3).at[axis].set(phi)))

        def halve(_, bracket):
            lo, hi = bracket
            mid = 0.5 * (lo + hi)
            V, _m = buoyancy(tris, z_water, jnp.array([0.0, 0.0, mid]), A)
            return jnp.where(V > volume, mid, lo), jnp.where(V > volume, hi, mid)
        lo, hi = jax.lax.fori_loop(0, BISECTIONS, halve, (-reach, reach))
        V, m = buoyancy(tris, z_water, jnp.array([0.0, 0.0, 0.5 * (lo + hi)]), A)
        # the moment of buoyancy and weight about the COG over the weight: (x_B - x_G) x n_b
        lever = jnp.cross(m / V - S_over_mass, A[2])
        return -lever[axis]
    return jax.vmap(one)(angles)


def first_vanishing(angles, gz):
    """The first positive angle where GZ goes from positive to <= 0 (linear between the samples), 0
    where it is <= 0 at every positive angle, None where it stays positive (the convention of
    analysis/stability.vanishing_angle, which this layer cannot import)."""
    a, g = np.asarray(angles), np.asarray(gz)
    a, g = a[a > 0], g[a > 0]
    if len(a) == 0:
        return None
    if np.all(g <= 0):
        return 0.0
    down = np.flatnonzero((g[:-1] > 0) & (g[1:] <= 0))
    if down.size == 0:
        return None
    i = int(down[0])
    return float(a[i] + (a[i + 1] - a[i]) * g[i] / (g[i] - g[i + 1]))
