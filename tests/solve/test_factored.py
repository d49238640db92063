"""Shaped tanks in pure JAX (solve/factored.py): the liquid block's dense and banded factors solve it
to round-off; a prismatic tank with chamfers moves as with the host's sparse LU; gradients through
it agree with finite differences; a batch through it is its single runs, a campaign worker's batch
its cases' runs; and a second `jaxslosh run` of a shaped scene in a new process traces and compiles
nothing."""
import os
import re
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

import jaxslosh as js
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.geometry import Prismatic
from jaxslosh.solve.factored import Banded, Dense, factored_inverse

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
C_A = 1.0 / (0.25 * 1.01 ** 2 * 0.01 ** 2)        # the paper scene's step: HHT alpha 0.01, dt 0.01
CHAMFERS = 'shape = "prismatic"\nchamfers = [[1.5, 1.0], [1.0, 0.8]]'


def _blocks():
    geo = Prismatic(size=(3.0, 6.0, 4.0), chamfers=((1.5, 1.0), (1.0, 0.8)))
    m = build_liquid(geo.size, 3.5, (2, 6, 4), 1000.0, 1500.0, 9.81, geometry=geo, sparse=True)
    free = np.flatnonzero(np.asarray(m.free))
    M = sp.kron(m.mass, sp.eye(3), format="csr")
    from jaxslosh.fem.slip import rotate_matrix
    M = rotate_matrix(np, M, np.asarray(m.frames)).tocsr()[free][:, free]
    K = m.stiffness.tocsr()[free][:, free]
    return M, 0.5 * (K + K.T)


@pytest.mark.parametrize("form", ["dense", "banded", "auto"])
def test_factors_solve_the_step_and_mass_blocks_of_two_tanks_to_round_off(form):
    """Two tanks stacked (two components of the block, one a scaled copy): each component's factor,
    in its own order (RCM for the banded one, padded to whole blocks), solves with the block to a
    backward error of round-off, and as SciPy's sparse solver does within the block's condition
    (measured: backward 1e-14, forward 2e-11 at a condition of 1.5e5)."""
    M, K = _blocks()
    rng = np.random.default_rng(3)
    for A in (C_A * M + K, M):
        A2 = sp.block_diag([A, 2.0 * A]).tocsr()
        F = factored_inverse(A2, form)
        assert len(F.parts) == 2 and F.n == A2.shape[0]
        if form != "auto":
            assert all(isinstance(p, Dense if form == "dense" else Banded) for p in F.parts)
        if form == "banded":
            k, b, _ = F.parts[0].Sinv.shape
            assert k >= 3 and k * b >= F.parts[0].n > (k - 1) * b      # block tridiagonal, the last padded
        cond = np.linalg.cond(A.toarray())
        norm = np.max(abs(A2).sum(axis=1))
        for r in (rng.standard_normal(A2.shape[0]), rng.standard_normal((A2.shape[0], 3))):
            x = np.asarray(jax.jit(lambda F, r: F @ r)(F, jnp.asarray(r)))
            assert np.max(np.abs(A2 @ x - r)) <= 1e-13 * (norm * np.max(np.abs(x)) + np.max(np.abs(r)))
            ref = spsolve(A2.tocsc(), r)
            assert np.linalg.norm(x - ref) <= 100 * np.finfo(float).eps * cond * np.linalg.norm(ref)


def _scene_text(solver, duration="0.15", extra=""):
    t = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    t = t.replace("size = [5.0, 5.0, 4.0]", "size = [3.0, 6.0, 4.0]").replace("mesh = [5, 5, 5]", "mesh = [2, 6, 4]")
    t = t.replace("fill_depth = 3.0", "fill_depth = 3.5").replace("duration = 20.0", f"duration = {duration}")
    t = t.replace("origin = [-2.5, -2.5, -1.0]", "origin = [-1.5, -3.0, -1.0]")
    t = t.replace("point = [4.5, 2.5, 0.0]", "point = [1.5, 3.0, 0.0]").replace("point = [4.5, 2.5, 3.0]",
                                                                                   "point = [1.5, 5.0, 3.5]")
    t = t.replace('walls = "rigid"\n', 'walls = "rigid"\n' + CHAMFERS + "\n")
    t = t.replace("[tanks.fluid]", '[tanks.fluid]\nelement = "stabilized"')      # the nodal blocks' factors
    return t.replace("[simulation]", f'[simulation]\nlinear_solver = "{solver}"\n{extra}', 1)


def test_a_prismatic_tank_moves_as_with_the_host_lu():
    """The same scene through the JAX factors and SciPy's SuperLU on the host (the path before): the
    Newton iterations see the same preconditioner to round-off, so the motion is the same to
    round-off. (Against the dense inverses: tests/fem/test_shapes.py, a cylinder.)"""
    runs = {s: js.simulate(js.load_scene(_scene_text(s))) for s in ("sparse", "sparse-host")}
    jx, host = runs["sparse"], runs["sparse-host"]
    assert jx.status == host.status == "ok"
    assert np.max(np.abs(np.asarray(jx.vessel.roll_pitch_yaw)[:, 0])) > 1e-3      # it moves
    surface = np.asarray(jx.probes["B"].displacement)
    assert np.max(np.abs(surface)) > 1e-5
    np.testing.assert_allclose(jx.vessel.roll_pitch_yaw, host.vessel.roll_pitch_yaw, rtol=0, atol=1e-12)
    np.testing.assert_allclose(jx.probes["B"].position, host.probes["B"].position, rtol=0, atol=1e-11)
    np.testing.assert_array_equal(jx.solver.iterations, host.solver.iterations)


# slow, for the default suite's budget: it keeps gradients through runs with finite differences of a
# box's tank (tests/run/test_gradients_liquid.py) and of an rt tank's fill depth (tests/run/test_gradients_rt.py)
@pytest.mark.slow
def test_a_gradient_through_a_prismatic_tank_agrees_with_finite_differences():
    scene = js.load_scene(_scene_text("sparse", duration="0.1"))
    key = "vessel.hydrostatics.gm_t"

    def loss(gm):
        r = js.simulate(scene, params={key: gm})
        return jnp.sum(r.vessel.roll_pitch_yaw[:, 0] ** 2) + jnp.sum(r.probes["B"].displacement[:, 2] ** 2)

    g = float(jax.grad(loss)(1.67))
    e = 1e-3
    fd = (float(loss(1.67 + e)) - float(loss(1.67 - e))) / (2 * e)
    assert abs(g) > 0
    assert abs(g - fd) <= 1e-6 * abs(fd)


def test_a_batch_through_a_prismatic_tank_is_its_single_runs():
    scene = js.load_scene(_scene_text("sparse", duration="0.1"))
    key = "vessel.hydrostatics.gm_t"
    gm = np.array([1.2, 2.4])
    batch, statuses = js.simulate_batch(scene, {key: jnp.asarray(gm)})
    assert statuses == ["ok", "ok"]
    for i, g in enumerate(gm):
        one = js.simulate(scene, params={key: float(g)})
        np.testing.assert_allclose(batch.vessel.roll_pitch_yaw[i], one.vessel.roll_pitch_yaw, rtol=0, atol=1e-11)
        np.testing.assert_allclose(batch.probes["B"].position[i], one.probes["B"].position, rtol=0, atol=1e-10)
    assert not np.allclose(batch.vessel.roll_pitch_yaw[0], batch.vessel.roll_pitch_yaw[1], rtol=0, atol=1e-6)


def _compiled_programs(stderr: str) -> set:
    """The run's programs (named `<program>_<key>` by programs.lower_program) XLA compiled, from
    JAX's compile log."""
    return set(re.findall(r"\b(advance|start)_[0-9a-f]{16}", stderr))


def test_a_second_run_of_a_shaped_scene_compiles_nothing(tmp_path):
    """The shaped scene's programs are exported and their executables kept by the first process; the
    second reads them: no program traced (no new file), none compiled (JAX's compile log), and the
    summary line's compile phase is about reading the files."""
    cache = tmp_path / "cache"
    env = dict(os.environ, JAXSLOSH_CACHE_DIR=str(cache), JAX_LOG_COMPILES="1",
               PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]))
    scene = tmp_path / "shaped.toml"
    scene.write_text(_scene_text("sparse", duration="0.05"))
    runs = []
    for k in range(2):
        out = str(tmp_path / f"r{k}.h5")
        p = subprocess.run([sys.executable, "-m", "jaxslosh", "run", str(scene), "-o", out, "--no-progress"],
                           capture_output=True, text=True, env=env, timeout=300)
        assert p.returncode == 0, p.stderr
        phase = float(re.search(r"compile ([0-9.]+) s", p.stdout + p.stderr).group(1))
        runs.append((p.stderr, phase, sorted(os.listdir(cache / "programs"))))
    (err1, phase1, files1), (err2, phase2, files2) = runs
    assert {f.split("-")[0] for f in files1} >= {"start", "advance", "model", "initial"}
    assert files2 == files1
    assert _compiled_programs(err1) == {"advance", "start"} and _compiled_programs(err2) == set()
    print(f"compile phase: first {phase1:.2f} s, second {phase2:.2f} s")
    a, b = js.load_result(str(tmp_path / "r0.h5")), js.load_result(str(tmp_path / "r1.h5"))
    np.testing.assert_array_equal(a.vessel.roll_pitch_yaw, b.vessel.roll_pitch_yaw)


TANK = """
[[tanks]]
name = "cargo"
shape = "prismatic"
chamfers = [[1.5, 1.0], [1.0, 0.8]]
origin = [-1.5, -3.0, -1.0]
size = [3.0, 6.0, 4.0]
fill_depth = 3.5
mesh = [2, 6, 4]
[tanks.fluid]
density = 1000.0
sound_speed = 1500.0
"""


# slow: the default suite has a batch through this tank (test_a_batch_through_a_prismatic_tank_is_its_single_runs)
# and the campaign worker's batches of a box (tests/campaign)
@pytest.mark.slow
def test_a_campaign_batch_through_a_prismatic_tank_gives_the_statistics_of_its_single_run(tmp_path):
    """A campaign worker's batch (two sea states, vmapped) through a shaped tank: each case's roll
    statistics are those of `js.simulate` of the case's own scene (measured: 3e-10 relative; the
    batch refreshes its Newton preconditioner on a schedule, a single run when convergence slows)."""
    from jaxslosh.campaign.cases import case_scene
    from jaxslosh.campaign.worker import run_batch
    from test_campaign import scene_text
    text = scene_text(duration=16.0, components=10).replace("[simulation]", '[simulation]\nlinear_solver = "sparse"')
    text = text.replace("mass = 4.1e5", "mass = 3.4e5") + TANK
    path = tmp_path / "campaign.toml"
    path.write_text(text)
    cases = [{"hs": 0.6, "tp": 7.0, "heading": 1.2, "seed": 0},
             {"hs": 0.9, "tp": 8.0, "heading": 1.5707963267948966, "seed": 1}]
    out = run_batch(text, str(path), None, cases, 2)
    assert [o["status"] for o in out] == ["ok", "ok"]
    r = js.simulate(case_scene(js.load_scene(text), cases[1]))
    t = np.asarray(r.time)
    roll = np.asarray(r.vessel.roll_pitch_yaw)[:, 0][t >= 10.0 - 1e-9]
    assert roll.std() > 1e-3
    np.testing.assert_allclose(roll.std(), out[1]["stats"]["roll"]["std"], rtol=1e-7)
    assert abs(out[0]["stats"]["roll"]["std"] - out[1]["stats"]["roll"]["std"]) > 1e-3 * roll.std()
