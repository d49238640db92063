"""Writes parametric_roll_hull.obj: a 10 m hull, wall-sided amidships and flared towards both ends
(V-shaped below the waterline there), the shape whose stability changes with the wave crest's
position along it (docs/guide/large-angles.md). File coordinates: waterline at z = 0 (draft 1 m), keel
at z = -1, deck at z = +1. Run from the repository root: python scenes/parametric_roll_hull.py"""
import os

import numpy as np

from jaxslosh.hull.surface import loft_surface, refine_outline, write_hull_mesh

LENGTH, DEPTH, DRAFT = 10.0, 2.0, 1.0
MID_HALF_BEAM = 1.4                  # wall-sided amidships
END_KEEL, END_DECK = 0.5, 2.2        # half-widths at the ends: keel, deck
FLARE_POWER = 3                      # how fast the flare grows towards the ends


def hull(nx=40, nz=4):
    x = np.linspace(-LENGTH / 2, LENGTH / 2, nx + 1)
    w = np.abs(2 * x / LENGTH) ** FLARE_POWER
    keel = MID_HALF_BEAM * (1 - w) + END_KEEL * w
    deck = MID_HALF_BEAM * (1 - w) + END_DECK * w
    sections = [refine_outline([[-k, 0.0], [k, 0.0], [d, DEPTH], [-d, DEPTH]], nz) for k, d in zip(keel, deck)]
    return loft_surface(x, np.array(sections)) - np.array([0.0, 0.0, DRAFT])


if __name__ == "__main__":
    write_hull_mesh(os.path.join(os.path.dirname(os.path.abspath(__file__)), "parametric_roll_hull.obj"), hull())
