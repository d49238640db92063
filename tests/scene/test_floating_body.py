"""The scene's rigid floating bodies as one family (docs/design.md): an abstract `FloatingBody` with
the vessel and the `[[bodies]]` body as its two finals, whose shared fields and rest pose code reads
alike, and whose constructors are the ones they always had."""
import dataclasses
import math

import numpy as np
import pytest

from jaxslosh.scene.types import Body, FloatingBody, Hydrostatics, Vessel

I3 = ((1.0, 0.0, 0.0), (0.0, 2.0, 0.0), (0.0, 0.0, 3.0))
HS = Hydrostatics(waterplane_area=10.0, displaced_volume=5.0, gm_t=1.0, gm_l=2.0)


def test_the_base_is_abstract_and_the_two_are_its_finals():
    with pytest.raises(TypeError):
        FloatingBody()
    assert FloatingBody.__subclasses__() == [Vessel, Body]
    assert all(getattr(c, "__final__", False) for c in (Vessel, Body))


def test_the_shared_fields_are_each_finals_own():
    shared = set(FloatingBody.__annotations__)
    assert {"name", "mass", "inertia", "hydrostatics", "initial", "hull", "hydrodynamics", "cog_height",
            "footprint"} == shared
    for c in (Vessel, Body):
        assert shared <= {f.name for f in dataclasses.fields(c)}, c


def test_the_constructors_keep_their_orders():
    v = Vessel(1.0e5, I3, HS)
    b = Body("barge", 2.0e4, I3, HS, (30.0, -4.0), 0.25)
    assert (v.mass, v.hydrostatics, v.name) == (1.0e5, HS, "vessel")
    assert (b.name, b.position, b.heading, b.cog_height) == ("barge", (30.0, -4.0), 0.25, 0.0)


def test_the_rest_point_of_each():
    """A point of its frame at rest: the vessel's frame is the one the bodies' places are given in (its
    COG at z = cog_height); a body's turns by its heading about its position."""
    v = Vessel(1.0e5, I3, HS, cog_height=1.5)
    assert (v.position, v.heading) == ((0.0, 0.0), 0.0)
    assert v.rest_point((2.0, -3.0, 4.0)) == (2.0, -3.0, 5.5)
    b = Body("barge", 2.0e4, I3, HS, (30.0, -4.0), math.pi / 2, cog_height=-0.5)
    np.testing.assert_allclose(b.rest_point((2.0, 1.0, 4.0)), (30.0 - 1.0, -4.0 + 2.0, 3.5), atol=1e-12)
