"""Coupled modes (issue 20): `jaxslosh modes --coupled`, the quadratic eigenproblem of the scene
linearised about rest, against the spectrum of a long free run of the paper example and against
the closed forms of a vessel alone; radiation at each mode's frequency by iteration."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.analysis.coupled import coupled_modes
from jaxslosh.cli import main
from jaxslosh.hydro.tables import interpolate_radiation, scene_tables

from helpers import vessel_scene

ROOT = Path(__file__).resolve().parents[2]


def spectrum_peak(t, x, lo, hi):
    """The frequency (rad/s) of the largest peak of |FFT| in [lo, hi]: a Hann window, zero padding to
    64 times the record, and a parabola through the log-magnitudes of the top bin and its neighbours."""
    x = (x - x.mean()) * np.hanning(x.size)
    n = 64 * x.size
    X = np.abs(np.fft.rfft(x, n))
    w = 2 * np.pi * np.fft.rfftfreq(n, t[1] - t[0])
    band = np.flatnonzero((w >= lo) & (w <= hi))
    k = band[np.argmax(X[band])]
    a, b, c = np.log(X[k - 1:k + 2])
    return w[k] + 0.5 * (a - c) / (a - 2 * b + c) * (w[1] - w[0])


@pytest.mark.slow
def test_paper_example_coupled_modes_against_a_long_free_run():
    """The paper example (scenes/paper_ship_tank.toml) set rolling and pitching by a tenth of its
    initial angular velocity, 300 s of the trapezoidal rule: the peaks of the roll spectrum and of
    probe B's vertical displacement (the free surface near the tank's end wall: the first sloshing
    mode along x) within 0.5 % of the coupled roll and first sloshing frequencies."""
    text = (ROOT / "scenes" / "paper_ship_tank.toml").read_text()
    text = text.replace('scheme = "hht"', 'scheme = "newmark"').replace("alpha = 0.01\n", "") \
        .replace("duration = 20.0", "duration = 300.0").replace("dt = 0.01", "dt = 0.02") \
        .replace("angular_velocity = [0.1, 0.05, 0.0]", "angular_velocity = [0.01, 0.005, 0.0]")
    scene = js.load_scene(text)
    modes = coupled_modes(scene, 8)
    dom = list(modes.dominant)
    roll = modes.damped[dom.index("roll")]
    slosh = modes.damped[dom.index("liquid")]
    r = js.simulate(scene)
    assert r.status == "ok"
    t = np.asarray(r.time)
    peak_roll = spectrum_peak(t, np.asarray(r.vessel.roll_pitch_yaw)[:, 0], 0.8, 1.5)
    peak_slosh = spectrum_peak(t, np.asarray(r.probes["B"].displacement)[:, 2], 2.2, 2.9)
    # the two first sloshing modes (along x and y) are 0.14 % apart: the nearer one
    liquid = modes.damped[[d == "liquid" for d in dom]]
    near = liquid[np.argmin(np.abs(liquid - peak_slosh))]
    print(f"roll: mode {roll:.5f}, spectrum peak {peak_roll:.5f} rad/s ({100 * (peak_roll / roll - 1):+.3f} %); "
          f"first sloshing: modes {slosh:.5f} / {near:.5f}, peak {peak_slosh:.5f} ({100 * (peak_slosh / near - 1):+.3f} %)")
    assert abs(peak_roll / roll - 1) < 0.005
    assert abs(peak_slosh / near - 1) < 0.005
    assert abs(near / slosh - 1) < 0.002


def test_vessel_alone_modes_are_the_closed_forms():
    """Without liquid the coupled modes are the hull's: heave sqrt(rho g A_w / m), roll and pitch
    sqrt(rho g V GM / I), no damping, surge, sway and yaw without restoring left out."""
    scene = vessel_scene()
    m = coupled_modes(scene, 6)
    rho_g = 1025.0 * 9.81
    ref = {"heave": math.sqrt(rho_g * 200.0 / 4.0e5), "roll": math.sqrt(rho_g * 390.0 * 1.5 / 5.0e6),
           "pitch": math.sqrt(rho_g * 390.0 * 15.0 / 1.5e7)}
    assert sorted(m.dominant) == sorted(ref)
    for w, d in zip(m.omega, m.dominant):
        assert abs(w / ref[d] - 1) < 1e-9, (d, w, ref[d])
    assert np.all(m.damping_ratio == 0)
    assert m.not_oscillating == 3


def test_radiation_at_the_modes_own_frequency():
    """The test box with its Capytaine tables: each mode is a fixed point, its frequency the root of
    the 6-dof determinant with A(w), B(w) at that same frequency (the residual's A_inf alone puts
    the roll elsewhere); heave, the most damped, about 10 % of critical."""
    data = Path(__file__).resolve().parents[1] / "data"
    text = (data / "box_20x10x2_hydro.toml").read_text()
    text = text[text.index("[vessel.hydrostatics]"):]
    scene = js.load_scene('title = "box"\n[environment]\ngravity = 9.81\nwater_density = 1025.0\n'
                          '[simulation]\nduration = 1.0\ndt = 0.05\n[vessel]\nmass = 4.1e5\n'
                          'inertia = [6.0e6, 1.6e7, 2.0e7]\n' + text)
    m = coupled_modes(scene, 6)
    t = scene_tables(scene.vessel.hydrodynamics)
    h = scene.vessel.hydrostatics
    rho_g = 1025.0 * 9.81
    Cr = np.diag([0, 0, rho_g * h.waterplane_area, rho_g * h.displaced_volume * h.gm_t,
                  rho_g * h.displaced_volume * h.gm_l, 0])
    M0 = np.diag([4.1e5] * 3 + [6.0e6, 1.6e7, 2.0e7])
    for k, d in enumerate(m.dominant):
        lam = -m.damping_ratio[k] * m.omega[k] + 1j * m.damped[k]
        A, B = interpolate_radiation(t, [m.damped[k]])
        Z = lam * lam * (M0 + A[0]) + lam * B[0] + Cr
        s = np.linalg.svd(Z, compute_uv=False)
        assert s[-1] < 1e-8 * s[0], (d, s[-1] / s[0])
        assert m.radiation[k] == "table"
    heave = m.damping_ratio[list(m.dominant).index("heave")]
    assert 0.05 < heave < 0.2


def test_modes_coupled_command(capsys):
    assert main(["modes", str(ROOT / "scenes" / "paper_ship_tank.toml"), "--coupled", "-n", "5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["coupled"] and len(d["omega"]) == 5 and d["omega"] == sorted(d["omega"])
    # the yaw mode: the stabilized element's rotation penalty holds the liquid's absolute rotation, so a
    # yawed tank pulls back (README, Frequency domain)
    assert d["dominant"] == ["yaw", "roll", "pitch", "heave", "liquid"]
    # issue 31, item 19: that yaw mode is labelled for what it is, by the share of its potential
    # energy in the penalty (all of it: no hydrostatics acts on yaw); the other modes hold none
    assert d["label"] == ["liquid rotation penalty (numerical)", "roll", "pitch", "heave", "liquid"]
    assert abs(d["penalty_share"][0] - 1) < 1e-3 and max(d["penalty_share"][1:]) < 1e-3
    assert main(["modes", str(ROOT / "scenes" / "paper_ship_tank.toml"), "--coupled", "-n", "3"]) == 0
    out = capsys.readouterr().out
    assert "roll" in out and "damping" in out
    assert "<- liquid rotation penalty (numerical)" in out.splitlines()[2] and "mode 1: liquid rotation penalty" in out
    assert main(["modes", str(ROOT / "scenes" / "paper_ship_tank.toml"), "--coupled", "--tank", "tank"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


TWO_TANKS = """
[[tanks]]
name = "fore"
origin = [2.0, -1.0, -1.0]
size = [2.0, 2.0, 2.0]
fill_depth = 1.0
mesh = [3, 3, 2]
[[tanks]]
name = "aft"
origin = [-6.0, -2.0, -1.0]
size = [4.0, 4.0, 2.0]
fill_depth = 1.0
mesh = [3, 3, 2]
"""


def test_modes_of_a_scene_with_several_tanks_shows_each_tank_labelled(tmp_path, capsys):
    """Issue 31, item 9: without --tank every tank is shown, each under its name (its first mode the
    one `--tank` gives alone); --json keeps the first tank's fields at the top and adds "tanks"."""
    from helpers import VESSEL
    path = tmp_path / "two.toml"
    path.write_text(VESSEL.format(duration=1.0, dt=0.01, scheme="hht", alpha=0.01, omega=[0.0, 0.0, 0.0],
                                  position=[0.0, 0.0, 0.0]) + TWO_TANKS)
    assert main(["modes", str(path), "-n", "2"]) == 0
    out = capsys.readouterr().out
    assert "tank 'fore' (1 of 2)" in out and "tank 'aft' (2 of 2)" in out
    assert main(["modes", str(path), "-n", "2", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["tank"] == "fore" and [t["tank"] for t in d["tanks"]] == ["fore", "aft"]
    assert d["omega"] == d["tanks"][0]["omega"]
    assert main(["modes", str(path), "-n", "2", "--json", "--tank", "aft"]) == 0
    aft = json.loads(capsys.readouterr().out)
    assert aft["omega"] == d["tanks"][1]["omega"] and "tanks" not in aft
    # a 4 m wide tank sloshes slower than a 2 m one (omega^2 = g k tanh(k h), k = pi / width)
    assert aft["omega"][0] < d["omega"][0]
    assert main(["modes", str(path), "--tank", "mid"]) == 2
    assert "--tank: no tank named 'mid' (tanks: fore, aft)" in capsys.readouterr().err
