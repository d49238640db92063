"""Waves and hydrodynamic databases on [[bodies]], and the coupled radiation of a multibody file
(docs/guide/bodies-and-connections.md), against Capytaine's own solution of the same two boxes
(tests/data/bodies, made by its generate.py; Capytaine is not needed to run these tests)."""
import os

import numpy as np
import pytest
import xarray as xr

import jaxslosh as js
from jaxslosh.hydro.multibody import read_multibody
from jaxslosh.hydro.spectra import wavenumber
from jaxslosh.scene.types import SceneError

from two_boxes_scene import DATA, G, box, reference, two_boxes


def test_side_by_side_the_rao_is_capytaines_post_pro_rao():
    """The coupled dataset (a 7 m gap, beam and head seas) gives the RAO Capytaine's post_pro.rao
    computed from it, for both bodies and every dof, within 1 % of each dof's largest response."""
    ref = reference()
    scene = js.load_scene(two_boxes())
    r = js.rao(scene, frequencies=ref["omega"], headings=ref["headings"])
    ours = np.concatenate([r.vessel, r.bodies["tender"]], axis=2)
    size = np.abs(ref["rao"]).max(axis=(0, 1))
    err = np.abs(ours - ref["rao"]).max(axis=(0, 1)) / size
    moving = size > 1e-6 * size.max()            # (surge and yaw in beam seas of symmetric boxes: 0)
    assert err[moving].max() < 0.01, err


def test_two_bodies_far_apart_each_have_their_own_rao():
    """1,000 m apart, each box on its own file: each body's RAO is that of the same box alone as the
    vessel, moved to its place in the incident field (the phase k (x cos b + y sin b))."""
    w = np.linspace(0.3, 0.9, 5)               # long waves: 70 to 690 m
    heads = np.array([0.0, np.pi / 2])
    pair = js.rao(js.load_scene(two_boxes(1000.0, ("barge.nc", "tender.nc"))), frequencies=w, headings=heads)
    alone = {name: js.rao(js.load_scene("[simulation]\nduration = 1.0\ndt = 0.1\n"
                                        + box("vessel", name, k, f"{name}.nc")), frequencies=w, headings=heads).vessel
             for k, name in enumerate(("barge", "tender"))}
    shift = np.exp(-1j * wavenumber(w, G)[:, None] * 1000.0 * np.sin(heads)[None, :])[:, :, None]
    for name, got, own in (("barge", pair.vessel, alone["barge"]), ("tender", pair.bodies["tender"],
                                                                     alone["tender"] * shift)):
        size = np.abs(own).max(axis=(0, 1))
        moving = size > 1e-6 * size.max()
        err = (np.abs(got - own).max(axis=(0, 1)) / np.maximum(size, 1e-300))[moving]
        assert err.max() < 0.01, (name, err)


def test_a_bodys_heading_turns_its_tables():
    """The tender turned by 90 deg in head seas is the tender in beam seas: its sway is the alone
    tender's surge... as the tables' axes turn with it (translations in inertial axes)."""
    w = np.linspace(0.4, 1.2, 4)
    turned = js.load_scene(two_boxes(1000.0, ("barge.nc", "tender.nc")).replace(
        "position = [0.0, 1000.0]", "position = [0.0, 1000.0]\nheading = 1.5707963267948966"))
    got = js.rao(turned, frequencies=w, headings=[np.pi / 2]).bodies["tender"][:, 0]
    own = js.rao(js.load_scene("[simulation]\nduration = 1.0\ndt = 0.1\n" + box("vessel", "tender", 1, "tender.nc")),
                 frequencies=w, headings=[0.0]).vessel[:, 0]
    own = own * np.exp(-1j * wavenumber(w, G) * 1000.0)[:, None]
    # body x (surge) is inertial y, body y (sway) is inertial -x; rotations stay in body axes
    np.testing.assert_allclose(got[:, 1], own[:, 0], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(got[:, [2, 3, 4]], own[:, [2, 3, 4]], rtol=1e-6, atol=1e-9)


def test_a_time_domain_run_in_regular_waves_is_the_rao():
    """Beam seas at a tabulated frequency (the memory's fit, the cross kernels between the bodies
    included, against the tables themselves): the steady amplitude and phase of sway, heave and
    roll of both bodies within 3 % of the RAO (measured: 0.2 to 0.7 %)."""
    ref = reference()
    w = float(ref["omega"][5])
    T, a = 2 * np.pi / w, 0.1
    waves = (f'[waves]\ntype = "regular"\namplitude = {a!r}\nfrequency = {w!r}\nheading = 1.5707963267948966\n'
             f'ramp = {2 * T!r}\n')
    scene = js.load_scene(two_boxes(waves=waves, duration=15 * T, dt=T / 60, damped=True))
    res = js.simulate(scene)
    rao = js.rao(scene, frequencies=[w], headings=[np.pi / 2])
    t = np.asarray(res.time)
    last = t > t[-1] - 3 * T
    basis = np.c_[np.cos(w * t[last]), np.sin(w * t[last]), np.ones(last.sum()), t[last]]
    for hist, R in ((res.vessel, rao.vessel[0, 0]), (res.bodies["tender"], rao.bodies["tender"][0, 0])):
        for j, y in ((1, np.asarray(hist.position)[:, 1]), (2, np.asarray(hist.position)[:, 2]),
                     (3, np.asarray(hist.roll_pitch_yaw)[:, 0])):
            c = np.linalg.lstsq(basis, y[last], rcond=None)[0]
            x = (c[0] - 1j * c[1]) / a
            assert abs(x - R[j]) < 0.03 * abs(R[j]), (j, x, R[j])


def test_the_coupled_file_reads_symmetric_without_a_warning():
    mb = read_multibody(os.path.join(DATA, "two_boxes.nc"), ("barge", "tender"), 1025.0, G)
    assert mb.tables.added_mass.shape == (12, 12, 12) and mb.warnings == ()


def test_an_asymmetric_or_active_file_is_warned_about_naming_the_worst_entry(tmp_path):
    ds = xr.open_dataset(os.path.join(DATA, "two_boxes.nc"), engine="h5netcdf").load()
    A = ds["added_mass"].values.copy()
    A[3, 2, 8] += 0.2 * np.sqrt(A[3, 2, 2] * A[3, 8, 8])     # barge heave / tender heave, 4th frequency
    B = ds["radiation_damping"].values.copy()
    B[6, 8, 8] = -0.5 * abs(B[6, 2, 2])     # the tender's heave gains energy
    ds["added_mass"] = (ds["added_mass"].dims, A)
    ds["radiation_damping"] = (ds["radiation_damping"].dims, B)
    path = str(tmp_path / "bad.nc")
    ds.to_netcdf(path, engine="h5netcdf")
    mb = read_multibody(path, ("barge", "tender"), 1025.0, G)
    assert len(mb.warnings) == 2, mb.warnings
    assert "barge__Heave / tender__Heave" in mb.warnings[0] or "tender__Heave / barge__Heave" in mb.warnings[0]
    assert "not positive semi-definite" in mb.warnings[1] and "tender__Heave" in mb.warnings[1]
    ds = xr.open_dataset(os.path.join(DATA, "two_boxes.nc"), engine="h5netcdf").load()
    ds["added_mass"] = (ds["added_mass"].dims, A)
    path = str(tmp_path / "asymmetric.nc")
    ds.to_netcdf(path, engine="h5netcdf")
    scene = js.load_scene(two_boxes().replace(os.path.join(DATA, "two_boxes.nc"), path))
    assert [x for x in scene.warnings if "not symmetric" in x] == [mb.warnings[0].replace("bad.nc", "asymmetric.nc")]
    assert not [x for x in js.load_scene(two_boxes()).warnings if "two_boxes.nc" in x]


def test_a_file_whose_bodies_are_not_the_scenes_names_its_key(tmp_path):
    text = two_boxes().replace('name = "tender"', 'name = "tug"')
    with pytest.raises(SceneError) as e:
        js.load_scene(text)
    assert e.value.key == "bodies[0].hydrodynamics.file" and "tug" in str(e.value), str(e.value)
    # the body without a `file` of its own, matched by name: the vessel's file names it
    text = two_boxes().replace('name = "tender"', 'name = "tug"')
    text = text[:text.rindex("file = ")] + "viscous_damping = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n"
    with pytest.raises(SceneError) as e:
        js.load_scene(text)
    assert e.value.key == "vessel.hydrodynamics.file" and "'tender'" in str(e.value), str(e.value)


def test_the_rao_command_writes_each_bodys_rao_at_a_list_of_frequencies(tmp_path, capsys):
    from jaxslosh.cli import main
    from jaxslosh.io.rao import load_rao
    p = tmp_path / "two.toml"
    p.write_text(two_boxes())
    out = str(tmp_path / "two_rao.h5")
    assert main(["rao", str(p), "--frequencies", "0.6091,1.0727", "--headings", "1.5707963267948966", "-o", out]) == 0
    data = load_rao(out)
    ref = reference()
    np.testing.assert_allclose(data.frequency, [0.6091, 1.0727])
    assert sorted(data.bodies) == ["tender"] and data.bodies["tender"].shape == (2, 1, 6)
    want = ref["rao"][[2, 5], 1][:, 6:]                  # tabulated 0.60909 and 1.07273 rad/s
    assert np.abs(data.bodies["tender"][:, 0, 2] - want[:, 2]).max() < 0.01 * np.abs(want[:, 2]).max()
    assert "tender heave" in capsys.readouterr().out


def test_wamit_nbody_files_read_as_the_same_coupled_tables(tmp_path):
    """The two boxes' coupled tables written as WAMIT's NBODY .1 and .3 (12 dofs, ULEN 1) read back
    as the NetCDF's."""
    rho = 1025.0
    t = read_multibody(os.path.join(DATA, "two_boxes.nc"), ("barge", "tender"), rho, G).tables
    with open(tmp_path / "two.1", "w") as f:
        for i in range(12):
            for j in range(12):
                f.write(f"0.0 {i + 1} {j + 1} {t.added_mass_infinite[i, j] / rho:.15e}\n")
        for m in np.argsort(-t.omega):
            for i in range(12):
                for j in range(12):
                    f.write(f"{2 * np.pi / t.omega[m]:.15e} {i + 1} {j + 1} {t.added_mass[m, i, j] / rho:.15e} "
                            f"{t.damping[m, i, j] / (rho * t.omega[m]):.15e}\n")
    with open(tmp_path / "two.3", "w") as f:
        for m in np.argsort(-t.omega):
            for h, beta in enumerate(t.headings):
                for i in range(12):
                    x = t.excitation[m, h, i] / (rho * G)
                    f.write(f"{2 * np.pi / t.omega[m]:.15e} {np.degrees(beta):.15e} {i + 1} {abs(x):.15e} "
                            f"{np.degrees(np.angle(x)):.15e} {x.real:.15e} {x.imag:.15e}\n")
    w = read_multibody(str(tmp_path / "two.1"), ("barge", "tender"), rho, G)
    np.testing.assert_allclose(w.tables.omega, t.omega, rtol=1e-12)
    for a, b in ((w.tables.added_mass, t.added_mass), (w.tables.damping, t.damping),
                 (w.tables.added_mass_infinite, t.added_mass_infinite), (w.tables.excitation, t.excitation)):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * np.abs(b).max())
    assert w.warnings == ()


@pytest.mark.slow       # 40 s on a loaded machine; its fast twin: the far-apart RAOs (the same matrices)
def test_coupled_modes_of_bodies_far_apart_are_each_bodys_own():
    """`modes --coupled` takes each body's radiation at the mode's frequency: 1,000 m apart the
    tender's roll, heave and pitch are those of the tender alone (the same fixed point)."""
    from jaxslosh.analysis.coupled import coupled_modes
    pair = coupled_modes(js.load_scene(two_boxes(1000.0, ("barge.nc", "tender.nc"))), n=6)
    alone = coupled_modes(js.load_scene("[simulation]\nduration = 1.0\ndt = 0.1\n"
                                        + box("vessel", "tender", 1, "tender.nc")), n=3)
    got = {d: w for d, w in zip(pair.dominant, pair.omega) if d.startswith("tender ")}
    assert len(got) == 3
    for d, w in zip(alone.dominant, alone.omega):
        assert got[f"tender {d}"] == pytest.approx(w, rel=1e-6)


def test_a_wave_heading_outside_a_bodys_tables_names_its_heading():
    """The tender's file holds headings 0 and pi/2 (relative to its x axis): turned by -90 deg in beam
    seas it would need pi, which it has not."""
    waves = '[waves]\ntype = "regular"\namplitude = 0.1\nfrequency = 0.9\nheading = 1.5707963267948966\n'
    text = two_boxes(1000.0, ("barge.nc", "tender.nc"), waves=waves)
    js.load_scene(text)
    with pytest.raises(SceneError) as e:
        js.load_scene(text.replace("position = [0.0, 1000.0]", "position = [0.0, 1000.0]\nheading = -1.5707963267948966"))
    assert e.value.key == "bodies[0].heading", str(e.value)
