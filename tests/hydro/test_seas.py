"""Irregular seas: the Pierson-Moskowitz spectrum, cos-2s directional spreading, reproducible phases,
and a spread sea through a run (Froude-Krylov per heading)."""

import numpy as np
import pytest
from scipy import integrate

import jaxslosh as js
from jaxslosh.cli import main
from jaxslosh.hydro.spectra import components, elevation, pierson_moskowitz, spreading, spreading_density

from test_waves import box_scene

SEA = '\n[waves]\ntype = "{kind}"\nhs = 2.0\ntp = 7.0\nheading = 1.2\nseed = {seed}\ncomponents = 60\n{extra}'


def sea(kind="pierson-moskowitz", seed=3, extra="", hydro=False, **kw):
    return box_scene(waves=SEA.format(kind=kind, seed=seed, extra=extra), hydro=hydro, **kw)


def test_pierson_moskowitz_m0_is_hs2_over_16():
    for hs, tp in ((1.0, 5.0), (3.5, 9.0), (8.0, 14.0)):
        m0 = integrate.quad(lambda w: pierson_moskowitz(w, hs, tp), 0.0, np.inf, limit=400)[0]
        assert abs(m0 / (hs * hs / 16.0) - 1) < 0.01
        w = np.linspace(0.05, 10.0, 200001)
        assert abs(w[np.argmax(pierson_moskowitz(w, hs, tp))] - 2 * np.pi / tp) < 1e-3


@pytest.mark.parametrize("s", [1.0, 2.0, 7.5, 30.0])
def test_spreading_weights_integrate_to_one(s):
    assert abs(integrate.quad(lambda th: spreading_density(th, s), -np.pi, np.pi)[0] - 1) < 1e-10
    theta, wgt = spreading(s, 15)
    assert theta.size == 15 and abs(wgt.sum() - 1) < 1e-14 and abs(theta[7]) < 1e-15
    # the discrete weights follow the density (a fine grid: within the midpoint rule's error)
    th, wg = spreading(s, 401)
    assert abs(np.sum(wg * np.cos(th)) - integrate.quad(lambda t: spreading_density(t, s) * np.cos(t),
                                                         -np.pi, np.pi)[0]) < 1e-6


def test_same_seed_same_phases_and_a_spread_sea_keeps_hs():
    a = sea(seed=5, extra="spreading = 4.0\ndirections = 9\n").waves
    c = components(a)
    assert c.omega.size == 60 * 9 and c.headings.size == 60 * 9
    np.testing.assert_array_equal(components(sea(seed=5, extra="spreading = 4.0\ndirections = 9\n").waves).phase,
                                  c.phase)
    assert not np.allclose(components(sea(seed=6, extra="spreading = 4.0\ndirections = 9\n").waves).phase, c.phase)
    # the long-crested sea of the same seed keeps its frequencies and phases; spread, the energy is shared
    lc = components(sea(seed=5).waves)
    np.testing.assert_array_equal(lc.omega, c.omega[::9])
    np.testing.assert_allclose(np.sum(c.amplitude ** 2), np.sum(lc.amplitude ** 2), rtol=1e-12)
    np.testing.assert_allclose(np.degrees(c.headings[:9]) - np.degrees(1.2), np.degrees(spreading(4.0, 9)[0]),
                               atol=1e-9)
    t = np.arange(0.0, 3600.0, 0.5)
    assert abs(4 * elevation(a, t, point=(30.0, -20.0)).std() / 2.0 - 1) < 0.08


def test_a_spread_sea_runs_and_a_long_crested_one_is_unchanged():
    # the excitation of a spread sea: each heading's Froude-Krylov force on its components
    spread = sea(extra="spreading = 2.0\ndirections = 5\n", duration=2.0, dt=0.05)
    r = js.simulate(spread)
    assert r.status == "ok" and np.isfinite(np.asarray(r.vessel.roll_pitch_yaw)).all()
    # a PM sea is the JONSWAP of gamma = 1
    pm = js.simulate(sea(duration=2.0, dt=0.05))
    jw = js.simulate(sea(kind="jonswap", extra="gamma = 1.0\n", duration=2.0, dt=0.05))
    np.testing.assert_allclose(np.asarray(pm.vessel.position), np.asarray(jw.vessel.position), atol=1e-3 * float(
        np.abs(np.asarray(pm.vessel.position)).max()))


@pytest.mark.parametrize("extra, key", [("gamma = 2.0\n", "waves.gamma"), ("spreading = -1.0\n", "waves.spreading"),
                                        ("directions = 5\n", "waves.directions"),
                                        ("spreading = 2.0\ndirections = 0\n", "waves.directions")])
def test_bad_sea_keys_name_the_key(tmp_path, capsys, extra, key):
    p = tmp_path / "s.toml"
    text = box_scene(hydro=False).text + SEA.format(kind="pierson-moskowitz", seed=1, extra=extra)
    p.write_text(text)
    assert main(["check", str(p)]) == 2
    assert key in capsys.readouterr().err


def test_spreading_needs_froude_krylov(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(box_scene(hydro=True).text + SEA.format(kind="jonswap", seed=1, extra="spreading = 2.0\n"))
    assert main(["check", str(p)]) == 2
    assert "waves.spreading" in capsys.readouterr().err
