"""The tank-shape family (jaxslosh/geometry): each final shape's volume against its own mesh and its
own closed surface, its outline inside its bounding box, and the loader building it."""
import os

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.fem.mesh import box_mesh
from jaxslosh.fem.shapes import hex_volumes
from jaxslosh.geometry import SHAPES, AbstractShape, Baffle, Box, Cylinder, MeshFile, Prismatic

BAFFLED = Box(size=(4.0, 2.0, 2.0), baffles=(Baffle("x", 2.0, "bottom", 0.8), Baffle("x", 1.0, "top", 1.2)))
CASES = [  # (shape, fill depth, counts, relative tolerance of the mesh's volume)
    (Box(size=(4.0, 2.0, 2.0)), 1.2, (4, 2, 3), 1e-12),
    (BAFFLED, 1.2, (4, 2, 5), 1e-12),
    (Prismatic(size=(3.0, 6.0, 4.0), chamfers=((1.5, 1.0), (1.0, 0.8))), 3.5, (2, 8, 8), 1e-12),
    (Prismatic(size=(2.0, 2.0, 1.0), chamfers=((1.0, 1.0), (0.0, 0.0))), 0.8, (2, 8, 6), 1e-12),
    (Cylinder(size=(4.0, 4.0, 3.0), axis="z"), 2.0, (24, 24, 2), 5e-3),
    (Cylinder(size=(3.0, 2.0, 2.0), axis="x"), 0.6, (2, 32, 12), 5e-3),
    (Cylinder(size=(2.0, 3.0, 2.0), axis="y"), 1.4, (32, 2, 12), 5e-3),
]


def _enclosed(tris) -> float:
    """The volume a closed, outward triangulated surface encloses (divergence theorem)."""
    return float(np.einsum("ij,ij->i", tris[:, 0], np.cross(tris[:, 1], tris[:, 2])).sum() / 6.0)


def test_every_shape_is_final_frozen_and_named_by_its_key():
    assert list(SHAPES) == ["box", "prismatic", "cylinder", "mesh"]
    for name, cls in SHAPES.items():
        assert issubclass(cls, AbstractShape) and cls.name == name
        assert getattr(cls, "__final__", False), name
        assert cls.__dataclass_params__.frozen, name
    assert hash(Box(size=(1.0, 2.0, 3.0))) == hash(Box(size=(1.0, 2.0, 3.0)))   # meshes are cached by shape


@pytest.mark.parametrize("shape, depth, counts, rtol", CASES, ids=lambda c: getattr(c, "name", ""))
def test_volume_is_its_mesh_and_its_surface(shape, depth, counts, rtol):
    """volume(h) is the closed form of the shape; its mesh's hexahedra fill the same volume (exactly
    for plane-faced shapes, converging for the cylinders' mapped grids) and, filled to the top, the
    closed inner surface of the stability command encloses it."""
    tm = shape.mesh(depth, counts)
    v = shape.volume(depth)
    assert hex_volumes(tm.nodes, tm.elements).sum() == pytest.approx(v, rel=rtol)
    assert tm.depth == pytest.approx(depth)
    assert _enclosed(shape.surface()) == pytest.approx(shape.volume(shape.size[2] * (1 - 1e-12)), rel=1e-9)


@pytest.mark.parametrize("shape, depth, counts, rtol", CASES, ids=lambda c: getattr(c, "name", ""))
def test_outline_stays_in_the_bounding_box(shape, depth, counts, rtol):
    lines = shape.outline(depth)
    pts = np.concatenate(lines)
    assert len(lines) >= 4 + len(shape.baffles)
    assert np.all(pts >= -1e-12) and np.all(pts <= np.asarray(shape.size) + 1e-12)


def test_a_mesh_file_is_its_hexahedra(tmp_path):
    import meshio
    nodes, elements = box_mesh((3.0, 2.0, 1.5), (3, 2, 2))
    path = str(tmp_path / "liquid.msh")
    meshio.write(path, meshio.Mesh(nodes, [("hexahedron", elements)]), file_format="gmsh22")
    shape = MeshFile(size=(3.0, 2.0, 2.0), file=path)
    assert shape.volume(1.5) == pytest.approx(9.0, rel=1e-12)
    assert shape.box_counts(1.5) == (3, 2, 2)                        # a box grid: built as the box
    assert shape.locks(1.5) == (False, "a mesh file that is a box grid builds as the box")
    assert shape.mesh(1.5, (1, 1, 1)).grid == (3, 2, 2)


def test_the_loader_builds_the_shape_and_a_hand_made_tank_gets_it():
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    t = js.load_scene(os.path.join(root, "scenes", "type_c_tank.toml")).tanks[0]
    assert isinstance(t.geometry, Cylinder) and t.geometry.axis == t.axis and t.geometry.size == tuple(t.size)
    assert t.liquid_volume == pytest.approx(t.geometry.volume(t.fill_depth))
    from jaxslosh.scene.types import Tank
    hand = Tank("t", (0.0, 0.0, 0.0), (3.0, 6.0, 4.0), 2.0, (2, 4, 4), shape="prismatic",
                chamfers=((1.0, 1.0), (0.0, 0.0)))
    assert hand.geometry == Prismatic(size=(3.0, 6.0, 4.0), chamfers=((1.0, 1.0), (0.0, 0.0)))
    assert hand.liquid_volume == pytest.approx(3.0 * (6.0 * 2.0 - 1.0))
