"""`modes --tank` of multimodal tanks (issue 43, item 5): each variant's own linear frequencies,
omega^2 = g k tanh(k h), against the closed forms: a two-dimensional box k = i pi / L; a
three-dimensional box k = pi sqrt((i / L)^2 + (j / B)^2); an upright cylinder k = j'_{m,s} / R, the
zeros of the Bessel functions' derivatives (tabulated values, Abramowitz & Stegun table 9.5)."""
import json
import math

import numpy as np
import pytest

from jaxslosh.cli.main import main

G, H = 9.81, 3.0
#: j'_{m,s} in increasing order: (1,1), (2,1), (0,1), (3,1), (4,1), (1,2) (A&S table 9.5)
JP = [(1.841183781, 2), (3.054236928, 2), (3.831705970, 1), (4.201188941, 2), (5.317553126, 2),
      (5.331442774, 2)]

SCENE = """
title = "multimodal modes"
[simulation]
duration = 1.0
dt = 0.01
[vessel]
mass = 1.0e3
inertia = [1.0e3, 1.0e3, 1.0e3]
[vessel.forced]
dof = "surge"
amplitude = 0.01
frequency = 1.0
[[tanks]]
name = "t"
origin = [0.0, 0.0, 0.0]
size = [{L}, {B}, 4.0]
fill_depth = {h}
model = "multimodal"
modes = {modes}
{extra}
"""


def _omega(k):
    k = np.asarray(k, dtype=float)
    return np.sqrt(G * k * np.tanh(k * H))


def _modes(tmp_path, capsys, n=10, **kw):
    path = tmp_path / "s.toml"
    path.write_text(SCENE.format(h=H, **kw))
    assert main(["modes", str(path), "--tank", "t", "-n", str(n), "--json"]) == 0
    return np.array(json.loads(capsys.readouterr().out.strip().splitlines()[-1])["omega"])


def test_an_upright_cylinder_has_the_bessel_frequencies(tmp_path, capsys):
    R = 2.5
    got = _modes(tmp_path, capsys, L=2 * R, B=2 * R, modes=10, extra='shape = "cylinder"\naxis = "z"')
    want = np.concatenate([[z] * m for z, m in JP]) / R         # cos and sin pairs for m >= 1
    assert len(got) == 10 and np.allclose(got[:10], _omega(want[:10]), rtol=1e-8, atol=0), (got, _omega(want))
    np.testing.assert_allclose(got[[0, 2, 4]], [2.656, 3.459, 3.877], atol=1e-3)   # not the 5 m box's 2.426, 3.509, 4.300


def test_a_three_dimensional_box_has_its_rectangle_frequencies(tmp_path, capsys):
    L, B = 5.0, 3.0
    got = _modes(tmp_path, capsys, n=8, L=L, B=B, modes=12, extra='flow = "3d"')
    k = sorted(math.pi * math.hypot(i / L, j / B) for i in range(8) for j in range(8) if i + j)
    np.testing.assert_allclose(got, _omega(k[:8]), rtol=1e-12)
    assert got[1] < _omega(2 * math.pi / L)           # (0, 1) across the tank sits among the lengthwise ones


def test_a_two_dimensional_box_keeps_its_lengthwise_waves(tmp_path, capsys):
    L = 5.0
    got = _modes(tmp_path, capsys, L=L, B=3.0, modes=4, extra="")
    np.testing.assert_allclose(got, _omega(np.arange(1, 5) * math.pi / L), rtol=1e-12)


def test_the_printed_table_of_a_cylinder(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(SCENE.format(L=5.0, B=5.0, h=H, modes=6, extra='shape = "cylinder"\naxis = "z"'))
    assert main(["modes", str(path), "--tank", "t"]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if line.strip()[:1].isdigit()]
    assert [float(r[1]) for r in rows][:5] == pytest.approx([2.65571, 2.65571, 3.45964, 3.45964, 3.87719], abs=2e-5)
    assert "2.42" not in out
