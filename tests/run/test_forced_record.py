"""Tank tests driven by a motion record (`[vessel.forced] file`, SPEC section 9) and the harmonic
form's `phase` (issue 33, item 2).

- A record sampled from the harmonic law reproduces the harmonic run (probe B, the finite-element
  tank and the same tank on its modes).
- The interpolant: through the samples, its acceleration continuous at every sample (its third
  derivative jumps there: the check can fail), and the body angular velocity of several recorded
  angles equal to A^T dA/dt of the recorded attitude (finite differences).
- Bad records: exit 2 naming the line and column; the scene key registry lists the forced keys.
"""
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli.main import main
from jaxslosh.physics.kinematics import quat_from_rpy, rotation_matrix
from jaxslosh.physics.vessel import RecordedMotion, record_coefficients
from jaxslosh.scene.keys import KEY_DOCS, scene_values, with_overrides
from jaxslosh.scene.types import DOFS, SceneError

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
A, W, RAMP, PHASE = 0.02, 2.4, 1.5, 0.3


def _law(t):
    s = np.clip(t / RAMP, 0.0, 1.0)
    return A * np.sin(W * t + PHASE) * (s - np.sin(2 * np.pi * s) / (2 * np.pi))


def _scene(tmp_path, forced, duration=3.0, extra_tank=""):
    t = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    t = t.replace("duration = 20.0", f"duration = {duration}").replace("mesh = [5, 5, 5]", "mesh = [4, 4, 3]")
    t = t.replace("[vessel.hydrostatics]", "[vessel.forced]\n" + forced + "\n\n[vessel.hydrostatics]")
    t = t.replace('walls = "rigid"\n', 'walls = "rigid"\n' + extra_tank + "\n")
    path = tmp_path / "scene.toml"
    path.write_text(t)
    return str(path)


def _write_csv(path, header, rows):
    with open(path, "w") as fh:
        fh.write(",".join(header) + "\n")
        for r in rows:
            fh.write(",".join(repr(float(x)) for x in r) + "\n")


@pytest.mark.parametrize("reduced", [False, True], ids=["finite elements", "20 modes"])
def test_a_record_of_the_harmonic_law_reproduces_the_harmonic_run(tmp_path, reduced):
    """Sway near the first sloshing frequency, sampled every 0.02 s (the run's step is 0.01 s):
    probe B within 1e-3 of its largest excursion (measured 7e-5 on the 5x5x5 tank)."""
    t = np.arange(0.0, 3.0 + 1e-9, 0.02)
    _write_csv(tmp_path / "motion.csv", ["t", "sway"], np.stack([t, _law(t)], 1))
    tank = "[tanks.reduction]\nmodes = 20" if reduced else ""
    harm = js.simulate(js.load_scene(_scene(
        tmp_path, f'dof = "sway"\namplitude = {A}\nfrequency = {W}\nramp = {RAMP}\nphase = {PHASE}', extra_tank=tank)))
    rec = js.simulate(js.load_scene(_scene(tmp_path, 'file = "motion.csv"', extra_tank=tank)))
    assert harm.status == rec.status == "ok"
    b_h, b_r = np.asarray(harm.probes["B"].displacement), np.asarray(rec.probes["B"].displacement)
    print(f"probe B: largest {np.abs(b_h).max():.4g} m, record - harmonic {np.abs(b_r - b_h).max():.3g} m")
    assert np.abs(b_h).max() > 1e-3                              # the liquid does move
    assert np.abs(b_r - b_h).max() < 1e-3 * np.abs(b_h).max(), np.abs(b_r - b_h).max()
    y = np.asarray(harm.vessel.position)[:, 1]
    assert np.abs(y - _law(np.asarray(harm.time))).max() < 1e-3 * A     # the harmonic form with its phase


def _motion(t, columns):
    knots, coef = record_coefficients(tuple(t), tuple(columns), DOFS)
    return RecordedMotion(knots=jnp.asarray(knots), coef=jnp.asarray(coef))


def test_the_interpolant_passes_the_samples_with_continuous_acceleration():
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.05, 0.2, 30)) - 0.1
    x = rng.normal(size=30)
    m = _motion(t, [("heave", tuple(x))])
    coords = jax.jit(jax.vmap(m.coordinates))(jnp.asarray(t))
    np.testing.assert_allclose(coords[:, 2], x, rtol=0, atol=1e-12)
    assert np.abs(np.delete(np.asarray(coords), 2, axis=1)).max() == 0.0          # the other dofs held
    acc = jax.jit(jax.vmap(m.accelerations))
    jerk = jax.jit(jax.vmap(lambda s: jax.jvp(lambda u: m.accelerations(u)[2], (s,), (1.0,))[1]))
    inner = jnp.asarray(t[1:-1])
    eps = 1e-9
    left, right = acc(inner - eps)[:, 2], acc(inner + eps)[:, 2]
    scale = np.abs(np.asarray(acc(jnp.asarray(t))[:, 2])).max()
    assert np.abs(left - right).max() < 1e-6 * scale                           # C2 at every sample
    assert np.abs(jerk(inner - eps) - jerk(inner + eps)).min() > 1e-3          # its third derivative jumps
    # natural ends: no acceleration at the record's first and last samples
    np.testing.assert_allclose(acc(jnp.asarray(t[[0, -1]]))[:, 2], 0.0, atol=1e-9 * scale)


def test_the_body_angular_velocity_of_recorded_angles():
    """omega from the recorded roll, pitch and yaw rates against A^T dA/dt of the attitude (central
    differences), and its derivative against differences of omega."""
    t = np.linspace(0.0, 4.0, 41)
    cols = [("roll", tuple(0.3 * np.sin(1.1 * t))), ("pitch", tuple(0.2 * np.cos(0.7 * t))),
            ("yaw", tuple(0.5 * t))]
    m = _motion(t, cols)
    A_of = lambda s: rotation_matrix(quat_from_rpy(m.coordinates(s)[3:]))       # noqa: E731
    h = 1e-5
    for s in (0.37, 1.9, 3.33):
        dA = (A_of(s + h) - A_of(s - h)) / (2 * h)
        Om = np.asarray(A_of(s).T @ dA)
        omega = np.asarray(m.rates(jnp.asarray(s))[3:])
        np.testing.assert_allclose(omega, [Om[2, 1], Om[0, 2], Om[1, 0]], atol=1e-8)
        alpha = (m.rates(jnp.asarray(s + h))[3:] - m.rates(jnp.asarray(s - h))[3:]) / (2 * h)
        np.testing.assert_allclose(np.asarray(m.accelerations(jnp.asarray(s))[3:]), alpha, atol=1e-7)


def test_a_phase_without_ramp_starts_the_motion_where_the_law_is(tmp_path):
    from jaxslosh.assemble.system import build
    b = build(js.load_scene(_scene(tmp_path, f'dof = "surge"\namplitude = {A}\nfrequency = {W}\nphase = {PHASE}')))
    assert abs(float(b.c0.X0[0]) - A * np.sin(PHASE)) < 1e-15
    assert abs(float(b.v0[0]) - A * W * np.cos(PHASE)) < 1e-15


GOOD = [[0.0, 0.0], [1.0, 0.01], [2.0, 0.0], [3.0, -0.01], [4.0, 0.0]]


@pytest.mark.parametrize("text, words", [
    ("t,sway\n0,0\n1,0.01\n0.5,0\n3,-0.01\n4,0\n", ["line 4, column t", "0.5 s does not follow 1 s", "increase"]),
    ("t,sway\n0,0\n1,0.01\n2,0\n3,-0.01\n3,0\n", ["line 6, column t"]),
    ("t,sway\n0,0\n1,nan\n2,0\n3,-0.01\n4,0\n", ["line 3, column sway", "nan"]),
    ("t,sway\n0,0\n1,\n2,0\n3,-0.01\n4,0\n", ["line 3, column sway", "'' is not a number"]),
    ("t,swey\n0,0\n1,0.01\n2,0\n3,-0.01\n4,0\n", ["line 1, column 2 'swey'", "not a record column"]),
    ("t,sway\n0,0\n1,0.01\n4,0\n", ["3 rows", "at least 4"]),
    ("time,sway\n0,0\n1,0.01\n2,0\n3,-0.01\n4,0\n", ["column 1 'time'"]),
    ("sway,roll\n0,0\n1,0.01\n2,0\n3,-0.01\n4,0\n", ["no column t"]),
    ("t,sway,sway\n0,0,0\n1,0.01,0\n2,0,0\n3,-0.01,0\n4,0,0\n", ["'sway' is given twice"]),
    ("t,sway\n0,0\n1,0.01,3\n2,0\n3,-0.01\n4,0\n", ["line 3: 3 values"]),
    ("t,sway\n0.5,0\n1,0.01\n2,0\n3,-0.01\n4,0\n", ["starts at t = 0.5 s"]),
    ("t,sway\n0,0\n1,0.01\n2,0\n3,-0.01\n", ["ends at t = 3 s", "simulation.duration"]),
])
def test_a_bad_record_exits_2_naming_the_line_and_column(tmp_path, capsys, text, words):
    (tmp_path / "motion.csv").write_text(text)
    assert main(["check", _scene(tmp_path, 'file = "motion.csv"', duration=4.0)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: vessel.forced.file: motion.csv") and err.count("\n") == 1, err
    for w in words:
        assert w in err, (w, err)


@pytest.mark.parametrize("forced, key", [
    ('file = "motion.csv"\ndof = "sway"', "vessel.forced.dof"),
    ('file = "motion.csv"\namplitude = 1.0', "vessel.forced.amplitude"),
    ('profile = "record"', "vessel.forced.file"),
    ('profile = "spin-up"\ndof = "roll"\nrate = 1.0\nduration = 2.0\nphase = 0.1', "vessel.forced.phase"),
    ('file = "nowhere.csv"', "vessel.forced.file"),
])
def test_record_keys_are_checked(tmp_path, capsys, forced, key):
    _write_csv(tmp_path / "motion.csv", ["t", "sway"], GOOD)
    assert main(["check", _scene(tmp_path, forced, duration=4.0)]) == 2
    assert capsys.readouterr().err.startswith(f"error: {key}: ")


def test_check_describes_the_record_and_the_registry_lists_the_forced_keys(tmp_path, capsys):
    _write_csv(tmp_path / "motion.csv", ["t", "sway", "roll"], [r + [0.0] for r in GOOD])
    path = _scene(tmp_path, 'file = "motion.csv"', duration=4.0)
    assert main(["check", path]) == 0
    out = capsys.readouterr().out
    assert "sway, roll from motion.csv (5 samples, t = 0 to 4 s) by a natural cubic spline" in out, out
    scene = js.load_scene(path)
    assert scene.vessel.forced.profile == "record" and scene.vessel.forced.times[-1] == 4.0
    with pytest.raises(SceneError, match="vessel.forced.file: motion.csv: the record ends at t = 4 s"):
        with_overrides(scene, duration=5.0)                      # the command line's --duration too
    harm = js.load_scene(_scene(tmp_path, f'dof = "roll"\namplitude = {A}\nfrequency = {W}\nphase = {PHASE}'))
    values = scene_values(harm)
    for key, v in (("amplitude", A), ("frequency", W), ("phase", PHASE), ("ramp", 0.0)):
        assert values[f"vessel.forced.{key}"] == v
    documented = {k for k, *_ in KEY_DOCS}
    assert {"vessel.forced.file", "vessel.forced.phase"} <= documented     # the scene reference's rows
    spin = js.load_scene(_scene(tmp_path, 'profile = "spin-up"\ndof = "yaw"\nrate = 1.0\nduration = 2.0'))
    assert scene_values(spin)["vessel.forced.rate"] == 1.0 and "vessel.forced.phase" not in scene_values(spin)
