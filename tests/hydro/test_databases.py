"""Hydrodynamic databases (issue 20): `[vessel.hydrodynamics] file = ...` reads Capytaine's NetCDF
datasets and WAMIT's .1 / .3 / .hst into the tables a scene holds; the same tables and the same run
from each; WAMIT's non-dimensionalisation, phase and axes checked against Capytaine's own WAMIT
exporter; a database about another point moved to the COG; `jaxslosh hydro --netcdf`."""
import math
from pathlib import Path

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli import main
from jaxslosh.hydro.box import box_hydrostatics
from jaxslosh.hydro.database import tables_from_dataset, write_wamit
from jaxslosh.hydro.radiation import restoring_matrix
from jaxslosh.hydro.tables import scene_tables

cpt = pytest.importorskip("capytaine")
pytest.importorskip("xarray")

RHO, G = 1025.0, 9.81
L, B, T, KG = 20.0, 10.0, 2.0, 2.5
HEADS = [0.0, math.pi / 4, math.pi / 2]
W = np.linspace(0.3, 1.8, 6)


def solve(shift=(0.0, 0.0), about_cog=True):
    """Capytaine's dataset of the test box (coarse panels), its COG at `shift` in the plane of the
    coordinates and 0.5 m above the waterline; rotations about the COG or about the origin."""
    from jaxslosh.hydro.capytaine import _lid_depth
    import logging
    logging.getLogger("capytaine").setLevel(logging.ERROR)
    z_wl = T - KG
    mesh = cpt.mesh_parallelepiped(size=(L, B, 2 * T), center=(shift[0], shift[1], 0.0), resolution=(10, 5, 4))
    hull = mesh.immersed_part()
    cog = (shift[0], shift[1], -z_wl)
    body = cpt.FloatingBody(mesh=hull, lid_mesh=hull.generate_lid(z=_lid_depth(hull, W.max())),
                            dofs=cpt.rigid_body_dofs(rotation_center=cog if about_cog else (0.0, 0.0, 0.0)),
                            center_of_mass=cog, name="box")
    probs = [cpt.RadiationProblem(body=body, radiating_dof=d, omega=x, rho=RHO, g=G)
             for d in body.dofs for x in list(W) + [np.inf]]
    probs += [cpt.DiffractionProblem(body=body, wave_direction=b, omega=x, rho=RHO, g=G) for b in HEADS for x in W]
    ds = cpt.assemble_dataset(cpt.BEMSolver().solve_all(probs, progress_bar=False))
    hs = box_hydrostatics(L, B, T, KG)
    import xarray as xr
    dofs = list(body.dofs)
    ds["hydrostatic_stiffness"] = xr.DataArray(
        restoring_matrix(RHO, G, hs["waterplane_area"], hs["displaced_volume"], hs["gm_t"], hs["gm_l"]),
        dims=["influenced_dof", "radiating_dof"], coords={"influenced_dof": dofs, "radiating_dof": dofs})
    return ds


@pytest.fixture(scope="module")
def dataset():
    return solve()


def scene_text(hydro=None, waves: str = "") -> str:
    return (f'title = "box"\n[environment]\ngravity = {G}\nwater_density = {RHO}\n[simulation]\nduration = 20.0\n'
            f'dt = 0.05\nscheme = "newmark"\n[vessel]\nmass = 4.1e5\ninertia = [6.0e6, 1.6e7, 2.0e7]\n'
            f'[vessel.hull]\nlength = {L}\nbeam = {B}\ndraft = {T}\nkg = {KG}\n'
            + ("" if hydro is None else f"[vessel.hydrodynamics]\n{hydro}\n") + waves)


def same(a, b, rel):
    """Each table within `rel` of its largest entry."""
    for x, y in zip(a, b):
        if x is None or y is None:
            assert x is None and y is None
            continue
        scale = np.abs(x).max()
        assert np.abs(np.asarray(x) - np.asarray(y)).max() <= rel * scale, np.abs(np.asarray(x) - np.asarray(y)).max() / scale


def test_capytaine_dataset_and_wamit_files_give_the_same_tables_and_run(dataset, tmp_path):
    """Capytaine -> NetCDF (Capytaine's own export) -> jaxslosh, and Capytaine -> WAMIT files (ours,
    ULEN = 10 m so that every power of the non-dimensionalisation matters) -> jaxslosh: the same
    tables within 1e-6 and the same regular-wave run."""
    ref = tables_from_dataset(dataset)
    cpt.io.xarray.export_dataset(str(tmp_path / "box.nc"), dataset)
    nc = js.load_scene(scene_text(f'file = "{tmp_path / "box.nc"}"'))
    t_nc = scene_tables(nc.vessel.hydrodynamics)
    same(t_nc, ref, 1e-12)
    assert t_nc.added_mass_infinite is not None and t_nc.excitation.shape == (6, 3, 6)
    written = write_wamit(str(tmp_path / "box"), ref, RHO, G, length=10.0,
                          stiffness=dataset["hydrostatic_stiffness"].values)
    assert [Path(p).suffix for p in written] == [".1", ".3", ".hst"]
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "scene.toml").write_text(scene_text('file = "../box.1"\nlength_scale = 10.0'))
    wam = js.load_scene(tmp_path / "run" / "scene.toml")        # a relative file: from the scene's folder
    same(scene_tables(wam.vessel.hydrodynamics), t_nc, 1e-6)
    assert not [w for w in wam.warnings if "hydrostatic" in w]   # the .hst agrees with the box's hydrostatics
    wave = '[waves]\ntype = "regular"\namplitude = 0.2\nfrequency = 0.9\nheading = 0.6\nramp = 5.0\n'
    r1 = js.simulate(js.load_scene(scene_text(f'file = "{tmp_path / "box.nc"}"', wave)))
    r2 = js.simulate(js.load_scene(scene_text(f'file = "{tmp_path / "box.1"}"\nlength_scale = 10.0', wave)))
    x1, x2 = np.asarray(r1.vessel.roll_pitch_yaw), np.asarray(r2.vessel.roll_pitch_yaw)
    assert np.abs(x1).max() > 1e-3
    assert np.abs(x1 - x2).max() < 1e-6 * np.abs(x1).max()
    assert np.abs(np.asarray(r1.vessel.position) - np.asarray(r2.vessel.position)).max() < \
        1e-6 * np.abs(np.asarray(r1.vessel.position)).max()


def test_our_wamit_reader_against_capytaines_wamit_exporter(dataset, tmp_path):
    """Capytaine writes WAMIT's files by its own reading of the manual (export_to_wamit: e^{i w t}
    phases, the non-dimensional forms, 7 significant digits, I the radiating dof in .1): read by our
    reader, the tables of its dataset within 1e-5 (the symmetric part of A and B)."""
    from capytaine.io.wamit import export_to_wamit
    export_to_wamit(dataset, str(tmp_path / "capy"), exports=("1", "3", "hst"))
    t = scene_tables(js.load_scene(scene_text(f'file = "{tmp_path / "capy.1"}"')).vessel.hydrodynamics)
    ref = tables_from_dataset(dataset)
    sym = lambda a: 0.5 * (a + np.swapaxes(a, -1, -2))  # noqa: E731
    np.testing.assert_allclose(t.omega, ref.omega, rtol=1e-6)
    same([sym(t.added_mass), sym(t.damping), sym(t.added_mass_infinite), t.excitation],
         [sym(ref.added_mass), sym(ref.damping), sym(ref.added_mass_infinite), ref.excitation], 1e-5)
    np.testing.assert_allclose(t.headings, HEADS, atol=1e-6)


def test_a_database_about_another_point_is_moved_to_the_cog(dataset, tmp_path):
    """The same box 3 m forward and 2 m to starboard of the coordinates' origin, rotations about
    that origin (a point on the free surface, not the COG), wave phases relative to it: with the
    COG's position `cog`, the tables about the COG of the centred solve (A = T^T A_P T, X moved and
    re-phased by e^{-i k r.e_beta})."""
    shifted = solve(shift=(3.0, -2.0), about_cog=False)
    cpt.io.xarray.export_dataset(str(tmp_path / "shifted.nc"), shifted)
    z_cog = -(T - KG)
    moved = scene_tables(js.load_scene(scene_text(f'file = "{tmp_path / "shifted.nc"}"\n'
                                                  f'cog = [3.0, -2.0, {z_cog}]')).vessel.hydrodynamics)
    raw = tables_from_dataset(shifted)
    ref = tables_from_dataset(dataset)
    same(moved, ref, 1e-6)
    assert np.abs(raw.added_mass - ref.added_mass).max() > 0.01 * np.abs(ref.added_mass).max()   # it did move
    # the dataset's own centre of mass is the default
    same(scene_tables(js.load_scene(scene_text(f'file = "{tmp_path / "shifted.nc"}"')).vessel.hydrodynamics), ref, 1e-6)


def test_hydro_command_writes_a_netcdf_dataset_beside_the_toml(tmp_path, capsys):
    scene = tmp_path / "hull.toml"
    scene.write_text(scene_text())
    assert main(["hydro", str(scene), "--frequencies", "0.4:1.6:5", "--headings", "0,1.5707963267948966",
                 "--panel-size", "2.5", "-o", str(tmp_path / "t.toml"), "--netcdf", str(tmp_path / "t.nc")]) == 0
    toml = js.load_scene(scene_text() + (tmp_path / "t.toml").read_text())
    nc = js.load_scene(scene_text(f'file = "{tmp_path / "t.nc"}"'))
    same(scene_tables(nc.vessel.hydrodynamics), scene_tables(toml.vessel.hydrodynamics), 1e-8)


def test_bad_databases_are_input_errors(tmp_path, capsys):
    p = tmp_path / "s.toml"
    (tmp_path / "x.txt").write_text("1 2 3\n")
    (tmp_path / "bad.1").write_text("not a wamit file at all\n")
    (tmp_path / "bad.nc").write_text("nonsense")
    cases = [('file = "missing.nc"', "no such file"), ('file = "x.txt"', "unknown format"),
             ('file = "bad.1"', "vessel.hydrodynamics.file"), ('file = "bad.nc"', "vessel.hydrodynamics.file"),
             ('file = "x.txt"\nfrequencies = [1.0, 2.0, 3.0, 4.0]', "vessel.hydrodynamics.frequencies"),
             ('viscous_damping = [0, 0, 0, 1, 0, 0]\ncog = [0.0, 0.0, 0.0]', "vessel.hydrodynamics.cog")]
    for hydro, what in cases:
        p.write_text(scene_text(hydro))
        assert main(["check", str(p)]) == 2, hydro
        err = capsys.readouterr().err
        assert what in err and err.count("\n") == 1, (hydro, err)


def test_tables_written_as_a_netcdf_dataset_read_back(dataset, tmp_path):
    """write_netcdf (tables to Capytaine's layout, without Capytaine) then file = ...: the same tables."""
    from jaxslosh.hydro.database import write_netcdf
    ref = tables_from_dataset(dataset)
    write_netcdf(str(tmp_path / "t.nc"), ref, RHO, G, stiffness=dataset["hydrostatic_stiffness"].values)
    same(scene_tables(js.load_scene(scene_text(f'file = "{tmp_path / "t.nc"}"')).vessel.hydrodynamics), ref, 1e-12)


# --------------------------------------------------------------------------------------------
# a database checked against the scene (issue 31)


def _file_warnings(scene):
    return [w for w in scene.warnings if w.startswith("vessel.hydrodynamics.file")]


@pytest.mark.parametrize("fault, word", [("cut", "lacks"), ("cut_line", "numbers where"), ("swap", "monotone"),
                                         ("again", "appears again"), ("pair", "lacks")])
def test_a_cut_or_disordered_wamit_file_is_refused_naming_the_line(dataset, tmp_path, capsys, fault, word):
    """A .1 cut in the middle of a frequency block (or of a line), a block without one (I, J) pair,
    periods out of order or given twice: exit 2 naming the file and the line, not zeros."""
    write_wamit(str(tmp_path / "box"), tables_from_dataset(dataset), RHO, G, length=10.0)
    lines = (tmp_path / "box.1").read_text().splitlines()
    head, blocks = lines[:36], [lines[36 + 36 * k:72 + 36 * k] for k in range(W.size)]   # A_inf, then per period
    text = {"cut": lines[:-7], "cut_line": lines[:-1] + [lines[-1][:40]],
            "swap": head + blocks[0] + blocks[2] + blocks[1] + sum(blocks[3:], []),
            "again": head + sum(blocks, []) + blocks[0],
            "pair": head + sum(blocks[:2], []) + blocks[2][:14] + blocks[2][15:] + sum(blocks[3:], [])}[fault]
    (tmp_path / "box.1").write_text("\n".join(text) + "\n")
    p = tmp_path / "s.toml"
    p.write_text(scene_text('file = "box.1"\nlength_scale = 10.0'))
    assert main(["check", str(p)]) == 2
    err = capsys.readouterr().err
    assert "box.1, line " in err and word in err and err.count("\n") == 1, err
    line = int(err.split(", line ")[1].split(":")[0])
    assert 1 <= line <= len(text)


def test_a_wamit_file_read_without_its_length_scale_is_warned_with_the_likely_ulen(dataset, tmp_path):
    """WAMIT files written with ULEN = 10 m, read with the default length_scale 1 m: the hydrostatic
    stiffness (.hst) 100 times too small names length_scale = 10 m; without the .hst, the heave RAO
    at the lowest frequency (0.3 rad/s, k L = 0.18: a long wave) far from its limit 1 does; read with
    length_scale = 10 m, or from Capytaine's own NetCDF, neither check speaks."""
    ref = tables_from_dataset(dataset)
    write_wamit(str(tmp_path / "box"), ref, RHO, G, length=10.0, stiffness=dataset["hydrostatic_stiffness"].values)
    p = tmp_path / "s.toml"
    p.write_text(scene_text('file = "box.1"'))
    warned = _file_warnings(js.load_scene(p))
    assert len(warned) == 1 and "length_scale = 10 m would make them agree" in warned[0], warned
    (tmp_path / "box.hst").unlink()
    warned = _file_warnings(js.load_scene(p))
    assert len(warned) == 1 and "heave RAO" in warned[0] and "length_scale" in warned[0], warned
    rao = float(warned[0].split(" is ")[1].split(" m/m")[0])
    assert rao < 0.05                                          # ~ 1 / ULEN^2
    est = float(warned[0].split("length_scale = ")[2].split(" m")[0])
    assert abs(est - 10.0) < 0.5                               # X_3 ~ rho g A_w e^{-k T} at k T = 0.02
    p.write_text(scene_text('file = "box.1"\nlength_scale = 10.0'))
    assert _file_warnings(js.load_scene(p)) == []
    cpt.io.xarray.export_dataset(str(tmp_path / "box.nc"), dataset)
    assert _file_warnings(js.load_scene(scene_text(f'file = "{tmp_path / "box.nc"}"'))) == []
    # the RAO the warning speaks of, from js.rao: the scene read right tends to 1
    ok = js.load_scene(scene_text(f'file = "{tmp_path / "box.nc"}"', '[waves]\ntype = "regular"\namplitude = 1.0\n'
                                  'frequency = 0.5\nheading = 0.0\n'))
    assert abs(abs(np.asarray(js.rao(ok, [0.3], [0.0]).vessel)[0, 0, 2]) - 1) < 0.1


def test_the_netcdf_stiffness_mismatch_is_one_warning(dataset, tmp_path, capsys):
    """A dataset whose roll and pitch stiffness differ from the scene's: one warning naming both."""
    from jaxslosh.hydro.database import write_netcdf
    C = np.array(dataset["hydrostatic_stiffness"].values, dtype=float)
    C[3, 3] *= 0.9
    C[4, 4] *= 0.95
    write_netcdf(str(tmp_path / "t.nc"), tables_from_dataset(dataset), RHO, G, stiffness=C)
    p = tmp_path / "s.toml"
    p.write_text(scene_text('file = "t.nc"'))
    assert main(["check", str(p)]) == 0
    err = [ln for ln in capsys.readouterr().err.splitlines() if "stiffness" in ln]
    assert len(err) == 1 and "C_44" in err[0] and "C_55" in err[0] and "C_33" not in err[0], err


def test_hydro_shows_capytaines_progress_per_frequency(tmp_path, capsys, monkeypatch):
    """`jaxslosh hydro`: Capytaine's solve counted per frequency on stderr (the infinite one last),
    as the project's progress display draws it; none with --no-progress or JAXSLOSH_PROGRESS=0."""
    scene = tmp_path / "hull.toml"
    scene.write_text(scene_text())
    argv = ["hydro", str(scene), "--frequencies", "0.5:1.4:4", "--headings", "0", "--panel-size", "5.0",
            "-o", str(tmp_path / "t.toml")]
    monkeypatch.setenv("JAXSLOSH_PROGRESS", "1")
    assert main(argv) == 0
    err = capsys.readouterr().err
    bars = [x for x in err.replace("\r", "\n").splitlines() if x.startswith("Capytaine: 7 problems per frequency [")]
    assert bars and "frequency 5/5" in bars[-1] and "100.0%" in bars[-1], err
    assert "Capytaine: hydrostatics ..." in err
    from jaxslosh.hydro import capytaine
    capytaine._CACHE.clear()                  # solved again, silently
    assert main(argv + ["--no-progress"]) == 0
    assert "Capytaine" not in capsys.readouterr().err
    monkeypatch.setenv("JAXSLOSH_PROGRESS", "0")
    assert main(argv) == 0
    assert "Capytaine" not in capsys.readouterr().err
