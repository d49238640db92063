"""Large-angle stability (jaxslosh/analysis/stability.py, `jaxslosh stability`): GZ of a box against
the wall-sided formula and, past the deck edge's immersion, against an independent section
computation; the free-surface loss of slack tanks (rectangular, horizontal cylinder, prismatic,
mesh); GM0 against closed forms; the JSON; the exit-2 cases."""
import json

import numpy as np
import pytest
from scipy.optimize import brentq

import jaxslosh as js
from jaxslosh.cli.main import main

from helpers import area_centroid, clip_polygon

RHO = 1025.0
L, B, D, KG = 16.0, 10.0, 5.0, 2.9


def _scene(mass=410000.0, depth=D, tanks="", hull=True):
    text = f"""title = "box barge"
[environment]
gravity = 9.81
water_density = {RHO}
[simulation]
duration = 1.0
dt = 0.01
[vessel]
mass = {mass}
inertia = [4.9e6, 1.45e7, 1.6e7]
"""
    if hull:
        text += f"[vessel.hull]\nlength = {L}\nbeam = {B}\ndraft = 2.5\nkg = {KG}\n"
        text += f"depth = {depth}\n" if depth is not None else ""
    else:
        text += "[vessel.hydrostatics]\nwaterplane_area = 160.0\ndisplaced_volume = 400.0\ngm_t = 1.67\ngm_l = 14.2\n"
    return text + tanks


def _tank(shape_keys, origin, size, fill=None, density=1000.0):
    t = f"[[tanks]]\nname = \"t{abs(hash((origin, size))) % 1000}\"\norigin = {list(origin)}\nsize = {list(size)}\n"
    if fill is not None:
        t += f"fill_depth = {fill}\nmesh = [2, 2, 2]\n"
    return t + shape_keys + f"[tanks.fluid]\ndensity = {density}\nsound_speed = 1500.0\n"


def _section_gz(phi, T, kg, depth, beam):
    """Independent: the box's rectangular section heeled by phi, clipped by the water line that
    keeps its area B T (Sutherland-Hodgman against a half-plane, shoelace area and centroid,
    the water line by Brent's method); GZ = y_G - y_B in the heeled frame."""
    c, s = np.cos(phi), np.sin(phi)
    rect = np.array([[-beam / 2, -kg], [beam / 2, -kg], [beam / 2, depth - kg], [-beam / 2, depth - kg]])
    world = rect @ np.array([[c, s], [-s, c]])            # rotate by phi (y, z)

    h = brentq(lambda h: area_centroid(clip_polygon(world, h))[0] - beam * T, world[:, 1].min() + 1e-9,
               world[:, 1].max() - 1e-9, xtol=1e-14)
    _, cb = area_centroid(clip_polygon(world, h))
    return 0.0 - cb[0]                                     # G at the origin


def test_box_gz_wall_sided_then_exact_section():
    s = js.stability(_scene(), np.radians(np.linspace(0, 80, 33)))
    T = 410000.0 / RHO / (L * B)
    gm = T / 2 + B ** 2 / (12 * T) - KG
    bm = B ** 2 / (12 * T)
    phi = np.asarray(s.angle)
    limit = min(np.arctan((D - T) / (B / 2)), np.arctan(T / (B / 2)))   # deck edge in, or bilge out
    wall = (phi > 0) & (phi < limit)
    assert wall.sum() >= 5
    ref = np.sin(phi) * (gm + bm / 2 * np.tan(phi) ** 2)
    np.testing.assert_allclose(s.gz[wall], ref[wall], rtol=5e-3)
    # the exact formula is exact: much closer than the 0.5 %
    np.testing.assert_allclose(s.gz[wall], ref[wall], rtol=1e-9)
    beyond = phi >= limit
    sec = np.array([_section_gz(p, T, KG, D, B) for p in phi[beyond]])
    np.testing.assert_allclose(s.gz[beyond], sec, rtol=0.01, atol=1e-4)
    np.testing.assert_allclose(s.gz[beyond], sec, atol=1e-9)
    # no liquid: both curves the same; GM0 the closed form; the box neither trims nor loses volume
    np.testing.assert_array_equal(s.gz, s.gz_frozen)
    assert s.gm0 == pytest.approx(gm, rel=1e-7)
    np.testing.assert_allclose(s.trim, 0.0, atol=1e-12)
    # the vanishing angle: where the exact section's GZ crosses zero
    va = brentq(lambda p: _section_gz(p, T, KG, D, B), np.radians(60), np.radians(89))
    assert s.vanishing_angle == pytest.approx(va, abs=np.radians(0.05))


def test_pitch_axis_gm0_is_the_longitudinal_one():
    s = js.stability(_scene(), np.radians([0.0, 1.0, 2.0]), axis="pitch")
    T = 410000.0 / RHO / (L * B)
    assert s.gm0 == pytest.approx(T / 2 + L ** 2 / (12 * T) - KG, rel=1e-7)
    assert s.criteria == ()
    phi = np.asarray(s.angle)      # wall-sided along the length too
    ref = np.sin(phi) * (T / 2 + L ** 2 / (12 * T) - KG + L ** 2 / (24 * T) * np.tan(phi) ** 2)
    np.testing.assert_allclose(s.gz, ref, rtol=1e-9, atol=1e-12)


def test_free_surface_loss_of_a_slack_rectangular_tank():
    l, b, H, h, rho_l = 6.0, 8.0, 3.0, 1.5, 1000.0
    scene = _scene(tanks=_tank("", (-3.0, -4.0, -1.0), (l, b, H), fill=h, density=rho_l))
    s = js.stability(scene, np.radians(np.linspace(0, 20, 11)), criteria=False)
    V = (410000.0 + rho_l * l * b * h) / RHO
    phi = np.asarray(s.angle)
    assert np.tan(phi.max()) < min(h, H - h) / (b / 2)     # the surface meets neither bottom nor roof
    loss = rho_l * l * b ** 3 / 12 / (RHO * V) * np.sin(phi) * (1 + np.tan(phi) ** 2 / 2)
    np.testing.assert_allclose((s.gz_frozen - s.gz)[1:], loss[1:], rtol=0.02)
    np.testing.assert_allclose((s.gz_frozen - s.gz)[1:], loss[1:], rtol=1e-9)
    assert s.gm0_frozen - s.gm0 == pytest.approx(rho_l * l * b ** 3 / 12 / (RHO * V), rel=1e-6)
    # GM0 with the liquid frozen: the box's closed form with the liquid's weight at its centroid
    T = V / (L * B)
    kg = (410000.0 * KG + rho_l * l * b * h * (KG - 1.0 + h / 2)) / (RHO * V)
    assert s.gm0_frozen == pytest.approx(T / 2 + B ** 2 / (12 * T) - kg, rel=1e-6)


def test_horizontal_cylinder_liquid_acts_at_the_axis():
    """A part-filled cylinder along x, heeled about x: the liquid's segment keeps its shape in the
    sea's frame, so its weight acts as if at the axis; GZ falls by (m_l / M) r_c sin(phi), r_c the
    distance from the axis to the liquid's rest centroid (exact for the circle; the polygon's
    error is far below the tolerance)."""
    R, h, rho_l = 1.5, 1.0, 1000.0
    scene = _scene(tanks=_tank('shape = "cylinder"\naxis = "x"\n', (-4.0, -1.5, -2.0), (8.0, 2 * R, 2 * R),
                               fill=h, density=rho_l))
    s = js.stability(scene, np.radians(np.linspace(0, 60, 7)), criteria=False)
    t = (h - R) / R
    seg = R * R * (np.arccos(-t) + t * np.sqrt(1 - t * t))          # segment area
    m_l = rho_l * 8.0 * seg
    r_c = 2 * (R * R - (h - R) ** 2) ** 1.5 / (3 * seg)            # axis to the segment's centroid
    phi = np.asarray(s.angle)
    np.testing.assert_allclose(s.gz_frozen - s.gz, m_l / (410000.0 + m_l) * r_c * np.sin(phi), rtol=2e-3, atol=1e-7)


def test_cylinders_along_y_and_z_lose_their_free_surfaces_inertia():
    """GM0's free-surface loss of a vertical cylinder (i = pi D^4 / 64) and of a horizontal one
    along y, heeled across its axis (its surface a rectangle: chord x length, i = c Ly^3 / 12)."""
    rho_l, D, R, Ly, h = 1000.0, 2.0, 1.0, 6.0, 0.6
    tanks = _tank('shape = "cylinder"\naxis = "z"\n', (-5.0, -3.0, -1.0), (D, D, 2.0), fill=1.0, density=rho_l)
    tanks += _tank('shape = "cylinder"\naxis = "y"\n', (2.0, -3.0, -1.5), (2 * R, Ly, 2 * R), fill=h, density=rho_l)
    s = js.stability(_scene(tanks=tanks), np.radians([0.0, 2.0]), criteria=False)
    t = (h - R) / R
    seg = R * R * (np.arccos(-t) + t * np.sqrt(1 - t * t))
    V = (410000.0 + rho_l * (np.pi * D * D / 4 * 1.0 + Ly * seg)) / RHO
    chord = 2 * np.sqrt(R * R - (h - R) ** 2)
    i_t = np.pi * D ** 4 / 64 + chord * Ly ** 3 / 12
    assert s.gm0_frozen - s.gm0 == pytest.approx(rho_l * i_t / (RHO * V), rel=2e-3)


def test_prismatic_and_mesh_tanks():
    """A prismatic tank filled into its straight part loses (at small heels) the free surface's own
    i = l b^3 / 12; a mesh tank that is a box grid of the liquid (walls continued up to its
    height) gives the box tank's curve."""
    meshio = pytest.importorskip("meshio")
    rho_l = 1000.0
    pris = _tank('shape = "prismatic"\nchamfers = [[1.0, 1.0], [1.5, 0.5]]\n', (-3.0, -4.0, -1.5), (6.0, 8.0, 3.0),
                 fill=1.8, density=rho_l)
    s = js.stability(_scene(tanks=pris), np.radians([0.0, 5.0]), criteria=False)
    vol = 6.0 * (8.0 * 1.8 - 1.0 * 1.0)
    V = (410000.0 + rho_l * vol) / RHO
    assert s.gm0_frozen - s.gm0 == pytest.approx(rho_l * 6.0 * 8.0 ** 3 / 12 / (RHO * V), rel=1e-6)

    import os
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        x, y, z = np.meshgrid(np.linspace(0, 6, 3), np.linspace(0, 8, 3), np.linspace(0, 1.5, 2), indexing="ij")
        nodes = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
        idx = np.arange(len(nodes)).reshape(3, 3, 2)
        hexes = [[idx[i, j, 0], idx[i + 1, j, 0], idx[i + 1, j + 1, 0], idx[i, j + 1, 0],
                  idx[i, j, 1], idx[i + 1, j, 1], idx[i + 1, j + 1, 1], idx[i, j + 1, 1]] for i in range(2) for j in range(2)]
        path = os.path.join(d, "liquid.vtu")
        meshio.write(path, meshio.Mesh(nodes, [("hexahedron", np.array(hexes))]))
        angles = np.radians([0.0, 10.0, 30.0, 50.0])
        mesh = js.stability(_scene(tanks=_tank(f'shape = "mesh"\nfile = "{path}"\n', (-3.0, -4.0, -1.0),
                                               (6.0, 8.0, 3.0), density=rho_l)), angles, criteria=False)
        box = js.stability(_scene(tanks=_tank("", (-3.0, -4.0, -1.0), (6.0, 8.0, 3.0), fill=1.5, density=rho_l)),
                           angles, criteria=False)
    np.testing.assert_allclose(mesh.gz, box.gz, atol=1e-9)
    np.testing.assert_allclose(mesh.gz_frozen, box.gz_frozen, atol=1e-9)


def test_json_fields_and_figure(tmp_path, capsys):
    path = tmp_path / "box.toml"
    path.write_text(_scene(tanks=_tank("", (-3.0, -4.0, -1.0), (6.0, 8.0, 3.0), fill=1.5)))
    fig = tmp_path / "gz.png"
    assert main(["stability", str(path), "--angles", "0:60:13", "--json", "-o", str(fig)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"angle", "gz", "gz_frozen", "gm0", "gm0_frozen", "vanishing_angle", "criteria"}
    np.testing.assert_allclose(out["angle"], np.radians(np.linspace(0, 60, 13)), rtol=1e-14)
    assert len(out["gz"]) == len(out["gz_frozen"]) == 13
    assert out["vanishing_angle"] is None             # GZ stays positive to 60 degrees here
    assert [c["name"] for c in out["criteria"]] == [
        "area 0-30 deg (m rad)", "area 0-40 deg (m rad)", "area 30-40 deg (m rad)", "GZ at an angle >= 30 deg (m)",
        "angle of maximum GZ (rad)", "GM0 (m)"]
    for c in out["criteria"]:
        assert set(c) == {"name", "value", "limit", "pass"} and c["pass"] == (c["value"] >= c["limit"])
    assert [c["limit"] for c in out["criteria"]] == pytest.approx([0.055, 0.09, 0.03, 0.2, np.radians(25), 0.15])
    assert out["criteria"][5]["value"] == out["gm0"]
    # the areas against the trapezoidal rule on a fine curve of their own
    fine = js.stability(str(path), np.radians(np.linspace(0, 40, 81)), criteria=False)
    a = np.asarray(fine.angle)
    area = lambda lo, hi: np.trapezoid(fine.gz[(a >= lo - 1e-12) & (a <= hi + 1e-12)],  # noqa: E731
                                       a[(a >= lo - 1e-12) & (a <= hi + 1e-12)])
    assert out["criteria"][0]["value"] == pytest.approx(area(0, np.radians(30)), rel=1e-4)
    assert out["criteria"][2]["value"] == pytest.approx(area(np.radians(30), np.radians(40)), rel=1e-4)
    assert fig.stat().st_size > 10000
    assert fine["gm0"] == pytest.approx(out["gm0"], rel=1e-12)


def _mesh_scene(path, open_deck=False):
    """The box of _scene as a mesh hull file: its coordinates with the waterline at z = 0 (draft
    2.5 m), the COG at kg - 2.5 above it."""
    from jaxslosh.hull.box import box_hull
    from jaxslosh.hull.surface import write_hull_mesh
    cog = np.array([0.0, 0.0, KG - 2.5])
    tris = box_hull(L, B, KG, D, 2) + cog
    if open_deck:
        tris = tris[~np.all(np.isclose(tris[:, :, 2], D - 2.5), axis=1)]
    write_hull_mesh(str(path), tris)
    # the loader reads a mesh hull for Capytaine or the nonlinear hydrostatics (it then checks it is closed)
    text = _scene(hull=False)
    return text[:text.index("[vessel.hydrostatics]")] + f"""[vessel.hull]
type = "mesh"
file = "{path}"
cog = {cog.tolist()}
[vessel.hydrostatics]
model = "nonlinear"
"""


def test_mesh_hull_is_the_box(tmp_path):
    pytest.importorskip("meshio")
    angles = np.radians([0.0, 15.0, 35.0, 60.0])
    mesh = js.stability(_mesh_scene(tmp_path / "box.obj"), angles, criteria=False)
    box = js.stability(_scene(), angles, criteria=False)
    np.testing.assert_allclose(mesh.gz, box.gz, atol=1e-9)
    assert mesh.gm0 == pytest.approx(box.gm0, rel=1e-9)


def test_open_mesh_hull_exit_2(tmp_path, capsys):
    pytest.importorskip("meshio")
    path = tmp_path / "s.toml"
    path.write_text(_mesh_scene(tmp_path / "open.obj", open_deck=True))
    assert main(["stability", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("error: vessel.hull.file:") and "not closed at the deck" in err


@pytest.mark.parametrize("text, key", [
    (_scene(hull=False), "vessel.hull"),
    (_scene(depth=2.0), "vessel.hull.depth"),
    (_scene(depth=None), "vessel.hull.depth"),
    (_scene(mass=1e7), "vessel.mass"),
])
def test_exit_2_names_the_key(tmp_path, capsys, text, key):
    path = tmp_path / "s.toml"
    path.write_text(text)
    assert main(["stability", str(path), "-o", str(tmp_path / "gz.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith(f"error: {key}:")
    assert not (tmp_path / "gz.png").exists()


def test_bad_angles_exit_2(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(_scene())
    assert main(["stability", str(path), "--angles", "0:80"]) == 2
    assert "--angles" in capsys.readouterr().err
