"""A nodal liquid element in a re-entrant tank (issue 43, item 10): a U-tube or a baffled tank with
element = "stabilized" loses a whole mode silently (docs/guide/liquid-element.md, "Why rt"). The
loader warns, once, where the tank is re-entrant (a U-tube's duct roof, a slit or a baffle in the
liquid) and the element is nodal; never for "rt" or a convex tank."""
import os
import sys

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli.main import main

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from section_meshes import section_hex, u_tube_hex  # noqa: E402

meshio = pytest.importorskip("meshio")

SHIP = """
title = "locking"
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
origin = [-0.1, -1.0, -0.5]
{tank}
"""
MESH = 'shape = "mesh"\nfile = "tank.msh"\nsize = [0.2, 2.0, 1.0]\n'
ELEMENT = '[tanks.fluid]\nelement = "{}"\n'
BAFFLE = '[[tanks.baffles]]\nnormal = "y"\nposition = 1.0\nfrom = "{}"\nheight = {}\n'
BOX = "size = [0.2, 2.0, 1.0]\nfill_depth = 0.6\nmesh = [2, 8, 4]\n"


def _hopper():
    """A convex section that is no box grid: 45-degree chamfers at the bottom corners."""
    zs = np.linspace(0.0, 0.8, 5)
    lo = np.maximum(0.0, 0.4 - zs)
    return section_hex(np.stack([np.linspace(a, 2.0 - a, 9) for a in lo]), zs, thickness=0.2, nx=1)


def _slit():
    """A 2 m section with a standing plate at y = 1 from the bottom to z = 0.4 (a slit of doubled nodes)."""
    zs = np.linspace(0.0, 0.8, 5)
    return section_hex(np.tile(np.linspace(0.0, 2.0, 9), (5, 1)), zs, slits=[(4, 0, 2, (2,))], thickness=0.2, nx=1)


MESHES = {"u-tube": lambda: u_tube_hex(2.0, 0.5, 0.3, 0.8, 8, 6, thickness=0.2, nx=1), "slit": _slit,
          "hopper": _hopper}


def _scene(tmp_path, tank, mesh=None):
    if mesh is not None:
        nodes, elements = MESHES[mesh]()
        meshio.write(str(tmp_path / "tank.msh"), meshio.Mesh(nodes, [("hexahedron", elements)]), file_format="gmsh22")
    path = tmp_path / "scene.toml"
    path.write_text(SHIP.format(tank=tank))
    return str(path)


def _locking(scene):
    return [w for w in scene.warnings if "locks" in w]


@pytest.mark.parametrize("mesh, what", [("u-tube", "a re-entrant mesh"), ("slit", "a re-entrant mesh")])
def test_a_reentrant_mesh_with_a_nodal_element_warns_once(tmp_path, capsys, mesh, what):
    path = _scene(tmp_path, MESH + ELEMENT.format("stabilized"), mesh)
    (w,) = _locking(js.load_scene(path))
    assert w.startswith("tanks[0] ('tank'): element = \"stabilized\" locks in this tank (" + what) and 'element = "rt"' in w
    assert main(["check", path]) == 0
    err = capsys.readouterr().err
    assert err.count("locks in this tank") == 1, err
    assert not _locking(js.load_scene(_scene(tmp_path, MESH + ELEMENT.format("rt"), mesh)))
    assert not _locking(js.load_scene(_scene(tmp_path, MESH, mesh)))      # the default: "rt"


def test_a_convex_mesh_does_not_warn(tmp_path):
    scene = js.load_scene(_scene(tmp_path, MESH + ELEMENT.format("stabilized"), "hopper"))
    assert scene.tanks[0].mesh[1:] == (1, 1)                             # no box grid: the re-entrancy test ran
    assert not _locking(scene), scene.warnings


@pytest.mark.parametrize("baffle", [("bottom", 0.3), ("top", 0.4)])
def test_a_baffle_with_a_nodal_element_warns(tmp_path, baffle):
    scene = js.load_scene(_scene(tmp_path, BOX + ELEMENT.format("stabilized") + BAFFLE.format(*baffle)))
    (got,) = _locking(scene)
    assert "(1 baffle in the liquid)" in got
    assert not _locking(js.load_scene(_scene(tmp_path, BOX + ELEMENT.format("stabilized"))))
    assert not _locking(js.load_scene(_scene(tmp_path, BOX + ELEMENT.format("rt") + BAFFLE.format(*baffle))))
