"""Batched runs: one vmapped compile, the same numbers as single runs; the sweep command."""
from pathlib import Path

import h5py
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.cli import main

from helpers import vessel_scene

ROOT = Path(__file__).resolve().parents[2]


def test_batch_equals_single_runs():
    scene = vessel_scene(duration=3.0, omega=(0.03, 0.01, 0.0))
    gm = np.array([1.0, 1.5, 2.5])
    batch, statuses = js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm})
    assert statuses == ["ok"] * 3 and batch.vessel.quaternion.shape == (3, 301, 4)
    for i, g in enumerate(gm):
        single = js.simulate(scene, params={"vessel.hydrostatics.gm_t": g})
        # the batch forms its Newton preconditioner anew every 4 steps, a single run when its
        # convergence slows: both converge to the Newton tolerance (1e-10 m/s^2), not bitwise alike.
        # An acceleration error below it bounds the attitudes' difference by 1e-10 t^2 / 2 = 4.5e-10
        # at 3 s; measured 6.4e-12 with the predictor a_n, 1.6e-11 with the extrapolated one (the
        # batch then stops after one iteration just below the tolerance, the single run after two)
        np.testing.assert_allclose(np.asarray(batch.vessel.quaternion[i]), np.asarray(single.vessel.quaternion),
                                   atol=5e-11)
    # a larger GM_T rolls less
    roll = np.abs(np.asarray(batch.vessel.roll_pitch_yaw)[:, :, 0]).max(axis=1)
    assert roll[0] > roll[1] > roll[2]


def test_batch_with_liquid_equals_single_runs():
    """With liquid the batch's preconditioner is approximate and carried between its refreshes
    (every 4 steps, a branch that vmap keeps a branch): the runs still converge to the single runs'
    solution (measured on the paper mesh over 3 s: quaternion 1.6e-11, probe B 1.5e-10 m)."""
    text = (ROOT / "scenes" / "paper_ship_tank.toml").read_text().replace("mesh = [5, 5, 5]", "mesh = [3, 3, 2]")
    scene = js.load_scene(text)
    gm = np.array([1.2, 2.0])
    batch, statuses = js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm}, duration=1.0)
    assert statuses == ["ok"] * 2
    for i, g in enumerate(gm):
        single = js.simulate(scene, params={"vessel.hydrostatics.gm_t": g}, duration=1.0)
        np.testing.assert_allclose(np.asarray(batch.vessel.quaternion[i]), np.asarray(single.vessel.quaternion),
                                   atol=1e-9)
        np.testing.assert_allclose(np.asarray(batch.probes["B"].position[i]), np.asarray(single.probes["B"].position),
                                   atol=1e-8)


def test_sweep_command_writes_the_grid(tmp_path, capsys):
    p = tmp_path / "v.toml"
    p.write_text(vessel_scene(duration=1.0, omega=(0.03, 0.01, 0.0)).text)
    out = tmp_path / "sw.h5"
    code = main(["sweep", str(p), "--param", "vessel.hydrostatics.gm_t=1.0,2.0",
                 "--param", "vessel.hydrostatics.gm_l=10,20,30", "-o", str(out)])
    assert code == 0
    with h5py.File(out) as f:
        assert f.attrs["format"] == "jaxslosh.sweep" and f.attrs["runs"] == 6
        assert f["vessel/roll_pitch_yaw"].shape == (6, 101, 3)
        np.testing.assert_allclose(f["sweep/vessel.hydrostatics.gm_l"][:], [10, 20, 30, 10, 20, 30])
    assert main(["sweep", str(p), "--param", "vessel.bogus=1,2"]) == 2
    assert "vessel.bogus" in capsys.readouterr().err


def test_batch_is_sharded_over_several_devices_with_the_same_numbers(tmp_path):
    """Two host devices (XLA's forced device count, in a fresh process): the batch is split over
    both, and each run equals the same batch on one device."""
    import os
    import subprocess
    import sys
    code = r"""
import jax
jax.config.update("jax_enable_x64", True)
import numpy as np, jaxslosh as js
from helpers import vessel_scene
assert len(jax.devices()) == 2
scene = vessel_scene(duration=1.0, omega=(0.03, 0.01, 0.0))
res, st = js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": np.array([1.0, 1.5, 2.0, 2.5])})
q = res.vessel.quaternion
print(len(q.sharding.device_set), st == ["ok"] * 4)
np.save(%r, np.asarray(q))
""" % str(tmp_path / "q.npy")
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2", JAX_PLATFORMS="cpu",
               PYTHONPATH=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split()[-2:] == ["2", "True"]
    one, _ = js.simulate_batch(vessel_scene(duration=1.0, omega=(0.03, 0.01, 0.0)),
                               {"vessel.hydrostatics.gm_t": np.array([1.0, 1.5, 2.0, 2.5])})
    np.testing.assert_allclose(np.load(tmp_path / "q.npy"), np.asarray(one.vessel.quaternion), atol=1e-13)


# ------------------------------------------------------------------------------------------------
# Issue 21 (A): a sweep of a tank's density deadlocked inside XLA. Its batched LAPACK kernels split a
# batch of matrices over XLA's intra-op thread pool and block the pool thread running them until the
# parts are done; several such kernels at once (the liquid's independent inverses, or one per device of
# a sharded batch) left no thread to run the parts. fem/linalg.py maps the runs instead.
SMALL_TANK = (ROOT / "scenes" / "paper_ship_tank.toml").read_text().replace("mesh = [5, 5, 5]", "mesh = [3, 3, 2]")
DENSITIES = [990.0, 1000.0, 1010.0, 1020.0]

_CHILD = r"""
import os, sys
if hasattr(os, "sched_setaffinity") and len(os.sched_getaffinity(0)) > 2:
    os.sched_setaffinity(0, sorted(os.sched_getaffinity(0))[:2])   # a pool of two threads, as on the report's machine
from jaxslosh.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.slow
def test_density_sweep_finishes_and_equals_single_runs(tmp_path):
    """The reported command on a smaller mesh, in a child process that XLA sees as two host devices
    on two CPUs (the two halves of the batch run side by side on a pool of two threads, where the
    batched inverses deadlocked each time): it must finish, exit 0, and each run must equal a single
    run with its density. Slow (a fresh process compiles the batch and four single runs); what made
    the deadlock possible is checked on the compiled program in the default suite (below), and a
    batch with liquid against its single runs in test_batch_with_liquid_equals_single_runs."""
    import os
    import subprocess
    import sys
    import jax
    scene_path = tmp_path / "tank.toml"
    scene_path.write_text(SMALL_TANK)
    out = tmp_path / "density.h5"
    flags = os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=2"
    env = dict(os.environ, XLA_FLAGS=flags.strip(), JAX_PLATFORMS="cpu")
    args = ["sweep", str(scene_path), "--param", "tanks.tank.fluid.density=" + ",".join(map(str, DENSITIES)),
            "--duration", "0.3", "-o", str(out)]
    try:
        done = subprocess.run([sys.executable, "-c", _CHILD] + args, capture_output=True, text=True, env=env,
                              timeout=540)
    except subprocess.TimeoutExpired:
        raise AssertionError("the density sweep did not finish in 9 minutes (deadlock)") from None
    assert done.returncode == 0, done.stderr[-2000:]
    with h5py.File(out) as f:
        assert f.attrs["runs"] == 4 and list(f.attrs["statuses"]) == ["ok"] * 4
        np.testing.assert_array_equal(f["sweep/tanks.tank.fluid.density"][:], DENSITIES)
        q, probe = f["vessel/quaternion"][:], f["probes/B/position"][:]
    scene = js.load_scene(SMALL_TANK)
    traced = jax.jit(lambda rho: js.simulate(scene, params={"tanks.tank.fluid.density": rho}, duration=0.3))
    singles = [traced(rho) for rho in DENSITIES]
    # and once with a concrete density: the liquid then assembled on the host, not from a tracer
    singles[0] = js.simulate(scene, params={"tanks.tank.fluid.density": DENSITIES[0]}, duration=0.3)
    for i, r in enumerate(singles):
        # each run converges to the Newton tolerance, the batch refreshing its preconditioner on
        # its own schedule: equal far below what 10 kg/m^3 of density moves (checked below)
        np.testing.assert_allclose(q[i], np.asarray(r.vessel.quaternion), rtol=0, atol=1e-10)
        np.testing.assert_allclose(probe[i], np.asarray(r.probes["B"].position), rtol=0, atol=1e-10)
    assert np.abs(probe[0] - probe[-1]).max() > 1e-7          # the runs did get their own densities


# slow, for the default suite's budget (it compiles a batch program only to read it): the density
# batches below run in it
@pytest.mark.slow
def test_no_batched_lapack_call_in_a_density_batch():
    """What made the deadlock possible, checked on the compiled program (whatever the machine): no
    LAPACK kernel gets a batch that it would split over the thread pool (jaxlib splits above 2e5
    FLOP, n^3 per matrix; fem.linalg keeps every call at one large matrix or a small batch)."""
    import re
    import jax.numpy as jnp
    from jaxslosh.run.batch import _batch_fn
    from jaxslosh.scene.keys import with_overrides
    scene = with_overrides(js.load_scene(SMALL_TANK), duration=0.02)
    hlo = _batch_fn(scene, ("tanks.tank.fluid.density",)).lower(jnp.asarray(DENSITIES)).compile().as_text()
    calls = [line for line in hlo.splitlines() if re.search(r'custom_call_target="lapack_', line)]
    assert calls                                            # the liquid's inverses are there
    largest = 0
    for line in calls:
        dims = [int(d) for d in re.search(r"f64\[([\d,]+)\]", line).group(1).split(",")]
        n = dims[-1] if dims[-1] > 1 else dims[-2]
        batch = int(np.prod(dims[:-2]))
        largest = max(largest, n)
        assert batch == 1 or batch * n ** 3 <= 100_000, line.strip()[:200]
    assert largest > 40                                     # the liquid block, one run at a time


# ------------------------------------------------------------------------------------------------
# Issue 21 (B): every run's values are checked as a scene file with them would be.
def _paper(tmp_path):
    p = tmp_path / "paper.toml"
    p.write_text((ROOT / "scenes" / "paper_ship_tank.toml").read_text())
    return p


@pytest.mark.parametrize("param, key, words", [
    ("vessel.mass=3.35e5,-4.1e5", "vessel.mass", "must be positive"),
    ("tanks.tank.fill_depth=3.0,4.5", "tanks.tank.fill_depth", "above the tank height"),
    ("tanks[0].fill_depth=4.5", "tanks[0].fill_depth", "above the tank height"),
    ("tanks.tank.fluid.density=-1000", "tanks.tank.fluid.density", "must be positive"),
    ("environment.gravity=-9.81", "environment.gravity", ">= 0"),
])
def test_sweep_refuses_values_the_loader_refuses(tmp_path, capsys, param, key, words):
    scene = _paper(tmp_path)
    out = tmp_path / "sw.h5"
    assert main(["sweep", str(scene), "--param", param, "--duration", "0.05", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --param " + key + ":") and words in lines[0], err
    assert "Traceback" not in err and not out.exists()


def test_sweep_refuses_vectors_repeated_keys_and_bad_outputs(tmp_path, capsys):
    scene = _paper(tmp_path)
    text = scene.read_text()
    out = tmp_path / "sw.h5"
    cases = [
        (["--param", "vessel.inertia=1e6,2e6"], "vessel.inertia"),       # 3 values per run: Python only
        (["--param", "vessel.initial.velocity=0.1,0.2"], "vessel.initial.velocity"),
        (["--param", "vessel.hydrostatics.gm_t=1.2,1.5", "--param", "vessel.hydrostatics.gm_t=1.8"],
         "vessel.hydrostatics.gm_t: given twice"),
        (["--param", "tanks[0].fill_depth=2.9", "--param", "tanks.tank.fill_depth=2.8"], "tanks.tank.fill_depth"),
        (["--param", "vessel.hydrostatics.gm_t=1.2", "-o", str(tmp_path / "no" / "such" / "sw.h5")], "does not exist"),
        (["--param", "vessel.hydrostatics.gm_t=1.2", "-o", str(tmp_path)], "is a folder"),
        (["--param", "vessel.hydrostatics.gm_t=1.2", "-o", str(scene)], "is the scene file"),
    ]
    for args, words in cases:
        code = main(["sweep", str(scene), "--duration", "0.05"] + args + ([] if "-o" in args else ["-o", str(out)]))
        err = capsys.readouterr().err
        assert code == 2 and len(err.strip().splitlines()) == 1 and words in err, (args, err)
        assert "Traceback" not in err
    assert not out.exists() and scene.read_text() == text and sorted(p.name for p in tmp_path.iterdir()) == [
        "paper.toml"]


def test_sweep_refuses_a_folder_it_cannot_write(tmp_path, capsys):
    import os
    scene = _paper(tmp_path)
    if os.geteuid() != 0:
        locked = tmp_path / "locked"
        locked.mkdir()
        locked.chmod(0o555)
        target = locked / "sw.h5"
    else:      # root writes in any folder that permissions close; not in Linux's /proc
        target = "/proc/jaxslosh_sweep.h5"
    assert main(["sweep", str(scene), "--param", "vessel.hydrostatics.gm_t=1.2", "-o", str(target)]) == 2
    err = capsys.readouterr().err
    assert "cannot write" in err and len(err.strip().splitlines()) == 1
    assert not os.path.exists(target)


def test_check_values_applies_values_as_the_loader_would():
    from jaxslosh.scene.keys import check_values, with_overrides
    scene = with_overrides(js.load_scene((ROOT / "scenes" / "paper_ship_tank.toml").read_text()), duration=0.5)
    s = check_values(scene, {"tanks[0].fill_depth": 3.5, "vessel.inertia": np.array([5e6, 1.5e7, 1.7e7]),
                             "vessel.initial.velocity": [0.1, 0.0, 0.0]})
    assert s.tanks[0].fill_depth == 3.5 and s.vessel.inertia[1][1] == 1.5e7
    assert s.vessel.initial.velocity == (0.1, 0.0, 0.0) and s.simulation.duration == 0.5
    assert any("gm_t" in w for w in check_values(scene, {"vessel.hydrostatics.gm_t": -0.2}).warnings)
    for values, message in [
        ({"vessel.mass": -4.1e5}, "vessel.mass: must be positive"),
        ({"tanks.tank.fill_depth": 4.5}, "tanks.tank.fill_depth: 4.5 m is above the tank height 4.0 m"),
        ({"vessel.inertia": [1e6, -2e6, 3e6]}, "vessel.inertia: the diagonal values must be positive"),
        ({"tanks.tank.fill_depth": 2.0}, "tanks.tank.fill_depth: with tanks.tank.fill_depth = 2"),  # probe B in the air
    ]:
        with pytest.raises(js.SceneError) as e:
            check_values(scene, values)
        assert str(e.value).startswith(message), str(e.value)
        assert e.value.key == next(iter(values))


def test_python_api_checks_concrete_values_and_takes_inertia_rows():
    import jax
    scene = vessel_scene(duration=0.5, omega=(0.03, 0.01, 0.0))
    with pytest.raises(js.SceneError, match=r"^vessel\.mass: must be positive.*\(run 1: vessel\.mass = -1\.0\)"):
        js.simulate_batch(scene, {"vessel.mass": np.array([4e5, -1.0])})
    with pytest.raises(js.SceneError, match=r"^vessel\.mass: must be positive"):
        js.simulate(scene, params={"vessel.mass": -1.0})
    # a traced value has no value to check: a jitted run takes it as before
    assert np.isfinite(float(jax.jit(lambda m: js.simulate(scene, params={"vessel.mass": m}).time[-1])(4e5)))
    # vessel.inertia: one row of 3 diagonal values per run, as a single run takes them
    rows = np.array([[5e6, 1.5e7, 1.7e7], [1e7, 1.5e7, 1.7e7]])
    batch, statuses = js.simulate_batch(scene, {"vessel.inertia": rows})
    assert statuses == ["ok", "ok"]
    for i, row in enumerate(rows):
        single = js.simulate(scene, params={"vessel.inertia": row})
        np.testing.assert_allclose(np.asarray(batch.vessel.quaternion[i]), np.asarray(single.vessel.quaternion),
                                   rtol=0, atol=1e-11)
    roll = np.abs(np.asarray(batch.vessel.roll_pitch_yaw)[:, :, 0]).max(axis=1)
    assert roll[1] > roll[0] * 1.01          # started at the same rate, twice the roll inertia decelerates less
