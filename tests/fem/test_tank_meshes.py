"""Tank mesh files checked on the way in, and baffles in one documented form (issue 30, items 8-9).

Each bad mesh is a small box grid written with meshio into tmp_path and spoiled in one way; the
command line must refuse it with exit status 2 and one line naming `tanks[0].file` and the element
or node at fault. A left-handed numbering is re-oriented (the mesh then builds exactly as the good
one) and `check` says how many were. Baffles: SPEC's keys are described by `check` (plane, side,
edge height); the README's earlier keys are refused with their translation.
"""
import os

import numpy as np
import pytest

from jaxslosh.cli.main import main
from jaxslosh.fem.mesh import box_mesh
from jaxslosh.fem.meshfile import check_hexahedra, read_mesh_file
from jaxslosh.geometry import MeshFile

meshio = pytest.importorskip("meshio")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FLIP = [0, 3, 2, 1, 4, 7, 6, 5]


def _scene(tmp_path, extra, mesh_tank=True):
    t = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read().replace("duration = 20.0", "duration = 0.1")
    if mesh_tank:
        t = t.replace("fill_depth = 3.0\n", "").replace("mesh = [5, 5, 5]\n", "")
    path = tmp_path / "scene.toml"
    path.write_text(t.replace('walls = "rigid"\n', 'walls = "rigid"\n' + extra + "\n"))
    return str(path)


def _write(tmp_path, nodes, elements, name="tank.msh"):
    path = tmp_path / name
    meshio.write(str(path), meshio.Mesh(nodes, [("hexahedron", elements)]), file_format="gmsh22")
    return path


def _box():
    return box_mesh((5.0, 5.0, 3.0), (5, 5, 5))


def _check(tmp_path, capsys, path):
    """(exit status, stdout, stderr) of `jaxslosh check` on the paper scene with this mesh tank."""
    capsys.readouterr()                                   # meshio.write's own warnings
    code = main(["check", _scene(tmp_path, f'shape = "mesh"\nfile = "{os.path.basename(path)}"')])
    out = capsys.readouterr()
    return code, out.out, out.err


def _collapsed():
    nodes, el = _box()
    nodes = nodes.copy()
    nodes[el[7, 6]] = nodes[el[7, 5]]           # two corners of element 7 (and its neighbours') at one place
    return nodes, el


def _thin_layer():
    """The z planes 0, 0.3, 0.30000000000000004, 1.2, 2.1, 3.0: one layer of zero thickness."""
    nodes, el = _box()
    nodes = nodes.copy()
    z = np.array([0.0, 0.3, 0.30000000000000004, 1.2, 2.1, 3.0])
    nodes[:, 2] = z[np.round(nodes[:, 2] / 0.6).astype(int)]
    return nodes, el


def _crack():
    """The upper two layers on their own nodes, whose lowest plane is one ulp above the lower part's top."""
    nodes, el = _box()
    up = np.flatnonzero(nodes[:, 2] > 1.7)
    extra = nodes[up].copy()
    extra[np.isclose(extra[:, 2], 1.8), 2] = np.nextafter(1.8, 2.0)
    remap = np.arange(len(nodes))
    remap[up] = len(nodes) + np.arange(len(up))
    el = el.copy()
    above = nodes[el].min(axis=1)[:, 2] > 1.7
    el[above] = remap[el[above]]
    return np.vstack([nodes, extra]), el


def _twisted():
    nodes, el = _box()
    nodes = nodes.copy()
    top = el[12, 6]                                       # pull a top corner of element 12 below its bottom face
    nodes[top, 2] -= 1.5
    return nodes, el


def _non_manifold():
    nodes, el = _box()
    return nodes, np.vstack([el, el[12:13]])              # element 12 twice: each of its faces in 3 or 2 elements


@pytest.mark.parametrize("make, words", [
    (_collapsed, ["element 7", "collapsed", "[1.0, 1.0, 1.7999999999999998]"]),
    (_thin_layer, ["element 1", "zero-thickness", "0.30000000000000004"]),
    (_crack, ["nodes 3", "216", "1.8000000000000003", "apart"]),
    (_twisted, ["element 12", "Jacobian", "node"]),
    (_non_manifold, ["shared by 3 elements", "12", "125", "non-manifold"]),
])
def test_a_bad_mesh_is_refused_naming_the_element_or_node(tmp_path, capsys, make, words):
    path = _write(tmp_path, *make())
    code, _, err = _check(tmp_path, capsys, path)
    assert code == 2, err
    assert err.startswith("error: tanks[0].file: ") and err.count("\n") == 1, err
    for w in words:
        assert w in err, (w, err)


def test_an_unreadable_file_and_one_without_hexahedra_exit_2(tmp_path, capsys):
    bad = tmp_path / "tank.msh"
    bad.write_text("not a mesh\n")
    code, out, err = _check(tmp_path, capsys, bad)
    assert code == 2 and err.startswith("error: tanks[0].file: cannot read the mesh file") and err.count("\n") == 1, err
    assert out == ""                                      # meshio's own prints do not leak
    tet = tmp_path / "tet.msh"
    meshio.write(str(tet), meshio.Mesh(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
                                       [("tetra", np.array([[0, 1, 2, 3]]))]), file_format="gmsh22")
    code, _, err = _check(tmp_path, capsys, tet)
    assert code == 2 and "tanks[0].file" in err and "no 8-node hexahedra" in err, err


def test_left_handed_elements_are_reoriented_and_counted(tmp_path, capsys):
    nodes, el = _box()
    good = read_mesh_file(_write(tmp_path, nodes, el, "good.msh"))
    el = el.copy()
    el[[3, 40, 77]] = el[[3, 40, 77]][:, FLIP]
    path = _write(tmp_path, nodes, el)
    m = read_mesh_file(path)
    assert m.reoriented == 3 and good.reoriented == 0
    np.testing.assert_array_equal(m.elements, good.elements)      # the same right-handed numbering as the good file
    geo = dict(size=(5.0, 5.0, 4.0))
    a = MeshFile(file=str(path), **geo).mesh(3.0, (5, 5, 5))
    b = MeshFile(file=str(tmp_path / "good.msh"), **geo).mesh(3.0, (5, 5, 5))
    np.testing.assert_array_equal(a.elements, b.elements)
    code, out, _ = _check(tmp_path, capsys, path)
    assert code == 0
    assert "note: 3 of the 125 hexahedra in tank.msh are numbered left-handed (inverted)" in out, out
    code, out, _ = _check(tmp_path, capsys, tmp_path / "good.msh")
    assert code == 0 and "left-handed" not in out


def test_a_plate_of_doubled_nodes_is_kept():
    """Nodes at exactly one place (a thin plate's two faces in a mesh file) are no crack: kept apart."""
    nodes, el = box_mesh((2.0, 1.0, 1.0), (2, 1, 1))
    plate = np.flatnonzero(np.isclose(nodes[:, 0], 1.0) & (nodes[:, 2] < 0.5))      # the plate's lower nodes
    copies = len(nodes) + np.arange(len(plate))
    remap = np.arange(len(nodes))
    remap[plate] = copies
    el = el.copy()
    el[1] = remap[el[1]]                                  # the element beyond the plate takes the copies
    nodes = np.vstack([nodes, nodes[plate]])
    out, flipped = check_hexahedra(nodes, el)
    assert flipped == 0 and np.array_equal(out, el)


def test_corner_jacobians_of_a_sheared_but_valid_element_pass():
    """A strongly sheared, tapered hexahedron is not degenerate: no false alarm."""
    nodes, el = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
    nodes = nodes.copy()
    nodes[:, 0] += 0.8 * nodes[:, 2]                      # 38.7 degrees of shear
    nodes[nodes[:, 2] > 0.5, 1] *= 0.3                    # the top three times narrower
    out, flipped = check_hexahedra(nodes, el)
    assert flipped == 0


def test_check_prints_each_baffle_as_read(tmp_path, capsys):
    extra = ('[[tanks.baffles]]\nnormal = "x"\nposition = 2.0\nfrom = "top"\nheight = 2.0\n'
             '[[tanks.baffles]]\nnormal = "y"\nposition = 3.0\nheight = 1.0')
    assert main(["check", _scene(tmp_path, extra, mesh_tank=False)]) == 0
    out = capsys.readouterr().out
    assert ("baffle 0: the plane x = 2 m from the tank's origin, hanging from the roof, its lower edge 2 m above "
            "the tank bottom") in out, out
    assert ("baffle 1: the plane y = 3 m from the tank's origin, standing on the bottom, its upper edge 1 m above "
            "the tank bottom") in out, out


@pytest.mark.parametrize("old, key, hint", [
    ('normal = "x"\nat = 2.0\nmount = "top"\nheight = 1.0', "tanks[0].baffles[0].at",
     ['position = 2.0 (for at)', 'from = "top" (for mount)', "height = 3 (the plate's lower edge"]),
    ('at = 4.0\nmount = "bottom"\nheight = 1.0', "tanks[0].baffles[0].at",
     ['position = 4.0', 'from = "bottom"', "height = 1 (the plate's upper edge"]),
    ('position = 4.0\nmount = "top"\nheight = 0.5', "tanks[0].baffles[0].mount",
     ['from = "top" (for mount)', "height = 3.5"]),
])
def test_the_old_baffle_keys_are_refused_with_their_translation(tmp_path, capsys, old, key, hint):
    assert main(["check", _scene(tmp_path, "[[tanks.baffles]]\n" + old, mesh_tank=False)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {key}: ") and err.count("\n") == 1, err
    for h in hint:
        assert h in err, (h, err)
