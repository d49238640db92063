"""The restoring of the hull's instantaneous wetted surface (`vessel.hydrostatics.model = "nonlinear"`,
SPEC section 8, PHYSICS.md section 5), and the incident-wave (Froude-Krylov) pressure on it.

The hull is a closed triangulated surface in the vessel frame (COG at the origin, hull/surface.py).
The still water lies at Z = z_water in the inertial frame (the rest COG at the origin). In the body
frame the sea is the half-space n_b . r <= z_water - Z0 with n_b = A^T e_z, so the surface is clipped
where it is (hull/clip.py: exact, a static number of pieces, continuous in the pose) and the
displaced volume V and its first moment m about the COG (body frame) give, by the divergence
theorem, the still-water pressure's resultant exactly:

    F = rho g V e_z (inertial),     M = m x (rho g n_b) (body, about the COG),

the gradient of the potential U = rho g (V (z_water - Z0) - n_b . m) = rho g int (z_water - Z) dV
(a test checks the rows against it). The weight is the vessel's `Weight` term, as without
hydrostatics: the two balance only where the hull floats.

Waves ([waves]): the linear incident pressure p = rho g sum a_i f_i(z) cos(theta_i) (the scene's
Airy components, finite depth too) is taken up to the incident free surface eta with Wheeler
stretching: f_i is evaluated at the stretched depth z_s = h (z - eta) / (h + eta) (deep water:
z - eta), so the total pressure rho g (-z + sum a_i f_i(z_s) cos theta_i) vanishes on the incident
surface itself, as the physical pressure does, and tends to the linear Froude-Krylov pressure for
small waves. Extrapolating the linear pressure hydrostatically above z = 0 instead would be as
simple but lets a crest carry the mean-level pressure gradient up to eta, which over-predicts the
crest's share by the factor 1 / f(0) - 1 of the dynamic part that Wheeler removes; both agree to
first order. Each hull triangle is cut by the plane tangent to eta at its centroid: the wetted
pieces then follow the wave without centroid switching, with an error of the order of the
triangle's size squared times the surface curvature (k a / panel^2), so panels must be small
against the wave length (assemble/hull.py divides the box accordingly).
"""
from __future__ import annotations

from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp

from ..hull.clip import clip_below, integrate_pressure
from ..hull.hydrostatics import buoyancy, still_force_moment
from .terms import AbstractTerm, Kin, Rows


class IncidentWaves(eqx.Module):
    """Airy components: eta(x, y, t) = r(t) height sum_i amp_i cos(w_i t + eps_i - k_i (x cos b_i + y sin b_i))
    (hydro/spectra.py's conventions, horizontal coordinates from the rest COG), r the scene's ramp."""
    omega: jax.Array      # (N,)
    k: jax.Array          # (N,)
    amp: jax.Array        # (N,) per unit `height`
    phase: jax.Array      # (N,)
    cb: jax.Array         # (N,) cos(heading)
    sb: jax.Array         # (N,) sin(heading)
    height: jax.Array     # () the scene's amplitude (regular) or Hs: may be traced
    depth: Optional[float] = eqx.field(static=True, default=None)
    ramp: float = eqx.field(static=True, default=0.0)

    def factor(self, t):
        a = self.height * self.amp
        if self.ramp > 0:
            s = jnp.clip(t, 0.0, self.ramp) / self.ramp
            a = a * (0.5 * (1.0 - jnp.cos(jnp.pi * s)))
        return a

    def phases(self, X, t):
        """theta (..., N) at inertial points X (..., 3)."""
        return self.omega * t + self.phase - self.k * (X[..., 0:1] * self.cb + X[..., 1:2] * self.sb)

    def elevation_and_slope(self, X, t):
        """eta (...,) and its horizontal gradient (..., 2) at X (..., 3)."""
        a = self.factor(t)
        th = self.phases(X, t)
        c, s = jnp.cos(th), jnp.sin(th)
        eta = jnp.sum(a * c, axis=-1)
        aks = a * self.k * s
        return eta, jnp.stack([jnp.sum(aks * self.cb, axis=-1), jnp.sum(aks * self.sb, axis=-1)], axis=-1)

    def head(self, X, zeta, t):
        """(...,) the dynamic pressure over rho g at X with zeta = Z - z_water, Wheeler-stretched."""
        a = self.factor(t)
        c = a * jnp.cos(self.phases(X, t))
        eta = jnp.sum(c, axis=-1)
        if self.depth is None:
            zs = zeta - eta
            f = jnp.exp(self.k * jnp.minimum(zs, 0.0)[..., None])
        else:
            h = self.depth
            zs = h * (zeta - eta) / (h + eta)
            zs = jnp.minimum(zs, 0.0)[..., None]
            f = (jnp.exp(self.k * zs) + jnp.exp(-self.k * (zs + 2.0 * h))) / (1.0 + jnp.exp(-2.0 * self.k * h))
        return jnp.sum(c * f, axis=-1)


class HullPressure(AbstractTerm):
    """Still-water pressure (and, with `waves`, the incident-wave pressure) on the instantaneous
    wetted surface of the closed hull `tris` (n, 3, 3), body frame, outward."""
    tris: jax.Array
    rho_w: jax.Array
    gravity: jax.Array
    z_water: jax.Array                      # inertial height of the still water plane
    waves: Optional[IncidentWaves] = None
    # (3,) body frame: the surface is tris + shift (a traced KG: assemble/hull.py); None: tris itself
    shift: Optional[jax.Array] = None

    def surface(self):
        """The closed surface (n, 3, 3) in the body frame, the shift applied."""
        return self.tris if self.shift is None else self.tris + self.shift

    def buoyancy(self, X0, A):
        """(V, m): displaced volume and its first moment about the COG (body frame) in still water."""
        return buoyancy(self.tris, self.z_water, X0, A, self.shift)

    def still_force_moment(self, X0, A):
        """F (inertial) and M (body, about the COG) of the still-water pressure."""
        return still_force_moment(self.tris, self.z_water, self.rho_w * self.gravity, X0, A, self.shift)

    def wave_force_moment(self, X0, A, t):
        """F (inertial) and M (body) of the total pressure (hydrostatic and incident) on the part of
        each triangle below the plane tangent to the incident surface at its centroid."""
        w = self.waves
        tris = self.surface()
        cen = tris.mean(axis=1)                                      # (n, 3) body
        C = X0 + cen @ A.T
        eta, slope = w.elevation_and_slope(C, t)
        N_in = jnp.concatenate([-slope, jnp.ones_like(eta)[:, None]], axis=1)          # (n, 3)
        off_in = self.z_water + eta - slope[:, 0] * C[:, 0] - slope[:, 1] * C[:, 1]
        nb = N_in @ A                                                # A^T N_in, per row
        ob = off_in - N_in @ X0
        pieces = jax.vmap(lambda tri, n, o: clip_below(tri[None], n, o)[0])(tris, nb, ob)
        rg = self.rho_w * self.gravity

        def pressure(x):
            X = X0 + x @ A.T
            zeta = X[..., 2] - self.z_water
            return rg * (w.head(X, zeta, t) - zeta)

        F, M = integrate_pressure(pieces, pressure, jnp.zeros(3))
        return A @ F, M

    def force_moment(self, X0, A, t):
        if self.waves is None:
            return self.still_force_moment(X0, A)
        return self.wave_force_moment(X0, A, t)

    def rows(self, k: Kin) -> Rows:
        F, M = self.force_moment(k.c.X0, k.A, k.t)
        return Rows(-jnp.concatenate([F, M]))

    def potential(self, k: Kin):
        """The still-water potential rho g int (z_water - Z) dV (the waves add work, not a potential)."""
        V, m = self.buoyancy(k.c.X0, k.A)
        return self.rho_w * self.gravity * (V * (self.z_water - k.c.X0[2]) - k.A[2] @ m)

