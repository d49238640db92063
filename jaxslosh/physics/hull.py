"""The restoring of the hull's instantaneous wetted surface (`vessel.hydrostatics.model = "nonlinear"`,
docs/guide/large-angles.md), and the incident-wave (Froude-Krylov) pressure on it.

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

from ..hull.clip import cross3, cut_pieces, panels as coordinate_major
from ..hull.hydrostatics import buoyancy, still_force_moment
from .about import About
from .terms import AbstractTerm, Kin, Rows


class IncidentWaves(eqx.Module):
    """Airy components: eta(x, y, t) = r(t) height sum_i amp_i cos(w_i t + eps_i - k_i (x cos b_i + y sin b_i))
    (hydro/spectra.py's conventions, horizontal coordinates from the rest COG), r the scene's ramp.
    Points are coordinate-major: X (3, ...)."""
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
        """theta (..., N) at inertial points X (3, ...)."""
        return self.omega * t + self.phase - self.k * (X[0][..., None] * self.cb + X[1][..., None] * self.sb)

    def elevation_and_slope(self, X, t):
        """eta (...,) and its horizontal gradient (2, ...) at X (3, ...)."""
        a = self.factor(t)
        th = self.phases(X, t)
        c, s = jnp.cos(th), jnp.sin(th)
        eta = jnp.sum(a * c, axis=-1)
        aks = a * self.k * s
        return eta, jnp.stack([jnp.sum(aks * self.cb, axis=-1), jnp.sum(aks * self.sb, axis=-1)])

    def head(self, X, zeta, t):
        """(...,) the dynamic pressure over rho g at X (3, ...) with zeta = Z - z_water, Wheeler-stretched."""
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


def _to_inertial(X0, A, x):
    """X0 + A x for body points x (3, ...), coordinate-major, written out (elementwise, fused)."""
    e = (Ellipsis,) + (None,) * (x.ndim - 1)
    return X0[e] + A[:, 0][e] * x[0] + A[:, 1][e] * x[1] + A[:, 2][e] * x[2]


class HullPressure(AbstractTerm):
    """Still-water pressure (and, with `waves`, the incident-wave pressure) on the instantaneous
    wetted surface of the closed hull `tris` (n, 3, 3), body frame, outward; kept coordinate-major
    (hull/clip.panels), the layout the clipping runs in."""
    panels: jax.Array                       # (3, 3, n): vertex, coordinate, triangle
    rho_w: jax.Array
    gravity: jax.Array
    z_water: jax.Array                      # inertial height of the still water plane
    waves: Optional[IncidentWaves] = None
    # (3,) body frame: the surface is tris + shift (a traced KG: assemble/hull.py); None: tris itself
    shift: Optional[jax.Array] = None
    # (3,) the rest COG's horizontal place (x, y, 0) in the waves' frame (from the vessel's rest COG):
    # a body's (X0 is its offset from its own rest), so that the waves reach it with its own phase;
    # None: the origin (the vessel)
    place: Optional[jax.Array] = None
    about: About = eqx.field(static=True, default=About())     # the hull (box or mesh file) and its waves

    def __init__(self, tris, rho_w, gravity, z_water, waves=None, shift=None, about=About(), place=None):
        self.panels = coordinate_major(tris)
        self.rho_w, self.gravity, self.z_water, self.waves, self.shift = rho_w, gravity, z_water, waves, shift
        self.place = place
        self.about = about

    def describe(self) -> tuple:
        return self.about.lines

    def surface(self):
        """The closed surface (n, 3, 3) in the body frame, the shift applied."""
        return self.tris if self.shift is None else self.tris + self.shift

    def surface_panels(self):
        """The closed surface coordinate-major (3, 3, n), the shift applied."""
        return self.panels if self.shift is None else self.panels + self.shift[None, :, None]

    @property
    def tris(self):
        """The hull's triangles (n, 3, 3)."""
        return jnp.moveaxis(self.panels, -1, 0)

    def buoyancy(self, X0, A):
        """(V, m): displaced volume and its first moment about the COG (body frame) in still water."""
        return buoyancy(self.panels, self.z_water, X0, A, self.shift)

    def still_force_moment(self, X0, A):
        """F (inertial) and M (body, about the COG) of the still-water pressure."""
        return still_force_moment(self.panels, self.z_water, self.rho_w * self.gravity, X0, A, self.shift)

    def wave_force_moment(self, X0, A, t):
        """F (inertial) and M (body) of the total pressure (hydrostatic and incident) on the part of
        each triangle below the plane tangent to the incident surface at its centroid, by the
        edge-midpoint rule on each wetted piece (hull/clip.cut_pieces)."""
        w, P = self.waves, self.surface_panels()
        if self.place is not None:       # the waves' frame; the water's height is the same (place[2] = 0)
            X0 = X0 + self.place
        C = _to_inertial(X0, A, (P[0] + P[1] + P[2]) / 3.0)          # (3, n) centroids, inertial
        eta, slope = w.elevation_and_slope(C, t)
        N_in = jnp.stack([-slope[0], -slope[1], jnp.ones_like(eta)])  # (3, n)
        off_in = self.z_water + eta - slope[0] * C[0] - slope[1] * C[1]
        nb = A.T @ N_in                                              # body frame
        ob = off_in - X0 @ N_in
        size = jnp.sqrt(nb[0] ** 2 + nb[1] ** 2 + nb[2] ** 2)
        a, b, wa, wb = cut_pieces(P, nb / size, ob / size)
        rg = self.rho_w * self.gravity
        # the three edge midpoints of both pieces: (3, 6, n) body points
        x = jnp.stack([0.5 * (a[0] + a[1]), 0.5 * (a[1] + a[2]), 0.5 * (a[2] + a[0]),
                       0.5 * (b[0] + b[1]), 0.5 * (b[1] + b[2]), 0.5 * (b[2] + b[0])], axis=1)
        X = _to_inertial(X0, A, x)
        zeta = X[2] - self.z_water
        p = rg * (w.head(X, zeta, t) - zeta) / 3.0                     # (6, n), the rule's weight in
        sa = 0.5 * wa * cross3(a[1] - a[0], a[2] - a[0])                # (3, n) area vectors
        sb = 0.5 * wb * cross3(b[1] - b[0], b[2] - b[0])
        s6 = jnp.stack([sa] * 3 + [sb] * 3, axis=1)                    # (3, 6, n) each point's piece
        # force and moment per unit pressure at each point, contracted with the pressures in one
        # product: p is then computed once (in elementwise sums XLA repeated its cosines and
        # exponentials in every fusion that reads it)
        G = jnp.concatenate([s6, cross3(x, s6)])                         # (6, 6, n)
        FM = -jnp.einsum("oqn,qn->o", G, p)
        return A @ FM[:3], FM[3:]

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

