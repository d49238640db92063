"""Bad input about [[bodies]] and [[connections]] that `jaxslosh check` refuses with exit status 2
naming the key (docs/guide/bodies-and-connections.md, what the loader checks): a connection point
outside its body's hull, two bodies overlapping at rest, a multibody file whose bodies are not the
scene's or stand elsewhere than the scene puts them."""
import os

import numpy as np
import pytest
import xarray as xr

import jaxslosh as js
from jaxslosh.cli import main

from two_boxes_scene import DATA, two_boxes

PAIR = """
title = "pair"
[simulation]
duration = 1.0
dt = 0.1
[vessel]
name = "ship"
mass = 4.1e5
inertia = [5.13e6, 1.474e7, 1.63e7]
footprint = [20.0, 10.0]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 400.0
gm_t = 1.67
gm_l = 14.2

[[bodies]]
name = "barge"
position = [0.0, 18.0]
mass = 2.05e5
inertia = [1.5e6, 6.0e6, 7.0e6]
footprint = [15.0, 8.0]
[bodies.hydrostatics]
waterplane_area = 120.0
displaced_volume = 200.0
gm_t = 2.5
gm_l = 20.0

[[connections]]
name = "bow_hawser"
kind = "hawser"
bodies = ["ship", "barge"]
points = [[10.0, 5.0, 2.0], [6.0, -4.0, 1.5]]
length = 9.8
stiffness = 2.0e5

[[connections]]
name = "fender"
kind = "fender"
bodies = ["ship", "barge"]
points = [[4.0, 5.0, -3.0], [4.0, -4.0, -3.0]]
length = 9.0
stiffness = 1.0e5
"""

BOX_HULL = """[vessel.hull]
type = "box"
length = 20.0
beam = 10.0
draft = 2.0
kg = 2.5
"""


def _check(tmp_path, capsys, text):
    p = tmp_path / "scene.toml"
    p.write_text(text)
    status = main(["check", str(p)])
    return status, capsys.readouterr()


def test_points_on_the_hulls_sides_are_inside(tmp_path, capsys):
    """The hawser's fairleads at the ship's bow corner and the barge's side, the fender's faces on
    both sides: inside (a side is the hull's own)."""
    status, out = _check(tmp_path, capsys, PAIR)
    assert status == 0, out.err


BAD_POINTS = [
    ("beyond the ship's bow", "[[10.0, 5.0, 2.0], [6.0", "[[10.5, 5.0, 2.0], [6.0", "connections[0].points",
     "x = 10.5 m outside [-10, 10]"),
    ("off the barge's port side (the other frame's sign)", "[6.0, -4.0, 1.5]", "[6.0, 4.5, 1.5]",
     "connections[0].points", "y = 4.5 m outside [-4, 4]"),
    ("the second fender's face", "[4.0, -4.0, -3.0]", "[4.0, -4.2, -3.0]", "connections[1].points",
     "point 2"),
]


@pytest.mark.parametrize("what,old,new,key,words", BAD_POINTS, ids=[b[0] for b in BAD_POINTS])
def test_a_connection_point_outside_its_bodys_footprint_exits_2(tmp_path, capsys, what, old, new, key, words):
    assert old in PAIR
    status, out = _check(tmp_path, capsys, PAIR.replace(old, new, 1))
    assert status == 2 and key in out.err and words in out.err, out.err


def test_the_vessels_box_hull_bounds_its_points_below_the_keel(tmp_path, capsys):
    """A box hull (kg 2.5 m: the keel 2.5 m below the COG) is the vessel's extent, its keel included:
    a fender 3 m below the COG is below it; at 2.5 m it touches it; the deck (no depth) is open."""
    text = PAIR.replace('footprint = [20.0, 10.0]\n', "").replace("[vessel.hydrostatics]", BOX_HULL
                                                                  + "[vessel.hydrostatics]")
    status, out = _check(tmp_path, capsys, text)
    assert status == 2 and "connections[1].points" in out.err and "below the keel at -2.5 m" in out.err, out.err
    status, out = _check(tmp_path, capsys, text.replace("[[4.0, 5.0, -3.0]", "[[4.0, 5.0, -2.5]")
                         .replace("[[10.0, 5.0, 2.0]", "[[10.0, 5.0, 40.0]"))
    assert status == 0, out.err


def test_a_body_without_extent_is_not_checked(tmp_path, capsys):
    """Without a footprint (or a hull) a body's points are taken as given."""
    text = PAIR.replace("footprint = [15.0, 8.0]\n", "").replace("[6.0, -4.0, 1.5]", "[60.0, -4.0, 1.5]")
    status, out = _check(tmp_path, capsys, text.replace("position = [0.0, 18.0]", "position = [0.0, 30.0]"))
    assert status == 0, out.err


def test_two_bodies_overlapping_at_rest_exit_2(tmp_path, capsys):
    """The footprints' rectangles (beams 10 and 8 m) overlap with the barge's COG 8 m abeam (a 1 m
    overlap); 9 m abeam they touch."""
    status, out = _check(tmp_path, capsys, PAIR.replace("position = [0.0, 18.0]", "position = [0.0, 8.0]"))
    assert status == 2 and "bodies[0].position" in out.err and "overlap at rest by 1 m" in out.err, out.err


def _placed(tmp_path, centres, key="rotation_center"):
    """two_boxes.nc with its bodies' centres stored as Capytaine does (dimensions body, space_coordinate)."""
    ds = xr.open_dataset(os.path.join(DATA, "two_boxes.nc"), engine="h5netcdf").load()
    ds = ds.assign_coords(body=["barge", "tender"], space_coordinate=["x", "y", "z"])
    ds = ds.assign_coords({key: (("body", "space_coordinate"), np.asarray(centres, dtype=float))})
    path = str(tmp_path / f"placed_{key}.nc")
    ds.to_netcdf(path, engine="h5netcdf")
    return two_boxes().replace(os.path.join(DATA, "two_boxes.nc"), path)


def test_a_multibody_files_centres_are_the_scenes_places(tmp_path):
    """Capytaine's generate.py put the barge's COG at (0, 0, -0.5) and the tender's at (0, 14, -0.5):
    the scene (the tender 14 m abeam, both COGs 0.5 m below the water) reads."""
    for key in ("rotation_center", "center_of_mass"):
        scene = js.load_scene(_placed(tmp_path, [[0, 0, -0.5], [0, 14, -0.5]], key))
        assert scene.bodies[0].position == (0.0, 14.0)


BAD_PLACES = [
    ("tender elsewhere", [[0, 0, -0.5], [0, 15, -0.5]], "bodies[0].position", "'tender' at x, y = 0, 15 m"),
    ("vessel off the origin", [[2, 0, -0.5], [0, 14, -0.5]], "vessel.hydrodynamics.file", "'barge' at x, y = 2, 0 m"),
    ("tender's rotation centre", [[0, 0, -0.5], [0, 14, -1.0]], "bodies[0].cog_height", "give cog_height = -1"),
    ("barge's rotation centre", [[0, 0, 0.0], [0, 14, -0.5]], "vessel.cog_height", "give cog_height = 0"),
]


@pytest.mark.parametrize("what,centres,key,words", BAD_PLACES, ids=[b[0] for b in BAD_PLACES])
def test_a_multibody_file_placing_a_body_elsewhere_exits_2(tmp_path, capsys, what, centres, key, words):
    status, out = _check(tmp_path, capsys, _placed(tmp_path, centres))
    assert status == 2 and key in out.err and words in out.err, out.err


def test_a_multibody_file_of_other_bodies_exits_2(tmp_path, capsys):
    status, out = _check(tmp_path, capsys, two_boxes().replace('name = "tender"', 'name = "tug"'))
    assert status == 2 and "bodies[0].hydrodynamics.file" in out.err and "'tug'" in out.err, out.err
