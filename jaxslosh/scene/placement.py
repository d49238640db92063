"""Where floating bodies lie at rest, as the scene's checks see them: a waterplane's outline (its
`footprint`, else its hull's plan, else the circle of its area), the overlap of two, and a hull's
extent in its body's frame (docs/guide/bodies-and-connections.md). No JAX."""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .fields import show
from ..hull.surface import HullMeshError
from .types import FloatingBody, SceneError


def read_footprint(table, where: str) -> Optional[tuple]:
    """`footprint = [length, beam]`: the waterplane's extent at rest (m), along the body's x axis and
    across it, for the overlap check; None when absent."""
    f = table.get("footprint") if isinstance(table, dict) else None
    if f is None:
        return None
    if not (isinstance(f, list) and len(f) == 2 and all(isinstance(c, (int, float)) and not isinstance(c, bool)
                                                          and math.isfinite(c) and c > 0 for c in f)):
        raise SceneError(f"{where}.footprint", f"must be [length, beam], two positive numbers (m), got {show(f)}")
    return (float(f[0]), float(f[1]))


def footprint_radius(area: float) -> float:
    """The radius of the circle of a waterplane's area: the footprint the overlap check compares."""
    return math.sqrt(area / math.pi)


def outline(centre, heading, footprint, area, shift=(0.0, 0.0)):
    """A waterplane at rest as the overlap check sees it: ("rect", its centre, its axes (2, 2), half
    sizes) for a footprint (its centre `shift` from the COG along the body's axes), else ("circle",
    centre, radius) of its area."""
    if footprint is None:
        return ("circle", np.asarray(centre, dtype=float), footprint_radius(area))
    c, s = math.cos(heading), math.sin(heading)
    axes = np.array([[c, s], [-s, c]])
    return ("rect", np.asarray(centre, dtype=float) + axes.T @ np.asarray(shift, dtype=float), axes,
            0.5 * np.asarray(footprint))


def plan(f, key: str):
    """(footprint, its centre from the COG) for the overlap check: its `footprint`, else its hull's
    plan (which bounds its waterplane), else (None, 0): the circle of its waterplane's area."""
    if f.footprint is not None or f.hull is None:
        return f.footprint, (0.0, 0.0)
    lo, hi = (np.asarray(v[:2]) for v in hull_extent(f, key))
    return tuple(hi - lo), tuple(0.5 * (hi + lo))


def apart(a, b) -> float:
    """A separation of two outlines: positive when they do not intersect, negative when they do (for two
    circles their gap; otherwise the largest gap along a separating axis, the rectangles' axes and, for a
    circle, the line from its centre to the rectangle's nearest point)."""
    if a[0] == "circle" and b[0] == "circle":
        return float(np.linalg.norm(a[1] - b[1]) - a[2] - b[2])
    if a[0] == "circle":
        a, b = b, a
    if b[0] == "circle":      # a rectangle and a circle: the circle's centre from the rectangle
        local = a[2] @ (b[1] - a[1])
        outside = np.maximum(np.abs(local) - a[3], 0.0)
        inside = float(np.min(a[3] - np.abs(local)))
        return float(np.linalg.norm(outside)) - b[2] if outside.any() else -inside - b[2]

    def half(r, axis):        # a rectangle's half extent along a unit axis
        return float(np.sum(r[3] * np.abs(r[2] @ axis)))
    d = b[1] - a[1]
    return max(abs(float(d @ axis)) - half(a, axis) - half(b, axis) for axis in (*a[2], *b[2]))


def refuse_overlaps(bodies, vessel) -> None:
    """Two bodies whose waterplanes intersect at rest are refused: they would float through each other
    (no contact is modelled but by fenders). A waterplane is the rectangle of its `footprint` along its
    heading where given, else its hull's plan, else the circle of its area about its COG."""
    keys = ["vessel.hull.file"] + [f"bodies[{i}].hull.file" for i in range(len(bodies))]
    outlines = []
    for f, key in zip((vessel, *bodies), keys):
        if f.hydrostatics is not None:
            footprint, shift = plan(f, key)
            outlines.append(("vessel" if f is vessel else f.name, np.asarray(f.position, dtype=float),
                             outline(f.position, f.heading, footprint, f.hydrostatics.waterplane_area, shift)))
    for j, (nb, pb, ob) in enumerate(outlines):
        for na, pa, oa in outlines[:j]:
            gap = apart(oa, ob)
            if gap >= 0:
                continue
            i = [b.name for b in bodies].index(nb)
            dist = float(np.linalg.norm(pa - pb))
            if oa[0] == ob[0] == "circle":
                raise SceneError(f"bodies[{i}].position", (
                    f"{show(list(pb))} puts {nb!r} {dist:.6g} m from {na!r}: their waterplanes (as circles of their "
                    f"areas, radii {ob[2]:.4g} and {oa[2]:.4g} m) overlap at rest; place the bodies at least "
                    f"{oa[2] + ob[2]:.6g} m apart, or give their `footprint` (length, beam)"))
            raise SceneError(f"bodies[{i}].position", (
                f"{show(list(pb))} puts {nb!r} {dist:.6g} m from {na!r}: their waterplanes (rectangles of their "
                f"`footprint` or their hull's plan, circles of their areas without either) overlap at rest by "
                f"{-gap:.4g} m"))


def hull_extent(owner: FloatingBody, key: str = "vessel.hull.file") -> Optional[tuple]:
    """((x_min, y_min, z_min or -inf), (x_max, y_max)) of a body's (or the vessel's) hull in its frame
    from its COG, what the connection points are checked against: its hull where it has one (its
    plan and its keel), else the rectangle of a `footprint` about the COG (its plan only: a
    footprint has no keel), else None (nothing to check against). `key`: the hull's file key."""
    if owner.hull is not None:
        try:
            return owner.hull.extent()
        except HullMeshError as e:
            raise SceneError(key, str(e)) from None
    if owner.footprint is not None:
        half = 0.5 * np.asarray(owner.footprint)
        return (-half[0], -half[1], -math.inf), (half[0], half[1])
    return None
