"""A multimodal tank (tanks.model = "multimodal") in the residual: forced, carried by a free vessel,
differentiated; its scene keys and validity warnings."""
import jax
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli.main import main

FORCED = """
[environment]
gravity = 9.81
[simulation]
duration = {duration}
dt = 0.02
scheme = "newmark"
[vessel]
mass = 1.0e4
inertia = [1.0e4, 1.0e4, 1.0e4]
[vessel.forced]
dof = "surge"
amplitude = {amplitude}
frequency = {w}
ramp = 2.0
[[tanks]]
name = "tank"
origin = [-0.5, -0.2, -0.3]
size = [1.0, 0.4, 0.8]
fill_depth = 0.5
model = "multimodal"
modes = 5
[tanks.damping]
ratio = {ratio}
[[probes]]
name = "wall"
tank = "tank"
point = [0.0, 0.2, 0.5]
[[probes]]
name = "bottom"
tank = "tank"
point = [0.3, 0.2, 0.0]
"""

L, H, G = 1.0, 0.5, 9.81


def _wall_transfer(w, zeta, n):
    """Linear theory: the free-surface elevation at x = 0 per unit surge amplitude, modes 1..n."""
    k = np.arange(1, n + 1) * np.pi / L
    wn = np.sqrt(G * k * np.tanh(k * H))
    c = ((-1.0) ** np.arange(1, n + 1) - 1.0) / k ** 2          # integral of x cos(k x) over the length
    mn = 0.5 * L / (k * np.tanh(k * H))
    return np.sum(-c * w ** 2 / (mn * (wn ** 2 - w ** 2 + 2j * zeta * wn * w)))


def _amplitude(t, z, w, t0):
    m = t > t0
    A = np.stack([np.cos(w * t[m]), np.sin(w * t[m]), np.ones(m.sum())], axis=1)
    a, b, _ = np.linalg.lstsq(A, z[m], rcond=None)[0]
    return np.hypot(a, b)


def test_forced_small_amplitude_is_linear_theory():
    """1 mm of surge: the steady elevation at the wall is linear theory's on the same five modes; a
    probe on the bottom follows the tank."""
    w = 4.0
    r = js.simulate(js.load_scene(FORCED.format(duration=16.0, amplitude=0.001, w=w, ratio=0.1)))
    assert r.status == "ok"
    t, z = np.asarray(r.time), np.asarray(r.probes["wall"].displacement)[:, 2]
    amp = _amplitude(t, z, w, 11.0)
    assert amp == pytest.approx(0.001 * abs(_wall_transfer(w, 0.1, 5)), rel=1e-2)
    bottom = np.asarray(r.probes["bottom"].displacement)
    np.testing.assert_allclose(bottom[:, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(bottom[:, 0], np.asarray(r.vessel.position)[:, 0], atol=1e-12)


def test_crest_is_higher_than_trough_near_resonance():
    """10 mm of surge near the first mode (5.32 rad/s): the crest at the wall exceeds the trough, which
    a linear liquid makes equal. (As long a run as the small-amplitude one: it reuses its compiled
    programs, the forcing and damping being the programs' inputs.)"""
    r = js.simulate(js.load_scene(FORCED.format(duration=16.0, amplitude=0.01, w=5.0, ratio=0.05)))
    t, z = np.asarray(r.time), np.asarray(r.probes["wall"].displacement)[:, 2]
    m = t > 9.0
    crest, trough = z[m].max(), -z[m].min()
    assert crest > 0.03
    assert crest > 1.1 * trough


FREE = """
[environment]
gravity = 9.81
[simulation]
duration = {duration}
dt = 0.01
scheme = "newmark"
[vessel]
mass = 2.0e4
inertia = [2.0e4, 4.0e4, 4.0e4]
[vessel.hydrostatics]
waterplane_area = 20.0
displaced_volume = 23.0
gm_t = 1.0
gm_l = 3.0
[vessel.initial]
angular_velocity = [0.0, 0.05, 0.0]
velocity = [0.1, 0.0, 0.0]
[[tanks]]
name = "tank"
origin = [-1.0, -0.5, 0.0]
size = [2.0, 1.0, 1.2]
fill_depth = 0.6
model = "multimodal"
modes = 4
[[probes]]
name = "wall"
tank = "tank"
point = [0.0, 0.5, 0.6]
"""


@pytest.mark.slow
def test_free_vessel_conserves_energy():
    """Newmark, no damping: the total energy of the vessel and its sloshing liquid stays constant
    over 10 sloshing periods (first mode 0.36 Hz)."""
    r = js.simulate(js.load_scene(FREE.format(duration=28.0)))
    assert r.status == "ok"
    E = np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)
    z = np.asarray(r.probes["wall"].displacement)[:, 2]
    assert np.abs(z).max() > 0.01                       # the liquid sloshes
    assert np.abs(E - E[0]).max() <= 1e-4 * E[0]


@pytest.mark.slow
@pytest.mark.parametrize("expansion", ["exact", "third-order"])
def test_gradient_through_a_run_matches_finite_differences(expansion):
    """Through the exact integrals and through their third-order polynomial (liquid/multimodal/expansion.py)."""
    scene = js.load_scene(FREE.format(duration=0.3).replace("modes = 4", f'modes = 4\nexpansion = "{expansion}"'))

    def f(h):
        r = js.simulate(scene, params={"tanks.tank.fill_depth": h})
        return r.probes["wall"].displacement[-1, 2]
    h = 0.6
    g = float(jax.grad(f)(h))
    eps = 1e-4
    fd = (float(f(h + eps)) - float(f(h - eps))) / (2 * eps)
    assert g == pytest.approx(fd, rel=1e-4, abs=1e-9)
    assert abs(g) > 1e-4


def test_keys_and_warnings():
    """The loader's keys and warnings for a multimodal tank (the run's warning of a surface past the
    roof: test_multimodal_steep.py, on the programs of its resonant run; that the command line prints
    a run's warnings: tests/io/test_files.py)."""
    base = FORCED.format(duration=1.0, amplitude=0.001, w=4.0, ratio=0.1)
    shallow = js.load_scene(base.replace("fill_depth = 0.5", "fill_depth = 0.05").replace(
        "point = [0.0, 0.2, 0.5]", "point = [0.0, 0.2, 0.05]"))
    assert any("shallow-water" in w and "tanks[0]" in w for w in shallow.warnings)
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.baffles"):
        js.load_scene(base + '[[tanks.baffles]]\nnormal = "x"\nposition = 0.5\nheight = 0.2\n')
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.modes"):
        js.load_scene(base.replace('model = "multimodal"\n', 'mesh = [2, 1, 2]\n'))
    two = base + '[[tanks]]\nname = "b"\norigin = [2.0, 0.0, 0.0]\nsize = [1.0, 1.0, 1.0]\nfill_depth = 0.5\nmesh = [2, 2, 2]\n'
    with pytest.raises(js.SceneError, match=r"tanks\[1\]\.model"):
        js.load_scene(two)


# slow, for the default suite's budget: it keeps a batch of multimodal tanks equal to its single runs
# (tests/solve/test_batch_fresh_redo.py)
@pytest.mark.slow
def test_batch_of_fill_depths_matches_single_runs():
    """simulate_batch takes a multimodal tank: each run of a batch is the single run's."""
    scene = js.load_scene(FORCED.format(duration=1.0, amplitude=0.005, w=5.0, ratio=0.02))
    depths = np.array([0.45, 0.5])
    r, statuses = js.simulate_batch(scene, {"tanks.tank.fill_depth": depths})
    assert statuses == ["ok", "ok"]
    one = js.simulate(scene, params={"tanks.tank.fill_depth": 0.45})
    np.testing.assert_allclose(np.asarray(r.probes["wall"].displacement)[0], np.asarray(one.probes["wall"].displacement),
                               rtol=1e-7, atol=1e-10)


def test_steep_surface_warns_with_its_time():
    """The run's validity watch: a multimodal surface steeper than tan 30 deg (breaking) is said with
    the frame's time; a gentler one is not."""
    from jaxslosh.run.validity import Watch
    scene = js.load_scene(FORCED.format(duration=1.0, amplitude=0.001, w=4.0, ratio=0.1))
    w = Watch(scene)
    beta = np.zeros((3, 5))
    beta[1, 0] = 0.5 / np.pi           # slope k_1 beta_1 = 0.5 at mid-tank: steep, not breaking
    beta[2, 1] = 0.31 / np.pi          # k_2 beta_2 = 0.62
    surface = np.zeros((3, 1, 2))
    w.update(np.array([0.1, 0.2, 0.3])[:2], surface[:2], np.zeros(2), beta[:2])
    assert not any("slope" in m for m in w.warnings())
    w.update(np.array([0.3]), surface[2:], np.zeros(1), beta[2:])
    msg = [m for m in w.warnings() if "slope" in m]
    assert len(msg) == 1 and "t = 0.3 s" in msg[0] and "0.62" in msg[0] and "tanks[0]" in msg[0], msg


def test_modes_command_lists_the_linear_frequencies(tmp_path, capsys):
    """`jaxslosh modes` on a multimodal tank: its own modes, omega^2 = g k tanh(k h), at most `modes`."""
    import json
    p = tmp_path / "s.toml"
    p.write_text(FORCED.format(duration=1.0, amplitude=0.001, w=4.0, ratio=0.1))
    assert main(["modes", str(p), "-n", "8", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    k = np.arange(1, 6) * np.pi / L
    np.testing.assert_allclose(out["omega"], np.sqrt(G * k * np.tanh(k * H)), rtol=1e-12)
    assert out["kind"] == ["sloshing"] * 5


def test_rao_of_a_multimodal_tank_is_the_finite_elements_along_its_length():
    """js.rao linearises the multimodal rows about rest: in head seas (the flow along the tank's
    length the only sloshing) the paper ship's pitch and surge RAOs with its tank as 10 modes are the
    10-mode finite elements' within 0.2 % below the sloshing resonance (2.43 rad/s) and 3 % near it
    (the 5 x 5 x 5 mesh's own first mode is off linear theory there). Measured: 0.045 % and 1.8 %,
    as with 20 modes each (the same to 4e-6), whose multimodal linearisation costs three times the
    CPU."""
    from pathlib import Path
    from test_frequency import with_hull
    text = (Path(__file__).resolve().parents[2] / "scenes" / "paper_ship_tank.toml").read_text()
    fem = text.replace('walls = "rigid"', 'walls = "rigid"\n[tanks.reduction]\nmodes = 10')
    mm = text.replace('mesh = [5, 5, 5]\nwalls = "rigid"', 'model = "multimodal"\nmodes = 10')
    w = np.array([0.6, 1.0, 1.5, 2.3])
    a, b = js.rao(with_hull(fem), w, [0.0]), js.rao(with_hull(mm), w, [0.0])
    for j in (0, 4):
        A, B = np.abs(a.vessel[:, 0, j]), np.abs(b.vessel[:, 0, j])
        assert A.min() > 0
        assert np.all(np.abs(B / A - 1) < [2e-3, 2e-3, 2e-3, 3e-2]), (j, B / A - 1)
