"""Liquid damping (`[tanks.damping]`, SPEC section 5): modal damping of the sloshing modes, the
laminar boundary-layer ratio, the solver's low-rank update, fits and batches of the ratio."""
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.damping import build_damping
from jaxslosh.assemble.liquid import build_liquid_block
from jaxslosh.assemble.system import build
from jaxslosh.cli.main import main
from jaxslosh.liquid.damping import rectangular_ratio
from jaxslosh.fit.identify import identify
from jaxslosh.fit.problem import add_noise
from jaxslosh.run.simulate import prepare
from jaxslosh.solve.integrator import initial_state, step
from jaxslosh.liquid.modal_damping import LowRankUpdate, ModalDamping

from helpers import vessel_scene

# A 1.0 x 0.4 m tank filled to 0.5 m, held still (a prescribed surge of amplitude 0 holds the six
# rigid dofs): its liquid alone, first sloshing mode about 5.3 rad/s (1.18 s).
HELD = """
title = "held tank"
[environment]
gravity = 9.81
[simulation]
duration = {duration}
dt = {dt}
scheme = "{scheme}"
alpha = {alpha}
[vessel]
mass = 1.0e4
inertia = [1.0e4, 1.0e4, 1.0e4]
[vessel.forced]
dof = "surge"
amplitude = 0.0
frequency = 1.0
[[tanks]]
name = "tank"
origin = [-0.5, -0.2, -0.3]
size = [1.0, 0.4, 0.6]
fill_depth = 0.5
mesh = [8, 2, 4]
"""


def held(duration=7.0, dt=0.01, scheme="newmark", alpha=0.0, extra=""):
    return js.load_scene(HELD.format(duration=duration, dt=dt, scheme=scheme, alpha=alpha) + extra)


def free_decay(scene, amplitude=1e-3, mode=None):
    """The corner's surface heave (t, z, omega, mode) of a free decay started on `mode` (default the
    first damped mode): a velocity along it, the rest at the hydrostatic start."""
    setup = prepare(scene)
    b, solver = setup.built, setup.solver
    system = b.system
    M = system.liquid.constant_blocks()[0]
    if mode is None:
        mode = np.linalg.solve(np.asarray(M), np.asarray(system.tail[0].B[:, 0]))
    mode = mode / np.max(np.abs(np.asarray(system.liquid.nodal_fields(system.liquid.frame_field(jnp.asarray(mode))))))
    omega = float(np.sqrt(mode @ np.asarray(system.liquid.constant_blocks()[1]) @ mode / (mode @ np.asarray(M) @ mode)))
    v0 = b.v0.at[6:].set(amplitude * omega * jnp.asarray(mode))
    corner = b.surfaces[0][0]
    s0, _ = initial_state(system, solver, b.c0, v0)
    z, ok = _decay_run(system, solver, s0, jnp.asarray(corner)[None], setup.n_steps)
    assert bool(jnp.all(ok))
    z = np.asarray(z) - float(system.liquid.surface_heave(b.c0.d, corner[None])[0])
    return np.arange(1, setup.n_steps + 1) * float(scene.simulation.dt), z, omega, mode


@eqx.filter_jit
def _decay_run(system, solver, s0, corner, n_steps):
    """The corner's heave and each step's convergence over n_steps steps. The model and solver are
    the program's inputs, not constants of a closure: runs of the same structure (the damped and
    undamped runs of a test, the tests' runs on one scheme) share one compiled program."""
    def one(s, _):
        s, info = step(system, solver, s)
        return s, (system.liquid.surface_heave(s.c.d, corner)[0], info.ok)
    return jax.lax.scan(one, s0, None, length=n_steps)[1]


def decrement(z):
    """The mean logarithmic decrement of successive maxima (each refined by a parabola through
    the sample and its neighbours): the slope of log(peak) against the peak's count."""
    i = np.flatnonzero((z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:])) + 1
    a, b, c = z[i - 1], z[i], z[i + 1]
    peaks = b - 0.125 * (c - a) ** 2 / (a - 2 * b + c)
    assert len(peaks) >= 4, peaks
    return -np.polyfit(np.arange(len(peaks)), np.log(peaks), 1)[0]


def target(zeta):
    return 2 * np.pi * zeta / np.sqrt(1 - zeta ** 2)


REDUCED = "[tanks.reduction]\nmodes = 6\n"


@pytest.mark.parametrize("order", ["full", "reduced"])
def test_free_decay_of_the_first_mode_has_the_logarithmic_decrement_of_its_ratio(order):
    """ratio = 0.02 on the first sloshing mode, trapezoidal rule at 118 steps a period: the decrement
    of the corner's heave is 2 pi 0.02 / sqrt(1 - 0.02^2) within 3 %; without damping it is below 1 % of it."""
    extra = (REDUCED if order == "reduced" else "")
    t, z, omega, mode = free_decay(held(extra=extra + "[tanks.damping]\nratio = [0.02]\n"))
    assert 5.0 < omega < 5.6
    delta = decrement(z)
    assert abs(delta / target(0.02) - 1) < 0.03, (delta, target(0.02))
    # undamped: the same table at ratio 0, a run of the same structure (its compiled program is the
    # damped run's), whose damping term adds nothing
    _, z0, _, _ = free_decay(held(extra=extra + "[tanks.damping]\nratio = [0.0]\n"), mode=mode)
    assert abs(decrement(z0)) < 0.01 * target(0.02), decrement(z0)


def test_hht_damps_too():
    """HHT (alpha = 0.01, its own dissipation small at 118 steps a period) with ratio = 0.02: the
    decrement is the ratio's within 5 %, and the undamped HHT run's is below 5 % of it."""
    t, z, _, mode = free_decay(held(scheme="hht", alpha=0.01, extra="[tanks.damping]\nratio = 0.02\n"))
    assert abs(decrement(z) / target(0.02) - 1) < 0.05, decrement(z)
    _, z0, _, _ = free_decay(held(scheme="hht", alpha=0.01, extra="[tanks.damping]\nratio = 0.0\n"), mode=mode)
    assert 0 <= decrement(z0) < 0.05 * target(0.02), decrement(z0)


def test_viscosity_against_the_boundary_layer_formula():
    """The first mode's laminar boundary-layer ratio from the mesh's mode (wall integrals) against the
    closed form for a rectangular tank (liquid/damping.py rectangular_ratio) within 10 % on two meshes,
    proportional to sqrt(nu); a ratio adds to it."""
    closed = rectangular_ratio(1.0, 0.4, 0.5, 9.81, 1e-6)
    k, h = math.pi / 1.0, 0.5                 # the formula written out here, apart from liquid/damping.py
    w = math.sqrt(9.81 * k * math.tanh(k * h))
    by_hand = math.sqrt(1e-6 / (2 * w)) * (1 / 1.0 + 1 / 0.4 + k * (1 - 2 * h / 1.0) / math.sinh(2 * k * h))
    assert abs(closed / by_hand - 1) < 1e-12, (closed, by_hand)
    for mesh in ([8, 2, 4], [12, 4, 6]):
        text = HELD.format(duration=1.0, dt=0.01, scheme="newmark", alpha=0.0).replace("[8, 2, 4]", str(mesh))
        for nu, ratio in ((1e-6, 0.0), (4e-6, 0.0), (1e-6, 0.01)):
            scene = js.load_scene(text + f"[tanks.damping]\nratio = {ratio}\nviscosity = {nu}\n")
            damping, table = build_damping(scene, None, _block(scene))
            zeta = float(np.asarray(table[0].zeta)[0])
            assert abs((zeta - ratio) / (closed * np.sqrt(nu / 1e-6)) - 1) < 0.10, (mesh, nu, zeta, closed)


def test_viscous_decay_matches_its_ratio():
    """A run with viscosity alone (1e-3 m^2/s, a ratio of a few per cent) decays with the decrement
    of the first mode's boundary-layer ratio within 3 %."""
    scene = held(extra="[tanks.damping]\nviscosity = 1.0e-3\n")
    _, table = build_damping(scene, None, _block(scene))
    zeta = float(np.asarray(table[0].zeta)[0])
    assert 0.02 < zeta < 0.06
    _, z, _, _ = free_decay(scene)
    assert abs(decrement(z) / target(zeta) - 1) < 0.03, (decrement(z), target(zeta))


def _block(scene):
    return build_liquid_block(scene, None, scene.environment.gravity)


@pytest.mark.parametrize("linear_solver", ["dense", "sparse"])
def test_the_step_block_takes_the_damping_by_a_low_rank_update(linear_solver):
    """The Woodbury update of the step block's inverse (on the dense inverse, or on the fast
    diagonalization of the sparse path) equals the dense inverse of c_a M + c_v C + K."""
    table = "[tanks.damping]\nratio = 0.03\nviscosity = 1e-6\n"
    scene = held(extra=table)
    setup = prepare(scene)
    system, solver = setup.built.system, setup.solver
    if linear_solver == "sparse":
        text = scene.text.replace("[simulation]", '[simulation]\nlinear_solver = "sparse"')
        solver = prepare(js.load_scene(text)).solver
    assert isinstance(solver.Cinv_step, LowRankUpdate)
    M, K = (np.asarray(x) for x in system.liquid.constant_blocks())
    damping, = (t for t in system.all_terms() if isinstance(t, ModalDamping))
    B, c = np.asarray(damping.B), np.asarray(damping.c)
    s = solver.scheme
    h = float(scene.simulation.dt)
    A = solver.c_a * M + K + s.gamma / (s.beta * h) * (B * c) @ B.T
    x = np.random.default_rng(0).standard_normal(M.shape[0])
    ref = np.linalg.solve(A, x)
    assert np.max(np.abs(np.asarray(solver.Cinv_step @ jnp.asarray(x)) - ref)) < 1e-9 * np.max(np.abs(ref))


# ------------------------------------------------------------------------------------------------
# the coupled ship: a tank on the test vessel, rolling and pitching from an initial angular velocity

TANK = """
[[tanks]]
name = "tank"
origin = [-2.0, -1.5, -1.0]
size = [4.0, 3.0, 2.0]
fill_depth = 1.2
mesh = [4, 3, 2]
[tanks.damping]
ratio = {ratio}
[[probes]]
name = "B"
tank = "tank"
point = [0.0, 0.0, 1.2]
"""


def ship(ratio=0.02, duration=8.0):
    return vessel_scene(duration=duration, dt=0.02, scheme="newmark", alpha=0.0, omega=(0.05, 0.02, 0.0),
                        extra=TANK.format(ratio=ratio))


def test_a_batch_of_two_ratios_equals_the_two_single_runs():
    """A vmapped batch of ratios 0.01 and 0.1 against two single runs: equal to the Newton
    tolerance (a batch forms its preconditioner on another schedule, so the iterates differ there)."""
    scene = ship(duration=3.0)
    key = "tanks.tank.damping.ratio"
    batch, statuses = js.simulate_batch(scene, {key: jnp.array([0.01, 0.1])})
    assert statuses == ["ok", "ok"]
    for i, ratio in enumerate((0.01, 0.1)):
        single = js.simulate(scene, params={key: ratio})
        zb = np.asarray(batch.probes["B"].displacement[i])
        assert np.max(np.abs(zb - np.asarray(single.probes["B"].displacement))) < 1e-7 * np.max(np.abs(zb))
        rpy = np.asarray(batch.vessel.roll_pitch_yaw[i])
        assert np.max(np.abs(rpy - np.asarray(single.vessel.roll_pitch_yaw))) < 1e-7 * np.max(np.abs(rpy))
    # the two ratios give different runs
    assert np.max(np.abs(np.asarray(batch.probes["B"].displacement[0] - batch.probes["B"].displacement[1]))) > 1e-4


@pytest.mark.slow
def test_identify_recovers_the_damping_ratio_from_a_noisy_decay():
    """8 s of the coupled roll and sloshing with ratio 0.02, noise on roll, pitch and the surface
    probe; the fit starts at 0.035 and recovers 0.02 within 2 %."""
    scene = ship(0.02)
    clean = js.simulate(scene)
    z = np.asarray(clean.probes["B"].displacement[:, 2])
    measured = add_noise(clean, {"roll": 1e-5, "pitch": 1e-5, "probes.B": 2e-2 * np.std(z)}, seed=3)
    key = "tanks.tank.damping.ratio"
    fit = identify(scene, measured, [key], x0={key: 0.035})
    assert fit.converged, fit.message
    assert abs(fit.values[key] / 0.02 - 1) < 0.02, fit.values


@pytest.mark.slow
def test_gradient_of_the_ratio_matches_central_differences():
    scene = ship(0.02, duration=2.0)
    key = "tanks.tank.damping.ratio"

    def loss(r):
        out = js.simulate(scene, params={key: r})
        return jnp.sum(out.probes["B"].displacement[:, 2] ** 2)

    g = float(jax.grad(loss)(0.02))
    h = 1e-4
    fd = (float(loss(0.02 + h)) - float(loss(0.02 - h))) / (2 * h)
    assert g != 0.0 and abs(g - fd) <= 1e-4 * abs(fd), (g, fd)


# ------------------------------------------------------------------------------------------------
# input

@pytest.mark.parametrize("table, key, words", [
    ("ratio = -0.01", "tanks[0].damping.ratio", "[0, 1)"),
    ("ratio = 1.0", "tanks[0].damping.ratio", "[0, 1)"),
    ("ratio = [0.01, 1.5]", "tanks[0].damping.ratio", "[0, 1)"),
    ("ratio = []", "tanks[0].damping.ratio", "non-empty"),
    ("viscosity = -1e-6", "tanks[0].damping.viscosity", ""),
    ("ratio = 0.01\nfoo = 1", "tanks[0].damping.foo", "unknown key"),
])
def test_bad_damping_is_refused_naming_the_key(tmp_path, capsys, table, key, words):
    p = tmp_path / "s.toml"
    p.write_text(HELD.format(duration=0.1, dt=0.01, scheme="newmark", alpha=0.0) + "[tanks.damping]\n" + table + "\n")
    assert main(["check", str(p)]) == 2
    err = capsys.readouterr().err
    assert key in err and words in err and len(err.strip().splitlines()) == 1, err


def test_a_list_longer_than_the_meshs_sloshing_modes_is_refused(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(HELD.format(duration=0.1, dt=0.01, scheme="newmark", alpha=0.0)
                 + "[tanks.damping]\nratio = [" + ", ".join(["0.01"] * 40) + "]\n")
    assert main(["run", str(p), "-o", str(tmp_path / "r.h5")]) == 2
    err = capsys.readouterr().err
    assert "tanks[0].damping.ratio" in err and "40" in err, err
    p.write_text(HELD.format(duration=0.1, dt=0.01, scheme="newmark", alpha=0.0) + REDUCED
                 + "[tanks.damping]\nratio = [0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01]\n")
    assert main(["run", str(p), "-o", str(tmp_path / "r.h5")]) == 2
    assert "reduced basis" in capsys.readouterr().err


def test_sweep_refuses_a_ratio_the_loader_refuses(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(HELD.format(duration=0.1, dt=0.01, scheme="newmark", alpha=0.0) + "[tanks.damping]\nratio = 0.02\n")
    assert main(["sweep", str(p), "--param", "tanks.tank.damping.ratio=0.01,1.5", "-o", str(tmp_path / "o.h5")]) == 2
    err = capsys.readouterr().err
    assert "tanks.tank.damping.ratio" in err and "[0, 1)" in err, err


def test_check_prints_the_damping_per_mode(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(HELD.format(duration=0.1, dt=0.01, scheme="newmark", alpha=0.0)
                 + "[tanks.damping]\nratio = [0.02, 0.03]\n")
    assert main(["check", str(p)]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("damping of tank 'tank'"))
    assert "0.02" in line and "0.03" in line and "rad/s" in line, line


def test_without_the_table_nothing_changes():
    """No [tanks.damping]: no damping term, the solver's inverse is the plain one."""
    scene = held()
    setup = prepare(scene)
    assert not setup.built.system.tail and not isinstance(setup.solver.Cinv_step, LowRankUpdate)
    system = build(scene).system
    assert system.all_terms()[-1] is system.liquid


def test_energy_projection_refuses_a_damped_scene():
    text = HELD.format(duration=0.1, dt=0.01, scheme="newmark", alpha=0.0).replace(
        'scheme = "newmark"', 'scheme = "newmark"\nenergy_projection = true')
    text = text.replace("[vessel.forced]\ndof = \"surge\"\namplitude = 0.0\nfrequency = 1.0\n", "")
    with pytest.raises(js.SceneError, match=r"\[tanks.damping\] removes energy"):
        js.load_scene(text + "[tanks.damping]\nratio = 0.02\n")
