"""The still-water pressure on a closed hull (n, 3, 3) in its own frame (origin at the COG), the
sea below Z = z_water in the inertial frame: its resultant, the linear model of the same hull at
rest, and the righting lever at fixed heels (for the capsize check of a run). docs/guide/large-angles.md."""
from __future__ import annotations

import functools

import jax
from jax.custom_derivatives import SymbolicZero
import jax.numpy as jnp
import numpy as np

from .clip import lid_integrals, panels

#: bisection steps of the sinkage at a fixed heel: the bracket (the hull's size) shrinks below round-off
BISECTIONS = 52


def buoyancy(P, z_water, X0, A, shift=None):
    """(V, m): the displaced volume and its first moment about the COG (body frame) for the pose
    (X0 inertial, A body to inertial) of the closed surface P (3, 3, n) (hull/clip.panels): the
    body's part below n_b . r = z_water - Z0, n_b = A^T e_z. `shift` (3,), body frame: the surface
    is `P + shift` (a traced KG moves the hull against the COG); the plane moves the other way over
    the fixed triangles instead, so the tangent stays the lid's (volume_below) and the triangles
    stay constants: V is unchanged and m gains shift V."""
    if shift is None:
        return volume_below(P, A[2], z_water - X0[2])
    V, m = volume_below(P, A[2], z_water - X0[2] - A[2] @ shift)
    return V, m + shift * V


def _below(P, n, c, second):
    nn = jnp.linalg.norm(n)
    return lid_integrals(P, n / nn, c / nn, second) + (nn,)


@jax.custom_jvp
def volume_below(P, n, c):
    """(V, m): the volume of the closed surface P (3, 3, n) (hull/clip.panels) below the plane
    n . x <= c and its first moment, with the derivative in the plane written out: moving the
    plane sweeps the lid, so d V = (A dc - s . dn) / |n| and d m = (s dc - J dn) / |n| with the
    lid's area A, first moment s and second moment J. The Newton preconditioner linearises the
    rows six times per iteration; through the clipping each is a pass over every panel, from these
    integrals a 3 x 3 product. A tangent in the surface itself is differentiated through the
    clipping."""
    V, m, _, _, _, _ = _below(P, n, c, False)
    return V, m


def _volume_below_jvp(primals, tangents):
    P, n, c = primals
    dP, dn, dc = tangents
    if not isinstance(dP, SymbolicZero):          # the surface moves: differentiate the clipping
        return jax.jvp(lambda *a: _below(*a, False)[:2], primals,
                       tuple(jnp.zeros_like(p) if isinstance(t, SymbolicZero) else t for t, p in zip(tangents, primals)))
    V, m, area, s, J, nn = _below(P, n, c, True)
    dn = jnp.zeros_like(n) if isinstance(dn, SymbolicZero) else dn
    dc = jnp.zeros_like(c) if isinstance(dc, SymbolicZero) else dc
    # the plane n . x = c moves along its unit normal by (dc - dn . x) / |n| at x
    dV = (area * dc - s @ dn) / nn
    dm = (s * dc - J @ dn) / nn
    return (V, m), (dV, dm)


volume_below.defjvp(_volume_below_jvp, symbolic_zeros=True)


def still_force_moment(P, z_water, rho_g, X0, A, shift=None):
    """F (inertial) and M (body, about the COG) of the still-water pressure on the closed surface P
    (3, 3, n): by the divergence theorem rho g V e_z, and m x rho g n_b for the first moment m of
    the displaced volume (the surface `P + shift`, as `buoyancy`)."""
    V, m = buoyancy(P, z_water, X0, A, shift)
    return jnp.array([0.0, 0.0, rho_g * V]), jnp.cross(m, rho_g * A[2])


def rest_hydrostatics(tris, z_water, rho=1025.0, g=9.81) -> dict:
    """The linear model of the same hull (eqs. 33-38) from the still-water stiffness at rest, written
    with the lid's (waterplane's) integrals: K33 = rho g A_w, K44 = rho g (int y^2 dA + V z_B) =
    rho g V GM_T, K55 = rho g (int x^2 dA + V z_B) = rho g V GM_L (the frame at the COG), and the
    centre of buoyancy (body frame). Host-side floats, in float64 whatever the session's setting:
    evaluated in NumPy (the loader calls it before the command line switches JAX to float64, and op
    by op in JAX the clipping compiled some sixty tiny programs)."""
    P = np.moveaxis(np.asarray(tris, dtype=np.float64), 0, -1)         # panels(), in NumPy
    V, m, area, s, J = lid_integrals(P, np.array([0.0, 0.0, 1.0]), np.float64(z_water), xp=np)
    V = float(V)
    safe = V if V > 0 else 1.0
    return {"waterplane_area": float(area), "displaced_volume": V,
            "gm_t": (float(J[1, 1]) + float(m[2])) / safe, "gm_l": (float(J[0, 0]) + float(m[2])) / safe,
            "centre_of_buoyancy": tuple(float(x) / safe for x in m)}


@functools.partial(jax.jit, static_argnames="axis")
def gz_curve(tris, z_water, volume, S_over_mass, angles, axis: int = 0):
    """GZ (m) at each heel of `angles` (rad) about body axis `axis` (0 roll, 1 pitch), the hull free
    to sink to the displaced `volume`, its trim (or heel) held; positive where the moment rights the
    vessel. `S_over_mass`: the centre of gravity in the frame (the liquid's weight moves it)."""
    reach = jnp.max(jnp.abs(tris)) + jnp.abs(z_water) + 1.0
    P = panels(tris)

    def one(phi):
        # the body's up direction n_b = A^T e_z after a rotation phi about body x (roll) or y (pitch)
        c, sn = jnp.cos(phi), jnp.sin(phi)
        up = jnp.stack([jnp.zeros_like(phi), sn, c]) if axis == 0 else jnp.stack([-sn, jnp.zeros_like(phi), c])

        def halve(_, bracket):
            lo, hi = bracket
            mid = 0.5 * (lo + hi)
            V, _m = volume_below(P, up, z_water - mid)
            return jnp.where(V > volume, mid, lo), jnp.where(V > volume, hi, mid)
        lo, hi = jax.lax.fori_loop(0, BISECTIONS, halve, (-reach, reach))
        V, m = volume_below(P, up, z_water - 0.5 * (lo + hi))
        # the moment of buoyancy and weight about the COG over the weight: (x_B - x_G) x n_b
        lever = jnp.cross(m / V - S_over_mass, up)
        return -lever[axis]
    return jax.vmap(one)(angles)


def first_vanishing(angles, gz):
    """The first positive angle where GZ goes from positive to <= 0 (linear between the samples), 0
    where it is <= 0 at every positive angle, None where it stays positive (a run's capsize check
    and `js.stability` both)."""
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
