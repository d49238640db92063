"""Tanks of other shapes (issue 18): sloshing frequencies against closed forms and an independent
solver (tests/sloshing_reference.py), the hydrostatics of inclined walls, a box given as a mesh file,
the scene's checks, and a coupled run."""
import os
import sys

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli.main import main
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.liquid.modes import free_matrices, liquid_modes
from jaxslosh.geometry import Baffle, Box, Cylinder, MeshFile, Prismatic

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import sloshing_reference as ref  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
G = 9.81


def modes(geo, depth, mesh, n=8):
    m = build_liquid(geo.size, depth, mesh, 1000.0, 1500.0, G, geometry=geo, sparse=True)
    md = liquid_modes(m, n)
    assert all(k == "sloshing" for k in md.kind), md.kind       # no spurious or circulation mode in the band
    return m, md


def distinct(omega, rtol=2e-3):
    out = [omega[0]]
    for w in omega[1:]:
        if w > out[-1] * (1 + rtol):
            out.append(w)
    return np.array(out)


def test_vertical_cylinder_first_three_modes_against_bessel():
    # R = 2 m filled to 2 m; the disk is mapped from the square (its mode pairs split slightly)
    geo = Cylinder(size=(4.0, 4.0, 3.0), axis="z")
    _, md = modes(geo, 2.0, (16, 16, 6), n=8)
    exact = ref.vertical_cylinder_omegas(2.0, 2.0, G, n=3)          # k R = 1.8412, 3.0542, 3.8317
    for w_exact in exact:
        nearest = md.omega[np.argmin(np.abs(md.omega - w_exact))]
        assert abs(nearest / w_exact - 1) < 0.01, (nearest, w_exact)
    # each of the three is there: the m = 1 pair, both m = 2 modes and the axisymmetric one
    assert np.sum(np.abs(md.omega / exact[0] - 1) < 0.01) == 2
    assert np.sum(np.abs(md.omega / exact[1] - 1) < 0.01) == 2


def test_horizontal_cylinder_half_full_against_mciver():
    # R = 1.5 m, a 1 m slice along x (its longitudinal modes lie far above the first transverse one)
    geo = Cylinder(size=(1.0, 3.0, 3.0), axis="x")
    m, md = modes(geo, 1.5, (2, 12, 6), n=3)
    exact = ref.horizontal_cylinder_half_full_first(1.5, G)          # omega^2 R / g = 1.3557
    assert abs(md.omega[0] / exact - 1) < 0.015
    # the liquid's volume is the half disk's, and every wall node sits on the circle
    assert abs(m.mass.sum() / 1000.0 / (0.5 * np.pi * 1.5 ** 2 * 1.0) - 1) < 0.01
    walls = np.unique(m.wall_faces)
    side = walls[np.abs(m.nodes[walls, 0] - 0.5) < 0.49]             # not on the end walls
    r = np.hypot(m.nodes[side, 1] - 1.5, m.nodes[side, 2] - 1.5)
    assert side.size > 0 and np.abs(r - 1.5).max() < 1e-12


def test_v_section_against_kirchhoff():
    # chamfers meeting at the centre line at 45 degrees: a 90-degree V, 2 m deep at the apex
    geo = Prismatic(size=(1.0, 4.0, 3.0), chamfers=((2.0, 2.0), (0.0, 0.0)))
    _, md = modes(geo, 2.0, (2, 8, 6), n=3)
    assert abs(md.omega[0] / ref.v_section_first(2.0, G) - 1) < 0.01


def test_trapezoidal_section_against_the_section_solver():
    # bottom chamfers 1.5 m wide, 3 m high, filled to 2.5 m: straight inclined walls
    geo = Prismatic(size=(1.0, 6.0, 4.0), chamfers=((1.5, 3.0), (0.0, 0.0)))
    _, md = modes(geo, 2.5, (2, 12, 8), n=3)
    w = ref.section_sloshing_omegas(ref.prismatic(6.0, 4.0, 1.5, 3.0), 2.5, G, n=2)
    assert abs(md.omega[0] / w[0] - 1) < 0.015


@pytest.mark.parametrize("fill", [2.0, 3.5])
def test_lng_section_against_the_section_solver(fill):
    """Hopper and top chamfers (membrane LNG tank section), filled above the hopper's kink and into
    the top chamfers: the first two transverse modes within 1.5 % of the section solver."""
    geo = Prismatic(size=(1.0, 6.0, 4.0), chamfers=((1.5, 1.0), (1.5, 1.0)))
    _, md = modes(geo, fill, (2, 12, 8), n=2)
    w = ref.section_sloshing_omegas(ref.prismatic(6.0, 4.0, 1.5, 1.0, 1.5, 1.0), fill, G, n=2)
    np.testing.assert_allclose(md.omega, w, rtol=0.015)


def test_a_pinned_line_inside_the_liquid_locks_without_the_paired_rows():
    """Why geometry/section.py pairs curl rows where a shape pins more than the box: pin the horizontal
    displacement of one line of bottom nodes in a plain box and the first mode (2.30 rad/s) jumps
    to near the next one; with the hopper's pairing, the hopper section is within 0.2 %."""
    import dataclasses
    m = build_liquid((5.0, 1.0, 3.0), 2.0, (10, 2, 6), 1000.0, 1500.0, G)
    free = m.free.reshape(-1, 3).copy()
    free[(np.abs(m.nodes[:, 0] - 2.0) < 1e-9) & (m.nodes[:, 2] < 1e-9), 0] = False
    pinned = liquid_modes(dataclasses.replace(m, free=free.reshape(-1)), 1).omega[0]
    assert pinned > 1.4 * liquid_modes(m, 1).omega[0]
    geo = Prismatic(size=(1.0, 6.0, 4.0), chamfers=((1.5, 1.0), (0.0, 0.0)))
    _, md = modes(geo, 2.5, (2, 12, 8), n=1)
    w = ref.section_sloshing_omegas(ref.prismatic(6.0, 4.0, 1.5, 1.0), 2.5, G, n=1)[0]
    assert abs(md.omega[0] / w - 1) < 0.002


def test_heeled_trapezoidal_tank_keeps_its_surface_as_level_as_the_box():
    """Gravity tilted by 5 degrees about x, the discrete static equilibrium: the free surface's
    spread of heights along gravity (compression included) is no larger with inclined walls than in
    the box of the same mesh and depth, and under 3 % of the tilt's."""
    def spread(chamfers):
        geo = Prismatic(size=(4.0, 6.0, 4.0), chamfers=chamfers)
        m = build_liquid(geo.size, 2.5, (4, 8, 6), 1000.0, 1500.0, G, geometry=geo)
        th = np.radians(5.0)
        g_b = G * np.array([0.0, np.sin(th), -np.cos(th)])
        K, _ = free_matrices(m)
        f = np.flatnonzero(m.free)
        d = np.zeros(3 * m.n_nodes)
        d[f] = np.linalg.solve(K, m.body_force(g_b)[f])
        D = m.to_global(d.reshape(-1, 3))
        s, up = m.surface, -g_b / G
        return np.ptp((m.nodes[s] + D[s]) @ up), np.ptp(m.nodes[s] @ up)
    trapezoid, tilt = spread(((1.5, 3.0), (0.0, 0.0)))
    box, _ = spread(((0.0, 0.0), (0.0, 0.0)))
    assert trapezoid <= box and trapezoid < 0.03 * tilt, (trapezoid, box, tilt)


def test_standing_baffle_against_the_section_solver():
    """A plate 1 m high across a 5 m tank filled to 2 m, at mid-length: its first mode within 2 % of
    the section solver's (2.1253 rad/s; 2.2891 without the plate)."""
    geo = Box(size=(5.0, 1.0, 3.0), baffles=(Baffle("x", 2.5, "bottom", 1.0),))
    _, md = modes(geo, 2.0, (20, 2, 8), n=2)
    exact = ref.section_sloshing_omegas(ref.rectangle(5.0), 2.0, G, n=1, baffles=(ref.Baffle(2.5, 1.0),))[0]
    assert abs(md.omega[0] / exact - 1) < 0.02
    assert md.omega[0] < 0.95 * ref.rectangular_omegas(5.0, 2.0, G, n=1)[0]


def _scene_text(extra, size="[5.0, 5.0, 4.0]", mesh="[5, 5, 5]", fill="3.0", duration="0.3"):
    t = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    t = t.replace("size = [5.0, 5.0, 4.0]", "size = " + size).replace("mesh = [5, 5, 5]", "mesh = " + mesh)
    t = t.replace("fill_depth = 3.0", "fill_depth = " + fill).replace("duration = 20.0", f"duration = {duration}")
    return t.replace('walls = "rigid"\n', 'walls = "rigid"\n' + extra + "\n")


def test_box_given_as_a_gmsh_file_runs_as_the_box(tmp_path):
    meshio = pytest.importorskip("meshio")
    from jaxslosh.fem.mesh import box_mesh
    nodes, elements = box_mesh((5.0, 5.0, 3.0), (5, 5, 5))
    path = tmp_path / "tank.msh"
    # a shuffled node order, as a mesher writes it
    perm = np.random.default_rng(0).permutation(len(nodes))
    inv = np.argsort(perm)
    meshio.write(str(path), meshio.Mesh(nodes[perm], [("hexahedron", inv[elements])]), file_format="gmsh22")
    box = js.simulate(js.load_scene(_scene_text("")))
    # SPEC section 5: a mesh tank gives neither fill_depth nor mesh (its file does)
    scene = _scene_text(f'shape = "mesh"\nfile = "{path}"').replace("fill_depth = 3.0\n", "").replace("mesh = [5, 5, 5]\n", "")
    mesh = js.simulate(js.load_scene(scene))
    assert box.status == mesh.status == "ok"
    np.testing.assert_allclose(mesh.vessel.roll_pitch_yaw, box.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(mesh.probes["B"].position, box.probes["B"].position, rtol=0, atol=1e-10)


def test_shape_keys_are_checked(tmp_path, capsys):
    cases = [('shape = "prismatic"\nchamfers = { bottom = [3.0, 1.0] }', "tanks[0].chamfers"),
             ('shape = "prismatic"\nchamfers = [[1.0, 1.0], [1.0]]', "tanks[0].chamfers[1]"),
             ('shape = "cylinder"\naxis = "z"', "tanks[0].size"),         # 5 x 4 across: not a circle
             ('[[tanks.baffles]]\nposition = 6.0\nheight = 1.0', "tanks[0].baffles[0].position"),
             ('[[tanks.baffles]]\nposition = 2.0\nfrom = "top"\nheight = 3.5', "tanks[0].baffles[0].height"),
             ('shape = "mesh"\nfile = "x.msh"', "tanks[0].mesh"),
             ('shape = "cylinder"\naxis = "w"', "tanks[0].axis"),
             ('shape = "mesh"\nfile = "nowhere.msh"', "tanks[0].file"),
             ('axis = "x"', "tanks[0].axis")]
    for extra, key in cases:
        path = tmp_path / "s.toml"
        text = _scene_text(extra, size="[5.0, 4.0, 4.0]")
        if "nowhere" in extra:
            text = text.replace("fill_depth = 3.0\n", "").replace("mesh = [5, 5, 5]\n", "")
        path.write_text(text)
        code = main(["check", str(path)])       # in process: the command's exit status and its line
        err = capsys.readouterr().err
        assert code == 2 and key in err, (extra, err)


def test_ship_with_a_vertical_cylinder_tank_full_and_reduced():
    """The paper's ship with a vertical cylindrical tank: a run at full order and one on 12 modes
    agree, and the liquid started at rest in an upright ship stays at rest."""
    text = _scene_text('shape = "cylinder"\naxis = "z"', mesh="[6, 6, 3]", duration="1.0")
    full = js.simulate(js.load_scene(text))
    red = js.simulate(js.load_scene(text + "\n[tanks.reduction]\nmodes = 12\n"))
    assert full.status == red.status == "ok"
    roll_full, roll_red = full.vessel.roll_pitch_yaw[:, 0], red.vessel.roll_pitch_yaw[:, 0]
    assert np.abs(roll_red - roll_full).max() < 0.02 * np.abs(roll_full).max()
    rest = js.simulate(js.load_scene(text.replace("angular_velocity = [0.1, 0.05, 0.0]",
                                                  "angular_velocity = [0.0, 0.0, 0.0]")))
    assert np.abs(rest.vessel.roll_pitch_yaw).max() < 1e-9


@pytest.mark.parametrize("name", ["type_c_tank", "lng_carrier"])
def test_shape_scenes_check(name, capsys):
    code = main(["check", os.path.join(ROOT, "scenes", f"{name}.toml")])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "warning" not in err                        # the masses balance the displacement


def test_horizontal_cylinder_longitudinal_mode_against_the_box():
    """A check: the lowest longitudinal mode of a half-full horizontal cylinder (R = 1.5 m, 6 m long)
    against the box of the same free surface and volume (6 m long, its depth the mean, pi R / 4)."""
    geo = Cylinder(size=(6.0, 3.0, 3.0), axis="x")
    _, md = modes(geo, 1.5, (8, 12, 6), n=2)
    box = ref.rectangular_omegas(6.0, np.pi * 1.5 / 4, G, n=1)[0]
    assert abs(md.omega[0] / box - 1) < 0.01


def test_wall_integrals_on_faces_equal_the_box_planes():
    """The boundary-layer damping's wall integral over any mesh's wall faces (liquid/damping.py) equals
    the box's plane-by-plane one on the same box grid."""
    from jaxslosh.liquid.damping import wall_integrals
    box = build_liquid((5.0, 4.0, 3.0), 2.0, (6, 4, 4), 1000.0, 1500.0, G)
    same = build_liquid((5.0, 4.0, 3.0), 2.0, (6, 4, 4), 1000.0, 1500.0, G,
                        geometry=Prismatic(size=(5.0, 4.0, 3.0)))
    assert same.wall_faces is not None and box.wall_faces is None
    X = liquid_modes(box, 3).shapes[:, np.flatnonzero(box.free)].T
    np.testing.assert_allclose(wall_integrals(same, X), wall_integrals(box, X), rtol=1e-10)


def test_box_written_by_gmsh_runs_as_the_box(tmp_path):
    """A box meshed by gmsh itself (transfinite, recombined into hexahedra, gmsh's own .msh 4.1)."""
    gmsh = pytest.importorskip("gmsh")
    path = str(tmp_path / "tank.msh")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("tank")
        gmsh.model.occ.addBox(0.0, 0.0, 0.0, 5.0, 5.0, 3.0)
        gmsh.model.occ.synchronize()
        for _, c in gmsh.model.getEntities(1):
            gmsh.model.mesh.setTransfiniteCurve(c, 6)
        for _, s in gmsh.model.getEntities(2):
            gmsh.model.mesh.setTransfiniteSurface(s)
            gmsh.model.mesh.setRecombine(2, s)
        for _, v in gmsh.model.getEntities(3):
            gmsh.model.mesh.setTransfiniteVolume(v)
        gmsh.model.mesh.generate(3)
        gmsh.write(path)
    finally:
        gmsh.finalize()
    geo = MeshFile(size=(5.0, 5.0, 4.0), file=path)
    m = build_liquid(geo.size, 3.0, (5, 5, 5), 1000.0, 1500.0, G, geometry=geo)
    box = build_liquid((5.0, 5.0, 4.0), 3.0, (5, 5, 5), 1000.0, 1500.0, G)
    assert m.geometry is None                  # recognised as the box grid, built as the box
    np.testing.assert_allclose(np.asarray(m.stiffness), np.asarray(box.stiffness), rtol=0, atol=1e-6)


def test_shaped_tank_sparse_solver_agrees_with_dense():
    """Full order through the shaped tank's JAX factors (solve/factored.py; the box's fast
    diagonalization needs the box grid): the stabilized element, given (the default there is "rt")."""
    text = _scene_text('shape = "cylinder"\naxis = "z"', mesh="[6, 6, 3]", duration="0.2")
    text = text.replace("[tanks.fluid]", '[tanks.fluid]\nelement = "stabilized"')
    dense = js.simulate(js.load_scene(text.replace("save_every = 1", 'save_every = 1\nlinear_solver = "dense"')))
    sparse = js.simulate(js.load_scene(text.replace("save_every = 1", 'save_every = 1\nlinear_solver = "sparse"')))
    assert dense.status == sparse.status == "ok"
    np.testing.assert_allclose(sparse.vessel.roll_pitch_yaw, dense.vessel.roll_pitch_yaw, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sparse.probes["B"].position, dense.probes["B"].position, rtol=0, atol=1e-8)


def test_a_kept_model_is_named_by_the_contents_of_the_mesh_file(tmp_path):
    """`jaxslosh run` keeps the model it built (programs.cached) under a name that holds the contents
    of every file the scene names: a mesh that changes after a run gives the next run a new model."""
    meshio = pytest.importorskip("meshio")
    from jaxslosh.fem.mesh import box_mesh
    from jaxslosh.run.tofile import model_key
    path = tmp_path / "tank.msh"

    def write(height):
        nodes, elements = box_mesh((5.0, 5.0, height), (5, 5, 5))
        meshio.write(str(path), meshio.Mesh(nodes, [("hexahedron", elements)]), file_format="gmsh22")

    write(3.0)
    text = _scene_text(f'shape = "mesh"\nfile = "{path}"').replace("fill_depth = 3.0\n", "").replace("mesh = [5, 5, 5]\n", "")
    scene = js.load_scene(text)
    first = model_key(scene)
    assert model_key(scene) == first and str(path) in dict(first[1])
    write(2.5)
    assert model_key(scene) != first
    path.unlink()
    assert model_key(scene) is None
