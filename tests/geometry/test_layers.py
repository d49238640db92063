"""The layers of the section mesher (geometry/section.py): for the face-normal element graded
toward the surface, every band between the section's kinks (and between a kink and the bottom or
the surface) two layers or more, the element count the user asked; for the nodal elements the
layers spread in proportion to the bands (fem/shapes.py `breaks`)."""
import numpy as np
import pytest

from jaxslosh.fem.shapes import breaks, surface_layers
from jaxslosh.geometry import Baffle, Box, Prismatic

LNG = Prismatic(size=(0.2, 1.0, 1.0), chamfers=((0.2, 0.2), (0.2, 0.2)))


def heights(geo, fill, counts, graded=True):
    tm = geo.mesh(fill, counts, graded=graded)
    return np.unique(np.round(tm.nodes[:, 2][_column(tm)], 12))


def _column(tm):
    """The nodes of the mesh's middle column (x = 0, the centre line of the section)."""
    y = tm.nodes[:, 1]
    return (tm.nodes[:, 0] == 0.0) & np.isclose(y, 0.5)


@pytest.mark.parametrize("fill", [0.3, 0.5, 0.85, 0.95])
@pytest.mark.parametrize("nz", [8, 16, 32])
def test_every_band_has_two_layers_thinner_toward_the_surface(fill, nz):
    z = heights(LNG, fill, (2, 24, nz))
    assert len(z) == nz + 1 and z[0] == 0.0 and z[-1] == fill
    kinks = [k for k in (0.2, 0.8) if k < fill]
    for k in kinks:                                   # every kink on a layer
        assert np.abs(z - k).min() < 1e-12
    ends = [0.0] + kinks + [fill]
    for lo, hi in zip(ends[:-1], ends[1:]):           # two layers or more in every band
        assert np.sum((z > lo + 1e-12) & (z <= hi + 1e-12)) >= 2, (lo, hi, z)
    dz = np.diff(z)
    top = dz[z[1:] > ends[-2] + 1e-12]
    assert np.all(np.diff(top) < 0)                   # thinner toward the surface within its band
    assert dz[-1] < fill / nz                         # and the surface layer thinner than an even one


def test_the_nodal_elements_keep_the_proportional_layers():
    """Their one-point curl locks on thin layers at a top chamfer's kink (the LNG section at 85 % on
    2x24x16: the stabilized element's second mode +0.63 % with that band split in two, -0.18 %
    with one layer), so `graded=False` is `breaks`: one layer of 0.05 m under the surface there."""
    z = heights(LNG, 0.85, (2, 24, 16), graded=False)
    np.testing.assert_allclose(z, breaks(0.0, 0.85, [0.2, 0.8], 16))
    assert np.sum(z > 0.8 + 1e-12) == 1


def test_a_plain_box_and_a_fill_within_the_hopper_keep_even_layers():
    """No kink below the surface: even layers (a box's grid and its traced fill depth rely on them)."""
    np.testing.assert_allclose(heights(Box(size=(0.2, 1.0, 1.0)), 0.6, (2, 4, 6)), np.linspace(0, 0.6, 7))
    np.testing.assert_allclose(heights(LNG, 0.15, (2, 24, 5)), np.linspace(0, 0.15, 6))


def test_baffles_keep_proportional_layers_two_a_band():
    """A baffle's edge is a kink; graded toward the surface the layers would thicken at a hanging
    plate's edge, where the flow is singular, so a tank with baffles keeps `breaks`' layers, two or
    more a band."""
    geo = Box(size=(0.2, 1.0, 1.0), baffles=(Baffle("y", 0.5, "top", 0.8),))
    z = np.unique(np.round(geo.mesh(0.45, (2, 18, 9)).nodes[:, 2], 12))
    np.testing.assert_allclose(z, breaks(0.0, 0.45, [0.2], 9, least=2), atol=1e-12)
    assert np.abs(z - 0.2).min() < 1e-12 and np.sum(z > 0.2 + 1e-12) == 5     # 0.25 m of 0.45: 5 of 9
    z = breaks(0.0, 0.45, [0.44], 9, least=2)
    assert np.sum(z > 0.44 + 1e-12) == 2 and len(z) == 10
    assert np.sum(breaks(0.0, 0.45, [0.44], 9) > 0.44 + 1e-12) == 1


def test_too_few_layers_for_the_kinks():
    with pytest.raises(ValueError, match="mesh\\[2\\]"):
        surface_layers(0.9, [0.2, 0.8], 2, 1.0)
    z = surface_layers(0.9, [0.2, 0.8], 4, 1.0)       # fewer than two per band: one at least
    assert len(z) == 5 and all(np.abs(z - k).min() < 1e-12 for k in (0.2, 0.8))
