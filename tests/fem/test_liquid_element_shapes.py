"""The liquid elements' accuracy over the tank shapes (issue 30): 3-D modes of prismatic tanks,
V troughs and horizontal cylinders against the project's independent reference
(tests/sloshing_reference.py: a section's modes times cos(m pi x / L), every m, so that modes
varying along the length count too), vertical cylinders and boxes against closed forms.

Sloping walls hold Stokes edge waves: a tank only 0.2 m long has a pair of them (one per wall)
among its section modes, which is physical, not spurious: they are the reference's m = 1 modes."""
import os
import sys

import numpy as np
import pytest

from jaxslosh.liquid.face.element import build_face_liquid, face_modes
from jaxslosh.geometry import Cylinder, Prismatic

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import shape_cases  # noqa: E402
import sloshing_reference as ref  # noqa: E402

G, RHO, C = 9.81, 1000.0, 1500.0


def rt_modes(geo, depth, mesh, n):
    tm = geo.mesh(depth, mesh)
    m = build_face_liquid(tm.nodes, tm.elements, tm.depth, RHO, C, G)
    md = face_modes(m, n)
    assert all(k == "sloshing" for k in md.kind), md.kind
    return md, m


def v_trough(length):
    """A 90-degree V trough 2 m wide, 1 m high (chamfers meeting at the centre line)."""
    return Prismatic(size=(length, 2.0, 1.0), chamfers=((1.0, 1.0), (0.0, 0.0)))


def test_v_trough_and_quarter_full_cylinder_in_3d():
    """The issue's item 7 on its meshes: a 90-degree V trough filled to 0.8 m, 2 m long, 8x12x8
    (the stabilized element's 4th mode +4.3 %), and a horizontal cylinder R = 1 m filled to 0.5 m,
    2.4 m long, 12x16x6: rt's first 6 modes within 1.5 % of the 3-D reference, the next two
    within 2.5 %."""
    w, order = ref.prism_sloshing_omegas(ref.prismatic(2.0, 1.0, 1.0, 1.0), 0.8, 2.0, G, 8, h_target=0.04)
    md, _ = rt_modes(v_trough(2.0), 0.8, (8, 12, 8), 8)
    tol = np.array([0.015] * 6 + [0.025] * 2)
    assert np.all(np.abs(md.omega / w - 1) < tol), (md.omega, w, order)
    assert abs(md.omega[3] / w[3] - 1) < 0.0125
    w, order = ref.prism_sloshing_omegas(ref.circle(1.0), 0.5, 2.4, G, 8, h_target=0.04)
    md, _ = rt_modes(Cylinder(size=(2.4, 2.0, 2.0), axis="x"), 0.5, (12, 16, 6), 8)
    assert np.all(np.abs(md.omega / w - 1) < tol), (md.omega, w, order)
    assert abs(md.omega[2] / w[2] - 1) < 0.005


def test_the_pair_at_sloping_walls_is_edge_waves():
    """A V trough 0.2 m long (two elements): the degenerate pair among the section's modes is the
    reference's m = 1 pair (Stokes' edge waves, one per wall, half a wave along the 0.2 m): the
    surface moves up in one half of the length and down in the other, and refining along the
    length brings it to the reference (the section's six modes stay within 0.5 %)."""
    T = 0.2
    w, order = ref.prism_sloshing_omegas(ref.prismatic(2.0, 1.0, 1.0, 1.0), 0.8, T, G, 8, h_target=0.04)
    assert list(order) == [0] * 6 + [1, 1]
    errors = []
    for mesh in ((2, 24, 16), (4, 24, 16)):
        md, m = rt_modes(v_trough(T), 0.8, mesh, 8)
        xc = m.nodes[m.faces[m.top]].mean(axis=1)
        q = md.fluxes[:, m.top]
        # odd about the middle of the length, face by face: the surface at x against its mirror at
        # T - x. (A sum over the surface, q @ cos(pi x / T) against q @ 1 as it was, is zero for the
        # pair's member that is also odd across the trough, and round-off for the section's modes,
        # whose surface is the same along the length: which round-off was larger depended on the BLAS.)
        mirrored = np.c_[T - xc[:, 0], xc[:, 1:]]
        mirror = np.argmin(np.linalg.norm(mirrored[:, None, :] - xc[None, :, :], axis=2), axis=1)
        assert np.allclose(xc[mirror], mirrored, atol=1e-9)
        odd = np.linalg.norm(q - q[:, mirror], axis=1) > np.linalg.norm(q + q[:, mirror], axis=1)
        pair = np.flatnonzero(odd)
        assert len(pair) == 2 and abs(md.omega[pair[0]] / md.omega[pair[1]] - 1) < 1e-6, md.omega
        rest = np.setdiff1d(np.arange(8), pair)
        assert np.all(np.abs(md.omega[rest[:6]] / w[:6] - 1) < 0.005), md.omega
        errors.append(abs(md.omega[pair[0]] / w[6] - 1))
    assert errors[1] < 0.015 and errors[1] < errors[0]


def stabilized_sloshing(geo, depth, mesh, n):
    from jaxslosh.liquid.nodal.model import build_liquid
    from jaxslosh.liquid.modes import liquid_modes
    model = build_liquid(geo.size, depth, mesh, RHO, C, G, element="stabilized", sparse=True, geometry=geo)
    md = liquid_modes(model, n=2 * n + 4)
    kind = np.array(md.kind)
    assert np.all(kind[:n] == "sloshing"), kind        # nothing else below the first n sloshing modes
    return md.omega[:n]


@pytest.mark.parametrize("chamfer", [(1.0, 0.3), (4.0, 0.5)])
def test_low_hopper_is_not_locked(chamfer):
    """A hopper flatter than 30 degrees, filled above it: an 8 m x 1.5 m section with (1.0, 0.3)
    chamfers, and a flat V bottom ((4.0, 0.5), chamfers meeting), filled to 1.2 m, 2x16x4. Layered
    as steeper hoppers are, the stabilized element's first mode was 1.836 rad/s against 1.299 (+41 %):
    the element at the kink had its floor and chamfer on one smooth wall, and the penalty holding
    that corner locked the liquid. With the layers following the bottom both elements are within
    0.5 % on the first mode, 1.5 % on the first three."""
    w = ref.section_sloshing_omegas(ref.prismatic(8.0, 1.5, *chamfer), 1.2, G, 3, h_target=0.05)
    geo = Prismatic(size=(0.2, 8.0, 1.5), chamfers=(chamfer, (0.0, 0.0)))
    tm = geo.mesh(1.2, (2, 16, 4))
    assert not tm.flat.any()
    for omega in (stabilized_sloshing(geo, 1.2, (2, 16, 4), 3), rt_modes(geo, 1.2, (2, 16, 4), 3)[0].omega):
        assert abs(omega[0] / w[0] - 1) < 0.005 and np.all(np.abs(omega / w - 1) < 0.015), (omega, w)


# --- every shape on about 1,000 elements (tests/shape_cases.py) --------------------------------


FAST = "horizontal_cylinder_50"


@pytest.mark.parametrize("name", [pytest.param(c, marks=() if c == FAST else pytest.mark.slow)
                                  for c in shape_cases.CASES + shape_cases.LNG_FILLS])
def test_every_shape_first_six_modes_within_2_5_percent(name):
    """The issue's "every shape": the first 6 sloshing modes within 2.5 % of the reference on a mesh
    of about 1,000 elements (560 to 1,024), with the element shape_cases.ELEMENT names ("rt" but for
    the box and the low hopper), and no other kind of mode among them."""
    geo, depth, mesh, element, w = shape_cases.case(name)
    omega, n_el, kinds = shape_cases.sloshing_omegas(geo, depth, mesh, element)
    assert 900 <= n_el <= 1100, n_el
    assert all(k == "sloshing" for k in kinds), kinds
    assert np.all(np.abs(omega / w - 1) < 0.025), (omega, w)
