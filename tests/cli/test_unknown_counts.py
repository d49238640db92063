"""`jaxslosh check`'s unknowns (assemble/effects.py count_unknowns, also assemble/cost.py) against the
assembled system's size: the face-normal element's free faces, and its elastic walls' nodal dofs,
for a box, a prismatic tank, a U-tube from a mesh file and a tank in elastic walls; the stabilized
element's nodal count beside them."""
import os
import sys

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.cost import estimate
from jaxslosh.assemble.effects import count_unknowns
from jaxslosh.assemble.system import build

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from section_meshes import u_tube_hex  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

SHIP = """
title = "counts"
[simulation]
duration = 0.02
dt = 0.01
[vessel]
mass = 2.0e4
inertia = [1.0e4, 2.0e4, 2.0e4]
[vessel.hydrostatics]
waterplane_area = 20.0
displaced_volume = 20.0
gm_t = 1.0
gm_l = 5.0
[[tanks]]
name = "tank"
origin = [-0.5, -1.0, -0.5]
{tank}
[tanks.fluid]
element = "{element}"
"""

TANKS = {
    "box": 'size = [1.0, 2.0, 1.5]\nfill_depth = 1.0\nmesh = [3, 4, 2]',
    "prismatic": 'shape = "prismatic"\nchamfers = [[0.5, 0.4], [0.2, 0.2]]\nsize = [1.0, 2.0, 1.5]\n'
                 'fill_depth = 1.2\nmesh = [2, 6, 4]',
    "mesh": 'shape = "mesh"\nfile = "u_tube.msh"\nsize = [0.2, 2.0, 1.0]',
}


def _counts(scene):
    """(check's count, the cost's, the assembled system's unknowns)."""
    return count_unknowns(scene), estimate(scene).unknowns, 6 + build(scene).system.nf


@pytest.mark.parametrize("shape", sorted(TANKS))
@pytest.mark.parametrize("element", ["rt", "stabilized"])
def test_the_counted_unknowns_are_the_assembled_ones(shape, element, tmp_path):
    if shape == "mesh":
        meshio = pytest.importorskip("meshio")
        nodes, elements = u_tube_hex(2.0, 0.5, 0.3, 0.8, 8, 6, thickness=0.2, nx=1)
        meshio.write(str(tmp_path / "u_tube.msh"), meshio.Mesh(nodes, [("hexahedron", elements)]),
                     file_format="gmsh22")
    path = tmp_path / "scene.toml"
    path.write_text(SHIP.format(tank=TANKS[shape], element=element))
    scene = js.load_scene(str(path))
    shown, cost, built = _counts(scene)
    assert shown == cost == built
    if element == "rt" and shape == "box":          # the interior faces and the top's, by hand
        assert built - 6 == 2 * 4 * 2 + 3 * 3 * 2 + 3 * 4 * 1 + 3 * 4


def test_the_counted_unknowns_of_rt_in_elastic_walls():
    """The elastic-walls scene with "rt": the free faces and the walls' free nodal dofs."""
    text = open(os.path.join(ROOT, "scenes", "paper_ship_elastic_tank.toml")).read()
    text = text.replace("mesh = [5, 5, 5]", "mesh = [3, 3, 2]").replace("[tanks.fluid]",
                                                                           '[tanks.fluid]\nelement = "rt"')
    scene = js.load_scene(text)
    shown, cost, built = _counts(scene)
    assert shown == cost == built
    assert np.isfinite(built)
