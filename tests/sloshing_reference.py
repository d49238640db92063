"""Independent reference values for linear sloshing frequencies (no jaxslosh imports).

Tests of new tank shapes compare the simulator against this module, so it shares nothing with
the simulator: its own geometry, its own mesh, scikit-fem for the finite elements.

Two parts:

* closed forms: the rectangular tank, the upright circular cylinder, the half-full horizontal
  cylinder (McIver's value) and the 90-degree V (Kirchhoff's exact mode);
* :func:`section_sloshing_omegas`, a finite-element solution of the 2-D linear sloshing problem
  of a liquid section of any convex tank section (rectangle, chamfered "prismatic" LNG section,
  V bottom, circle), with thin vertical baffles.

The 2-D problem (Ibrahim 2005, *Liquid Sloshing Dynamics*, ch. 2; Faltinsen & Timokha 2009,
*Sloshing*, ch. 4). Coordinates (s, z): s across the section from the tank's left wall, z up
from the tank bottom; the liquid fills the section below the free surface z = d (fill depth).
Small motions of an ideal liquid have a velocity potential Phi(s, z, t) = phi(s, z) cos(omega t)
with

    Laplace(phi) = 0                         in the liquid Omega,
    d phi / dn = 0                           on the wetted walls and both faces of each baffle,
    d phi / dz = (omega^2 / g) phi           on the free surface Gamma_F (z = d).

Weak form: for all test functions v,

    integral_Omega grad(phi) . grad(v) dA = lambda integral_Gamma_F phi v ds,  lambda = omega^2/g,

i.e. the Steklov eigenproblem K phi = lambda B phi with K the stiffness (Laplacian) matrix and B
the mass matrix of the free surface only. Eliminating the nodes off the surface (static
condensation, S = K_FF - K_FI K_II^-1 K_IF) leaves the definite problem
S phi_F = lambda B_FF phi_F on the surface nodes, solved by shift-invert Lanczos (ARPACK) with
the surface block of (K + c B)^-1 = (S + c B_FF)^-1, to machine precision. lambda = 0 (phi
constant) is the trivial mode, one per separate pool of liquid; it is dropped.

A prism of the section with end walls at x = 0 and x = L (a prismatic tank, a horizontal
cylinder) has the modes phi(s, z) cos(m pi x / L): for each m the same problem with k^2 phi added
to the Laplacian, k = m pi / L (prism_sloshing_omegas), m = 0 being the section's own modes.

Discretisation: quadratic (P2) triangles. The liquid (convex: a convex tank section below a
level) is meshed by Delaunay triangulation (scipy.spatial.Delaunay) of its boundary sampled
every h, of each baffle sampled every h, and of an equilateral lattice of spacing h kept clear of
both; a polygon is meshed exactly, so the 90-degree V's mode phi = s z (a quadratic) is
reproduced to rounding. A baffle is a slit: the mesh nodes on it are doubled (one copy for each
face) except at its free edge (the tip), round which the liquid flows. The potential near a tip
behaves like r^(1/2) (flow round a sharp edge), which slows convergence on a uniform mesh; the
elements round each tip are refined locally (red-green refinement, ring radius halved 8 times),
which brings the error down to ~1e-5 of the frequency at the default size. Where the free
surface meets a wall at an obtuse angle (a circle filled above its centre, a top chamfer) the
potential is mildly singular too: refined the same way. Circular walls are curved
(isoparametric) elements: the wall's nodes, mid-side ones included, lie on the circle.

Accuracy (the tests' refinement studies, default element size): halving h changes the first
three frequencies of a rectangle, circle or chamfered section by < 1e-5 (the 90-degree V is
exact to rounding), the first frequency of a baffled section by < 2e-5, its second and third
by < 2e-5. Limits: a nearly full circle (free surface narrower than ~1/10 of the diameter) is
meshed at a capped size (see :func:`default_h`) and is less accurate: pass a smaller
``h_target`` there. Linear theory only (small motions, no viscosity, no surface tension), and
2-D: modes uniform along the tank.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components
from scipy.special import jn_zeros, jnp_zeros

G = 9.81

# ---------------------------------------------------------------------------------------------
# closed forms
# ---------------------------------------------------------------------------------------------


def rectangular_omegas(a: float, h: float, g: float = G, n: int = 3) -> np.ndarray:
    """The n lowest sloshing frequencies (rad/s) of a rectangular tank, 2-D.

    Length a (between the walls), liquid depth h: omega_m^2 = g k_m tanh(k_m h), k_m = m pi / a,
    m = 1..n (Lamb 1932, *Hydrodynamics*, 6th ed., ch. IX; Ibrahim 2005, ch. 2). Odd m are
    antisymmetric about mid-length (m = 1: the first sloshing mode), even m symmetric. The same
    formula gives the modes of a 3-D rectangular tank that do not vary across its breadth.
    """
    k = np.arange(1, n + 1) * math.pi / a
    return np.sqrt(g * k * np.tanh(k * h))


def cylinder_bessel_roots(n: int = 3) -> list[tuple[float, int, int]]:
    """The n lowest nonzero roots epsilon of J_m'(epsilon) = 0, all m, with (m, j) labels.

    A mode of an upright circular cylinder is phi = J_m(k r) cos(m theta) cosh(k (z + h)) with
    J_m'(k R) = 0 (no flow through the wall), so k R = epsilon_mj, the j-th positive zero of J_m'.
    For m = 0 the zero at epsilon = 0 is the trivial mode; J_0' = -J_1, so the nonzero zeros of
    J_0' are the zeros of J_1. Taken from scipy.special.jnp_zeros / jn_zeros and sorted:
    1.8412 (m=1, j=1), 3.0542 (m=2, j=1), 3.8317 (m=0, j=1), 4.2012 (m=3, j=1), 5.3176 (m=4, j=1),
    5.3314 (m=1, j=2), ...
    """
    roots = []
    for m in range(n + 1):  # J_m' first zero > m, so m <= n covers the n lowest roots
        z = jn_zeros(1, n) if m == 0 else jnp_zeros(m, n)
        roots += [(float(e), m, j + 1) for j, e in enumerate(z)]
    roots.sort()
    return roots[:n]


def vertical_cylinder_omegas(R: float, h: float, g: float = G, n: int = 3) -> np.ndarray:
    """The n lowest distinct sloshing frequencies (rad/s) of an upright circular cylinder.

    Radius R, liquid depth h: omega^2 = g k tanh(k h), k = epsilon / R with epsilon the roots of
    :func:`cylinder_bessel_roots` (Lamb 1932, ch. IX; Ibrahim 2005, ch. 2). n = 3 gives the
    first antisymmetric (m=1, k R = 1.8412), the first m=2 (3.0542) and the first axisymmetric
    (m=0, 3.8317) modes; each m >= 1 frequency belongs to two modes (cos and sin m theta).
    """
    k = np.array([e for e, _, _ in cylinder_bessel_roots(n)]) / R
    return np.sqrt(g * k * np.tanh(k * h))


MCIVER_HALF_FULL = 1.3557
"""omega^2 R / g of the first (antisymmetric) sloshing mode of a half-full horizontal circular
cylinder, 2-D (McIver 1989, "Sloshing frequencies for cylindrical and spherical containers filled
to an arbitrary depth", J. Fluid Mech. 201, 243-257). This module's solver gives 1.35573."""


def horizontal_cylinder_half_full_first(R: float, g: float = G) -> float:
    """First sloshing frequency (rad/s) of a half-full horizontal circular cylinder of radius R.

    omega^2 = 1.3557 g / R (McIver 1989, see :data:`MCIVER_HALF_FULL`); the transverse mode,
    uniform along the axis.
    """
    return math.sqrt(MCIVER_HALF_FULL * g / R)


def v_section_first(h: float, g: float = G) -> float:
    """First sloshing frequency (rad/s) of a 90-degree V section (walls at 45 degrees), depth h.

    Kirchhoff's exact solution (Kirchhoff 1879; Lamb 1932, ch. IX): with the apex at the origin,
    the walls z = |s| and the free surface z = h, phi = s z is harmonic, has no normal derivative
    on the walls (grad phi = (z, s) is along the wall z = s) and satisfies d phi/dz = s = phi / h
    on the surface, so omega^2 = g / h, h the depth at the apex. It is the lowest (antisymmetric)
    mode. In :func:`prismatic` terms: prismatic(b, H, cw=b/2, ch=b/2) filled to h <= b/2.
    """
    return math.sqrt(g / h)


# ---------------------------------------------------------------------------------------------
# geometry
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Section:
    """A convex tank section in the plane (s, z): s across from the leftmost wall, z up from the
    bottom (lowest point z = 0).

    Either a convex polygon (``vertices``, counter-clockwise; vertical edges may go up to
    z = inf for an open-topped rectangle) or a circle (``radius`` R, centre (R, R)). Build it with
    :func:`rectangle`, :func:`prismatic`, :func:`circle` or :func:`polygon`.
    """

    vertices: tuple[tuple[float, float], ...] = ()
    radius: float = 0.0

    @property
    def is_circle(self) -> bool:
        return self.radius > 0.0

    @property
    def height(self) -> float:
        """Height of the tank (its top at z = height; inf for an open rectangle)."""
        if self.is_circle:
            return 2.0 * self.radius
        return max(z for _, z in self.vertices)

    def _edges(self):
        v = self.vertices
        return list(zip(v, v[1:] + v[:1]))

    def interval(self, z: float) -> tuple[float, float]:
        """(s_left, s_right): the section's extent across at level z."""
        if self.is_circle:
            R = self.radius
            half = math.sqrt(max(R * R - (z - R) ** 2, 0.0))
            return R - half, R + half
        hits = []
        for (s0, z0), (s1, z1) in self._edges():
            if not min(z0, z1) <= z <= max(z0, z1):
                continue
            if s0 == s1:  # vertical edge (may reach z = inf)
                hits.append(s0)
            elif z0 == z1:
                hits += [s0, s1]
            else:
                hits.append(s0 + (z - z0) * (s1 - s0) / (z1 - z0))
        if not hits:
            raise ValueError(f"level z = {z} is outside the section")
        return min(hits), max(hits)

    def vertical(self, s: float) -> tuple[float, float]:
        """(z_bottom, z_top): the section's extent up the vertical line at s."""
        if self.is_circle:
            R = self.radius
            half = math.sqrt(max(R * R - (s - R) ** 2, 0.0))
            return R - half, R + half
        hits = []
        for (s0, z0), (s1, z1) in self._edges():
            if not min(s0, s1) <= s <= max(s0, s1):
                continue
            if s0 == s1:
                hits += [z0, z1]
            elif z0 == z1:
                hits.append(z0)
            else:
                hits.append(z0 + (s - s0) * (z1 - z0) / (s1 - s0))
        if not hits:
            raise ValueError(f"s = {s} is outside the section")
        return min(hits), max(hits)


def polygon(vertices) -> Section:
    """A convex polygonal section from its corners (s, z), counter-clockwise, lowest z = 0."""
    v = []
    for s, z in vertices:  # drop repeated corners (a chamfer of zero size)
        p = (float(s), float(z))
        if not v or p != v[-1]:
            v.append(p)
    if len(v) > 1 and v[0] == v[-1]:
        v.pop()
    if len(v) < 3:
        raise ValueError("a polygon needs 3 distinct corners")
    if min(z for _, z in v) != 0.0:
        raise ValueError("the section's bottom must be at z = 0")
    for (s0, z0), (s1, z1) in zip(v, v[1:] + v[:1]):
        if math.isinf(z0) != math.isinf(z1) and s0 != s1:
            raise ValueError("only vertical edges may go up to z = inf")
    finite = [p for p in v if math.isfinite(p[1])]
    scale = max(max(abs(s), abs(z)) for s, z in finite)
    for i in range(len(finite)):  # convex and counter-clockwise (cross products >= 0)
        (a, b), (c, d), (e, f) = finite[i - 2], finite[i - 1], finite[i]
        if (c - a) * (f - d) - (d - b) * (e - c) < -1e-12 * scale**2:
            raise ValueError("the polygon must be convex and counter-clockwise")
    return Section(vertices=tuple(v))


def rectangle(b: float, H: float = math.inf) -> Section:
    """Rectangular section, width b, height H (H only matters for a hanging baffle)."""
    return polygon([(0.0, 0.0), (b, 0.0), (b, H), (0.0, H)])


def prismatic(b: float, H: float, cw: float = 0.0, ch: float = 0.0, tw: float = 0.0,
              th: float = 0.0) -> Section:
    """Chamfered ("prismatic" LNG) section: a b x H rectangle with its corners cut off.

    Bottom corners cut by chamfers cw wide and ch high, top corners by chamfers tw wide and th
    high. cw = b/2 gives a V bottom (a right angle at the apex when ch = cw), tw = b/2 a
    roof-shaped top.
    """
    if not (0 <= cw <= b / 2 and 0 <= tw <= b / 2 and ch >= 0 and th >= 0 and ch + th <= H):
        raise ValueError("chamfers larger than the section")
    return polygon([(cw, 0.0), (b - cw, 0.0), (b, ch), (b, H - th), (b - tw, H), (tw, H),
                    (0.0, H - th), (0.0, ch)])


def circle(R: float) -> Section:
    """Circular section of radius R (a horizontal cylinder), centre (R, R)."""
    return Section(radius=float(R))


@dataclass(frozen=True)
class Baffle:
    """A thin vertical plate across the section at s = ``s``.

    Standing (``hanging=False``): on the bottom, ``height`` high (from the bottom at s up to
    z = z_bottom(s) + height). Hanging (``hanging=True``): from the tank's top down, its lower
    edge ``height`` below the top at s (z = z_top(s) - height). Only the part in the liquid
    counts; a plate across the whole depth parts the liquid into two pools.
    """

    s: float
    height: float
    hanging: bool = False

    def plate(self, section: Section) -> tuple[float, float]:
        """(z_low, z_high) of the plate in ``section``."""
        zb, zt = section.vertical(self.s)
        if self.hanging:
            if not math.isfinite(zt):
                raise ValueError("a hanging baffle needs the tank height (e.g. rectangle(b, H))")
            return zt - self.height, zt
        return zb, zb + self.height


# ---------------------------------------------------------------------------------------------
# mesh
# ---------------------------------------------------------------------------------------------


def _liquid_boundary(section: Section, d: float):
    """The liquid's boundary, counter-clockwise, as pieces ("line", p, q) or ("arc", t0, t1)
    (angles about the circle's centre), and a function giving the distance of points (2, m)
    inside the liquid to its boundary (the liquid is convex: the least distance to a side)."""
    if section.is_circle:
        R = section.radius
        a = math.asin((d - R) / R)
        t0, t1 = math.pi - a, 2 * math.pi + a
        left, right = (R + R * math.cos(t0), d), (R + R * math.cos(t1), d)
        pieces = [("arc", t0, t1), ("line", right, left)]
        return pieces, lambda P: np.minimum(R - np.hypot(P[0] - R, P[1] - R), d - P[1])
    out = []
    for p, q in section._edges():  # clip the polygon to z <= d (Sutherland-Hodgman)
        if p[1] <= d:
            out.append(p)
        if (p[1] <= d) != (q[1] <= d):
            s = p[0] if p[0] == q[0] else p[0] + (d - p[1]) * (q[0] - p[0]) / (q[1] - p[1])
            out.append((s, d))
    v = [p for i, p in enumerate(out) if p != out[i - 1]]
    pieces = [("line", p, q) for p, q in zip(v, v[1:] + v[:1])]

    def distance(P):
        dist = np.full(P.shape[1], np.inf)
        for _, p, q in pieces:
            e = np.subtract(q, p)
            normal = np.array([e[1], -e[0]]) / np.hypot(*e)  # outward
            dist = np.minimum(dist, -((P[0] - p[0]) * normal[0] + (P[1] - p[1]) * normal[1]))
        return dist

    return pieces, distance


def _sample_boundary(section, pieces, h, must, tol):
    """Points along the boundary, spacing <= h, through every corner and every point of
    ``must`` (baffle feet and tops); counter-clockwise, the closing point left out."""
    pts = []
    for piece in pieces:
        if piece[0] == "line":
            p, q = np.array(piece[1]), np.array(piece[2])
            e = q - p
            length = np.hypot(*e)
            ts = [0.0, 1.0]
            for m in must:
                t = np.dot(np.subtract(m, p), e) / length**2
                off = abs(e[0] * (m[1] - p[1]) - e[1] * (m[0] - p[0])) / length
                if tol < t * length < length - tol and off < tol:
                    ts.append(t)
            ts = sorted(ts)
            for a, b in itertools.pairwise(ts):
                n = max(1, math.ceil((b - a) * length / h - 1e-9))
                for i in range(n):
                    pts.append(p + e * (a + (b - a) * i / n))
        else:
            R = section.radius
            t0, t1 = piece[1], piece[2]
            ts = [t0, t1]
            for m in must:
                if abs(math.hypot(m[0] - R, m[1] - R) - R) < tol:
                    t = math.atan2(m[1] - R, m[0] - R) % (2 * math.pi)
                    t = t + 2 * math.pi if t < t0 - 1e-12 else t
                    if t0 + tol / R < t < t1 - tol / R:
                        ts.append(t)
            ts = sorted(ts)
            for a, b in itertools.pairwise(ts):
                n = max(1, math.ceil((b - a) * R / h - 1e-9))
                for i in range(n):
                    t = a + (b - a) * i / n
                    pts.append(np.array([R + R * math.cos(t), R + R * math.sin(t)]))
    return np.array(pts).T


@dataclass(frozen=True)
class SectionMesh:
    """The mesh of a liquid section: ``mesh`` (skfem MeshTri1, or MeshTri2 with curved walls),
    ``surface`` (its free-surface facets), ``tips`` (the baffles' free edges, (s, z)),
    ``pools`` (how many separate pools of liquid), ``width`` (of the free surface)."""

    mesh: object
    surface: np.ndarray
    tips: tuple
    pools: int
    width: float


def default_h(section: Section, fill_depth: float) -> float:
    """Default element size: the smaller of 1/40 of the free surface's width and 1/20 of the
    depth, but not below 1/100 of the square root of the liquid's area (at most ~1.2e4 lattice
    nodes: it binds only for a nearly full circle). The tests' refinement studies show the first
    three frequencies to 1e-5 or better with it."""
    sl, sr = section.interval(fill_depth)
    pieces, _ = _liquid_boundary(section, fill_depth)
    if section.is_circle:
        R = section.radius
        t = pieces[0][2] - pieces[0][1]
        area = 0.5 * R * R * (t - math.sin(t))
    else:
        s, z = np.array([p[1] for p in pieces]).T
        area = 0.5 * abs(np.dot(s, np.roll(z, -1)) - np.dot(z, np.roll(s, -1)))  # shoelace
    return max(min((sr - sl) / 40.0, fill_depth / 20.0), math.sqrt(area) / 100.0)


def section_mesh(section: Section, fill_depth: float, baffles=(), h_target: float | None = None,
                 tip_refinements: int = 8) -> SectionMesh:
    """Triangular mesh of the liquid of ``section`` below z = ``fill_depth``, baffles as slits.

    Nodes: the boundary sampled every <= h (through the corners, baffle feet and tops), each
    baffle sampled every <= h, and an equilateral lattice of spacing h (rows parallel to the
    free surface) kept 0.5 h from the boundary and 0.6 h from the baffles; triangles: their
    Delaunay triangulation (the liquid is convex, and the baffle's segments are Gabriel edges,
    so both are edges of the mesh). The nodes on a baffle are then doubled (one copy for the
    elements on each side) except at its tip; the elements round each tip, and round a corner
    where the surface meets a wall at an obtuse angle, are refined ``tip_refinements`` times
    (red-green, the ring radius halved each time). Curved walls: the wall's nodes, including the
    P2 mid-side nodes, are put on the circle (MeshTri2).
    """
    from scipy.spatial import Delaunay
    from skfem import MeshTri1, MeshTri2

    d = float(fill_depth)
    if not 0.0 < d <= section.height:
        raise ValueError(f"fill depth {d} outside (0, {section.height}]")
    sl, sr = section.interval(d)
    if sr - sl <= 0.0:
        raise ValueError("the free surface has no width")
    h = float(default_h(section, d) if h_target is None else h_target)
    scale = max(d, sr, section.interval(0.5 * d)[1])
    tol = 1e-9 * scale
    pieces, distance = _liquid_boundary(section, d)

    # baffles: the wetted part of each plate, plates at one s merged; feet and tops on the
    # boundary are boundary nodes; ends inside the liquid are tips
    plates: dict[float, list[list[float]]] = {}
    for bf in baffles:
        s = float(bf.s)
        zb = section.vertical(s)[0]
        lo, hi = bf.plate(section)
        lo, hi = max(lo, zb), min(hi, d)
        if hi - lo <= tol:  # a plate out of the liquid, or of no height
            continue
        a, b = section.interval(0.5 * (lo + hi))
        if not a + tol < s < b - tol:
            raise ValueError(f"baffle at s = {s} lies on or outside the tank's wall")
        plates.setdefault(s, []).append([lo, hi])
    slits, must, tips = [], [], []
    for s, spans in sorted(plates.items()):
        zb = section.vertical(s)[0]
        spans.sort()
        merged = [spans[0]]
        for lo, hi in spans[1:]:
            if lo <= merged[-1][1] + tol:
                merged[-1][1] = max(merged[-1][1], hi)
            else:
                merged.append([lo, hi])
        for lo, hi in merged:
            ends = [lo <= zb + tol, hi >= d - tol]  # on the boundary?
            lo, hi = (zb if ends[0] else lo), (d if ends[1] else hi)
            n = max(1, math.ceil((hi - lo) / h - 1e-9))
            zs = lo + (hi - lo) * np.arange(n + 1) / n
            zs[-1] = hi
            slits.append((s, zs, ends))
            must += [(s, z) for z, on in zip((lo, hi), ends) if on]
            tips += [(s, z) for z, on in zip((lo, hi), ends) if not on]

    # corners where the free surface meets a wall leaning outwards (the liquid's angle there
    # is obtuse: a top chamfer, a circle filled above its centre): the potential is singular
    # there too, if mildly; refined like the tips
    corners = []
    eps = 1e-6 * scale
    below = section.interval(d - eps)
    if below[0] < sl - 1e-3 * eps:
        corners.append((sl, d))
    if below[1] > sr + 1e-3 * eps:
        corners.append((sr, d))

    boundary = _sample_boundary(section, pieces, h, must, tol)
    nb = boundary.shape[1]
    # slit nodes: boundary ones found among the boundary nodes, the others appended
    extra, slit_ids = [], []
    for s, zs, ends in slits:
        ids = []
        for i, z in enumerate(zs):
            if (i == 0 and ends[0]) or (i == len(zs) - 1 and ends[1]):
                j = int(np.argmin(np.hypot(boundary[0] - s, boundary[1] - z)))
                assert np.hypot(boundary[0, j] - s, boundary[1, j] - z) < 10 * tol
                ids.append(j)
            else:
                ids.append(nb + len(extra))
                extra.append((s, z))
        slit_ids.append(ids)
    # equilateral lattice, rows down from the free surface
    dz = h * math.sqrt(3) / 2
    smin, smax = min(p[0] for p in boundary.T), max(p[0] for p in boundary.T)
    rows = np.arange(1, math.ceil(d / dz) + 1)
    cols = np.arange(math.floor(smin / h) - 1, math.ceil(smax / h) + 2)
    J, I = np.meshgrid(rows, cols, indexing="ij")
    L = np.array([(I + 0.5 * (J % 2)).ravel() * h, d - J.ravel() * dz])
    keep = distance(L) >= 0.5 * h
    for s, zs, _ in slits:
        gap = np.hypot(L[0] - s, np.clip(L[1], zs[0], zs[-1]) - L[1])
        keep &= gap >= 0.6 * h
    P = np.hstack([boundary, np.array(extra).T.reshape(2, -1), L[:, keep]])

    t = Delaunay(P.T).simplices.T.copy()
    area = ((P[0, t[1]] - P[0, t[0]]) * (P[1, t[2]] - P[1, t[0]])
            - (P[1, t[1]] - P[1, t[0]]) * (P[0, t[2]] - P[0, t[0]]))
    good = np.abs(area) > 1e-9 * h * h
    t, area = t[:, good], area[good]
    t[[1, 2]] = np.where(area < 0, t[[2, 1]], t[[1, 2]])  # counter-clockwise
    if np.unique(t).size != P.shape[1]:
        raise RuntimeError("mesh: some nodes were left out of the triangulation")
    edges = {tuple(sorted(e)) for k in range(3) for e in zip(t[k], t[(k + 1) % 3])}
    for ids in slit_ids:
        if any(tuple(sorted(e)) not in edges for e in itertools.pairwise(ids)):
            raise RuntimeError("mesh: a baffle is not along mesh edges; try another h_target")

    # slits: double every baffle node but the tips, the copy for the elements right of it
    centre_s = P[0, t].mean(axis=0)
    newp = [P]
    count = P.shape[1]
    for (s, zs, ends), ids in zip(slits, slit_ids):
        for i, node in enumerate(ids):
            if (i == 0 and not ends[0]) or (i == len(ids) - 1 and not ends[1]):
                continue  # a tip
            right = np.any(t == node, axis=0) & (centre_s > s)
            t[:, right] = np.where(t[:, right] == node, count, t[:, right])
            newp.append(P[:, [node]])
            count += 1
    mesh = MeshTri1(np.ascontiguousarray(np.hstack(newp)), np.ascontiguousarray(t))

    def wall_facets(m):  # boundary facets on the curved wall: not the surface, not a baffle
        bf = m.boundary_facets()
        ends = m.p[:, m.facets[:, bf]]  # (2, 2, facets)
        flat = np.all(np.abs(ends[1] - d) < tol, axis=0)
        for s, _, _ in slits:
            flat |= np.all(np.abs(ends[0] - s) < tol, axis=0)
        return bf[~flat]

    def on_circle(x, nodes):  # x with the given nodes moved radially onto the circle
        R, x = section.radius, x.copy()
        r = x[:, nodes] - R
        x[:, nodes] = R + R * r / np.linalg.norm(r, axis=0)
        return x

    for level in range(tip_refinements):  # graded refinement round the tips and corners
        if not tips + corners:
            break
        radius = 1.5 * h * 0.5**level
        centres = mesh.p[:, mesh.t].mean(axis=1)
        near = np.zeros(mesh.t.shape[1], dtype=bool)
        for ts, tz in tips + corners:
            near |= np.hypot(centres[0] - ts, centres[1] - tz) < radius
        mesh = mesh.refined(np.nonzero(near)[0])
        if section.is_circle:  # the new wall nodes onto the circle, before the next level
            wall = mesh.facets[:, wall_facets(mesh)].ravel()
            mesh = replace(mesh, doflocs=on_circle(mesh.p, wall))

    adjacency = sp.coo_matrix((np.ones(3 * mesh.t.shape[1]),
                               (mesh.t.ravel(), np.roll(mesh.t, 1, axis=0).ravel())),
                              shape=(mesh.p.shape[1],) * 2)
    pools = connected_components(adjacency, directed=False)[0]

    if section.is_circle:  # curved wall: P2 geometry with the wall's nodes on the circle
        mesh = MeshTri2.from_mesh(mesh)
        dofs = mesh.dofs.get_facet_dofs(wall_facets(mesh)).flatten()
        mesh = replace(mesh, doflocs=on_circle(mesh.doflocs, dofs))

    surface = mesh.facets_satisfying(lambda x: np.abs(x[1] - d) < tol, boundaries_only=True)
    return SectionMesh(mesh=mesh, surface=surface, tips=tuple(tips), pools=pools, width=sr - sl)


# ---------------------------------------------------------------------------------------------
# eigenproblem
# ---------------------------------------------------------------------------------------------


def _surface_mass(m: SectionMesh, basis, degree: int):
    """The free surface's mass matrix B = integral phi_i phi_j ds, element by element.

    The surface is straight and its P2 mid-side nodes at the middle, so the 1-D element matrices
    are exact: L/6 [[2, 1], [1, 2]] (P1) and L/30 [[4, -1, 2], [-1, 4, 2], [2, 2, 16]] (P2, ends
    then middle). (skfem's FacetBasis would do the same, but on the curved MeshTri2 it inverts
    the element map by Newton iteration to an absolute 1e-12, which fails on the tiniest graded
    elements.)"""
    f = m.surface
    ends = m.mesh.facets[:, f]
    length = np.hypot(*(m.mesh.p[:, ends[1]] - m.mesh.p[:, ends[0]]))
    dofs = [basis.nodal_dofs[0, ends[0]], basis.nodal_dofs[0, ends[1]]]
    if degree == 1:
        local = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    else:
        dofs.append(basis.facet_dofs[0, f])
        local = np.array([[4.0, -1.0, 2.0], [-1.0, 4.0, 2.0], [2.0, 2.0, 16.0]]) / 30.0
    rows, cols, vals = [], [], []
    for i, di in enumerate(dofs):
        for j, dj in enumerate(dofs):
            rows.append(di)
            cols.append(dj)
            vals.append(local[i, j] * length)
    B = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(basis.N, basis.N))
    return B.tocsr()


def section_sloshing_lambdas(m: SectionMesh, n: int = 4, degree: int = 2, wavenumber: float = 0.0) -> np.ndarray:
    """The n lowest nonzero lambda = omega^2 / g of the Steklov problem on a meshed section.

    ``wavenumber`` k > 0: the modes phi(s, z) cos(k x) of the prism over the section (walls at
    the ends), for which the section's potential solves Laplace's equation less k^2 phi: the
    stiffness gets k^2 int phi psi, and no mode is trivial."""
    from skfem import Basis, BilinearForm, ElementTriP1, ElementTriP2
    from skfem.helpers import dot, grad

    elem = {1: ElementTriP1(), 2: ElementTriP2()}[degree]
    k2 = float(wavenumber) ** 2

    @BilinearForm
    def laplace(u, v, _):
        return dot(grad(u), grad(v)) + k2 * u * v

    basis = Basis(m.mesh, elem)
    K = laplace.assemble(basis).tocsr()
    pools = m.pools if k2 == 0.0 else 0
    B = _surface_mass(m, basis, degree)
    F = basis.get_dofs(m.surface).all()
    k = n + pools
    if F.size < 2 * k + 1:
        raise ValueError("too few surface nodes for n modes; refine")
    # Shift-invert Lanczos on the surface unknowns, about -c < 0. A = K + c B is positive
    # definite; B is zero off the surface, so the surface block of A^-1 is (S + c B_FF)^-1 with
    # S = K_FF - K_FI K_II^-1 K_IF the condensed (Dirichlet-to-Neumann) matrix: one sparse
    # factorisation of A, and S phi_F = lambda B_FF phi_F is solved without forming S.
    c = 1.0 / m.width
    lu = spla.splu((K + c * B).tocsc())

    def surface_solve(x):
        rhs = np.zeros(basis.N)
        rhs[F] = np.ravel(x)
        return lu.solve(rhs)[F]

    op = spla.LinearOperator((F.size, F.size), matvec=surface_solve, dtype=float)
    BFF = B[F][:, F].tocsc()
    v0 = np.random.default_rng(0).standard_normal(F.size)  # fixed: reproducible to the bit
    lam = spla.eigsh(op, k=k, M=BFF, sigma=-c, which="LM", OPinv=op, ncv=max(2 * k + 1, 20),
                     v0=v0, return_eigenvectors=False)
    lam = np.sort(lam)
    zero, rest = lam[:pools], lam[pools:]
    if pools and np.max(np.abs(zero)) > 1e-6 * rest[0]:
        raise RuntimeError(f"trivial modes not found near zero: {lam}")
    return rest


def section_sloshing_omegas(boundary: Section, fill_depth: float, g: float = G, n: int = 4,
                            baffles=(), h_target: float | None = None, degree: int = 2,
                            tip_refinements: int = 8) -> np.ndarray:
    """The n lowest sloshing frequencies omega (rad/s) of a liquid section, 2-D.

    ``boundary``: the tank section (:func:`rectangle`, :func:`prismatic`, :func:`circle`,
    :func:`polygon`), s from its left wall, z from its bottom; the liquid fills it up to
    z = ``fill_depth``. ``baffles``: :class:`Baffle` plates. ``h_target``: element size (default
    :func:`default_h`); ``degree``: 2 (P2, default) or 1. Solves K phi = (omega^2/g) B phi (see
    the module's docstring) and drops the trivial mode(s) phi = constant.

    Modes of a section are the tank's modes uniform along its length (a prismatic tank's
    transverse modes, a horizontal cylinder's transverse modes).
    """
    m = section_mesh(boundary, fill_depth, baffles, h_target, tip_refinements)
    return np.sqrt(g * section_sloshing_lambdas(m, n, degree))


def prism_sloshing_omegas(boundary, fill_depth: float, length: float, g: float = G, n: int = 6,
                          h_target: float | None = None, degree: int = 2, baffles=()) -> tuple[np.ndarray, np.ndarray]:
    """The n lowest sloshing frequencies (rad/s) of the prism of the section over 0 <= x <= ``length``
    (end walls), 3-D: separated as phi(s, z) cos(m pi x / length), each m a section problem with
    wavenumber m pi / length (:func:`section_sloshing_lambdas`). Returns (omega (n,), m (n,)), the
    longitudinal order of each mode: m = 0 are the section's own modes, m > 0 vary along the length
    (along a sloping wall they include edge waves, omega^2 ~ g k sin(slope), lower than a box's).
    ``boundary``: a :class:`Section` (with ``baffles``: plates along the whole length), or the
    rectangles of a union (:func:`u_tube`; ``h_target`` then required)."""
    if isinstance(boundary, Section):
        m = section_mesh(boundary, fill_depth, baffles, h_target)
    else:
        m = rectilinear_section_mesh(boundary, fill_depth, float(h_target))
    out, order = [], []
    for j in range(n + 1):
        lam = section_sloshing_lambdas(m, n, degree, wavenumber=j * math.pi / length)
        out.append(lam)
        order.append(np.full(len(lam), j))
        if j and lam[0] > np.sort(np.concatenate(out))[n - 1]:
            break
    lam, order = np.concatenate(out), np.concatenate(order)
    keep = np.argsort(lam, kind="stable")[:n]
    return np.sqrt(g * lam[keep]), order[keep]


# ---------------------------------------------------------------------------------------------
# sections that are not convex: unions of rectangles (a U-tube)
# ---------------------------------------------------------------------------------------------


def u_tube(length: float, reservoir: float, duct: float, height: float) -> tuple:
    """A U-tube anti-roll tank's section as rectangles (s0, s1, z0, z1): two reservoirs
    ``reservoir`` wide at the ends of a section ``length`` long and ``height`` high, joined along
    the bottom by a duct ``duct`` high (closed above). Pass it to
    :func:`rectilinear_sloshing_omegas`."""
    if not 0 < 2 * reservoir < length or not 0 < duct < height:
        raise ValueError("a U-tube needs 2 reservoir < length and 0 < duct < height")
    return ((0.0, reservoir, 0.0, height), (reservoir, length - reservoir, 0.0, duct),
            (length - reservoir, length, 0.0, height))


def rectilinear_section_mesh(rects, fill_depth: float, h_target: float,
                             corner_refinements: int = 8) -> SectionMesh:
    """Triangular mesh of the liquid in a union of axis-parallel rectangles (s0, s1, z0, z1)
    below z = ``fill_depth`` (it need not be convex: a U-tube).

    A tensor grid through every rectangle's sides and the fill level, spacing <= h, each cell cut
    into two triangles, the cells outside every rectangle dropped. Re-entrant corners (the liquid's
    angle 270 degrees: the potential there goes like r^(2/3)) are refined ``corner_refinements``
    times as the baffles' tips are (red-green, ring radius halved each time). The free surface is
    every boundary facet at z = fill_depth; it may be in several pieces (both reservoirs)."""
    from skfem import MeshTri1

    d = float(fill_depth)
    h = float(h_target)
    rects = [tuple(float(v) for v in r) for r in rects]
    wet = [(s0, s1, z0, min(z1, d)) for s0, s1, z0, z1 in rects if z0 < d]

    def lines(values):
        values = sorted(set(values))
        out = [values[0]]
        for a, b in itertools.pairwise(values):
            n = max(1, math.ceil((b - a) / h - 1e-9))
            out += list(a + (b - a) * np.arange(1, n + 1) / n)
        return np.array(out)

    xs = lines([v for r in wet for v in r[:2]])
    zs = lines([v for r in wet for v in r[2:]])
    mesh = MeshTri1.init_tensor(xs, zs)
    scale = max(xs[-1] - xs[0], zs[-1] - zs[0])
    tol = 1e-9 * scale

    def inside(P):
        return np.any([(P[0] > s0) & (P[0] < s1) & (P[1] > z0) & (P[1] < z1) for s0, s1, z0, z1 in wet], axis=0)

    centres = mesh.p[:, mesh.t].mean(axis=1)
    mesh = mesh.remove_elements(np.nonzero(~inside(centres))[0])
    used = np.unique(mesh.t)
    remap = np.full(mesh.p.shape[1], -1)
    remap[used] = np.arange(used.size)
    mesh = MeshTri1(np.ascontiguousarray(mesh.p[:, used]), np.ascontiguousarray(remap[mesh.t]))

    # re-entrant corners: a rectangle's corner with liquid in three of the four quadrants round it
    corners = []
    e = 1e-6 * scale
    for s0, s1, z0, z1 in wet:
        for s, z in ((s0, z0), (s0, z1), (s1, z0), (s1, z1)):
            q = np.array([[s - e, s + e, s - e, s + e], [z - e, z - e, z + e, z + e]])
            if inside(q).sum() == 3 and (s, z) not in corners:
                corners.append((s, z))
    for level in range(corner_refinements):
        if not corners:
            break
        radius = 1.5 * h * 0.5**level
        c = mesh.p[:, mesh.t].mean(axis=1)
        near = np.zeros(mesh.t.shape[1], dtype=bool)
        for s, z in corners:
            near |= np.hypot(c[0] - s, c[1] - z) < radius
        mesh = mesh.refined(np.nonzero(near)[0])

    adjacency = sp.coo_matrix((np.ones(3 * mesh.t.shape[1]),
                               (mesh.t.ravel(), np.roll(mesh.t, 1, axis=0).ravel())),
                              shape=(mesh.p.shape[1],) * 2)
    pools = connected_components(adjacency, directed=False)[0]
    surface = mesh.facets_satisfying(lambda x: np.abs(x[1] - d) < tol, boundaries_only=True)
    ends = mesh.p[0, mesh.facets[:, surface]]
    width = float(np.sum(np.abs(ends[1] - ends[0])))
    return SectionMesh(mesh=mesh, surface=surface, tips=tuple(corners), pools=pools, width=width)


def rectilinear_sloshing_omegas(rects, fill_depth: float, g: float = G, n: int = 4,
                                h_target: float | None = None, degree: int = 2,
                                corner_refinements: int = 8) -> np.ndarray:
    """The n lowest sloshing frequencies omega (rad/s) of the liquid in a union of rectangles
    (:func:`u_tube`), 2-D: the same Steklov problem as :func:`section_sloshing_omegas`.
    ``h_target``: element size (default: 1/20 of the fill depth)."""
    h = float(fill_depth) / 20.0 if h_target is None else float(h_target)
    m = rectilinear_section_mesh(rects, fill_depth, h, corner_refinements)
    return np.sqrt(g * section_sloshing_lambdas(m, n, degree))


def richardson(values, ratio: float = 2.0):
    """(limit, observed order) from three values on meshes refined by ``ratio`` each time
    (Richardson extrapolation with the observed order p: e_k ~ C h_k^p)."""
    f1, f2, f3 = (np.asarray(v, dtype=float) for v in values)
    d12, d23 = f1 - f2, f2 - f3
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.log(np.abs(d12 / d23)) / math.log(ratio)
    p = np.where(np.isfinite(p) & (p > 0.5), p, 2.0)
    return f3 - d23 / (ratio**p - 1.0), p
