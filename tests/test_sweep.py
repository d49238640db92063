"""Batched runs: one vmapped compile, the same numbers as single runs; the sweep command."""
from pathlib import Path

import h5py
import numpy as np

import jaxslosh as js
from jaxslosh.cli import main

from helpers import vessel_scene

ROOT = Path(__file__).resolve().parents[1]


def test_batch_equals_single_runs():
    scene = vessel_scene(duration=3.0, omega=(0.03, 0.01, 0.0))
    gm = np.array([1.0, 1.5, 2.5])
    batch, statuses = js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm})
    assert statuses == ["ok"] * 3 and batch.vessel.quaternion.shape == (3, 301, 4)
    for i, g in enumerate(gm):
        single = js.simulate(scene, params={"vessel.hydrostatics.gm_t": g})
        # the batch forms its Newton preconditioner anew every 4 steps, a single run when its
        # convergence slows: both converge to the Newton tolerance (1e-10 m/s^2), not bitwise alike
        np.testing.assert_allclose(np.asarray(batch.vessel.quaternion[i]), np.asarray(single.vessel.quaternion),
                                   atol=1e-11)
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
               PYTHONPATH=os.path.dirname(os.path.abspath(__file__)))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split()[-2:] == ["2", "True"]
    one, _ = js.simulate_batch(vessel_scene(duration=1.0, omega=(0.03, 0.01, 0.0)),
                               {"vessel.hydrostatics.gm_t": np.array([1.0, 1.5, 2.0, 2.5])})
    np.testing.assert_allclose(np.load(tmp_path / "q.npy"), np.asarray(one.vessel.quaternion), atol=1e-13)
