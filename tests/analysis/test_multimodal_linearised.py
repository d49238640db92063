"""A multimodal tank linearised about rest. `jaxslosh modes --coupled`: its rows' tangent (by jax)
in the coupled eigenproblem, against the closed form of a vessel free in surge carrying the tank.
`jaxslosh rao`: a two-dimensional tank in beam seas says what it leaves out.

Forced in surge at frequency w, a two-dimensional tank of N modes pushes back with the apparent mass
m + sum_n m_n w^2 / (w_n^2 - w^2) (n odd, m_n = 8 m tanh(k_n h) / (n^3 pi^3 h / L), the spring-mass
model its rows reproduce): a vessel of mass m_v free in surge then has its coupled modes at the roots
of m_v + m + sum_n m_n w^2 / (w_n^2 - w^2) = 0, one above each odd mode's w_n; the even modes do not
move the tank's mass centre along x and stay at w_n. Heave is the waterplane's spring on the whole
mass (the liquid heaves as a rigid body at first order). Pitch and roll are held by enormous inertias
(they would couple through the liquid's moment)."""
import json

import numpy as np
from scipy.optimize import brentq

from jaxslosh.cli.main import main

L, B, H, G, RHO = 1.0, 0.4, 0.5, 9.81, 1000.0
M_V = 500.0
M_L = RHO * L * B * H
AWP = 0.5
N = 4

SCENE = f"""
[environment]
gravity = {G}
water_density = 1025.0
[simulation]
duration = 1.0
dt = 0.01
[vessel]
mass = {M_V}
inertia = [1.0e12, 1.0e12, 1.0e12]
[vessel.hydrostatics]
waterplane_area = {AWP}
displaced_volume = {(M_V + M_L) / 1025.0}
gm_t = 1.0
gm_l = 1.0
[[tanks]]
name = "tank"
origin = [-0.5, -0.2, -0.3]
size = [{L}, {B}, 0.8]
fill_depth = {H}
model = "multimodal"
modes = {N}
"""


def _closed_form():
    n = np.arange(1, N + 1)
    k = n * np.pi / L
    wn = np.sqrt(G * k * np.tanh(k * H))
    odd = n % 2 == 1
    mn = 8 * M_L * np.tanh(k * H) / (n ** 3 * np.pi ** 3 * H / L)

    def f(w):
        return M_V + M_L + np.sum(mn[odd] * w ** 2 / (wn[odd] ** 2 - w ** 2))

    ends = list(wn[odd]) + [10 * wn[-1]]
    coupled = [brentq(f, a * (1 + 1e-9), b * (1 - 1e-9)) for a, b in zip(ends[:-1], ends[1:])]
    heave = np.sqrt(1025.0 * G * AWP / (M_V + M_L))
    return np.array(coupled), wn[~odd], heave


def test_coupled_modes_of_a_vessel_free_in_surge_carrying_a_multimodal_tank(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(SCENE)
    assert main(["modes", str(p), "--coupled", "-n", "10", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    w = np.asarray(out["omega"])
    found = w[w > 0.1]                       # roll and pitch: the huge inertias' slow modes
    coupled, even, heave = _closed_form()
    expected = np.sort(np.concatenate([coupled, even, [heave]]))
    assert found.shape == expected.shape, (found, expected)
    np.testing.assert_allclose(found, expected, rtol=1e-6)
    # the coupling moves the first sloshing mode well off the tank's own (the closed form holds the
    # vessel, not just the tank)
    w1 = np.sqrt(G * np.pi / L * np.tanh(np.pi * H / L))
    assert coupled[0] > 1.05 * w1
    dominant = dict(zip(np.round(w, 9), out["dominant"]))
    assert dominant[np.round(found[np.argmin(abs(found - heave))], 9)] == "heave"
    assert all(dominant[np.round(found[np.argmin(abs(found - we))], 9)] == "liquid" for we in even)


def test_rao_in_beam_seas_says_a_2d_tank_does_not_slosh_across(tmp_path, capsys):
    """A two-dimensional multimodal tank sloshes along its length only: `jaxslosh rao` at a heading
    with a beam component says so, names the tank and the key that gives waves across it; in head
    seas (heading 0 or pi) it says nothing, nor for a `flow = "3d"` tank."""
    from pathlib import Path

    import jaxslosh as js
    from jaxslosh.analysis.rao import across_tank_warnings
    from test_frequency import HULL
    text = (Path(__file__).resolve().parents[2] / "scenes" / "paper_ship_tank.toml").read_text()
    text = text.replace('mesh = [5, 5, 5]\nwalls = "rigid"', 'model = "multimodal"\nmodes = 2')
    text = text.replace("[vessel.hydrostatics]", HULL + "[vessel.hydrostatics]", 1)
    p = tmp_path / "s.toml"
    p.write_text(text)
    assert main(["rao", str(p), "--frequencies", "1:1:1", "--headings", "0,1.5707963267948966",
                 "-o", str(tmp_path / "r.h5")]) == 0
    err = capsys.readouterr().err
    lines = [x for x in err.splitlines() if x.startswith("warning: tanks[")]
    assert len(lines) == 1, err
    assert "tanks[0] 'tank'" in lines[0] and "heading 90 deg" in lines[0] and 'flow = "3d"' in lines[0], lines
    scene = js.load_scene(text)
    assert across_tank_warnings(scene, [0.0, np.pi]) == []
    assert across_tank_warnings(js.load_scene(text.replace("modes = 2", 'flow = "3d"\nmodes = 2')), [np.pi / 2]) == []
