"""The `jaxslosh` command: exit statuses, one-line errors, result files (SPEC sections 2-3)."""
import subprocess
import sys

import h5py
import numpy as np
import pytest

from jaxslosh.cli import main
from jaxslosh.io.result import load_result

from helpers import VESSEL

GOOD = VESSEL.format(duration=1.0, dt=0.01, scheme="hht", alpha=0.01, omega=[0.02, 0.01, 0.0], position=[0, 0, 0])

# (what is wrong, replace this, by this, a key that the message must name)
BAD = [
    ("non-positive mass", "mass = 4.0e5", "mass = -1.0", "vessel.mass"),
    ("zero dt", "dt = 0.01", "dt = 0.0", "simulation.dt"),
    ("negative duration", "duration = 1.0", "duration = -1.0", "simulation.duration"),
    ("unknown key", "scheme = \"hht\"", "scheme = \"hht\"\nsteps = 3", "simulation.steps"),
    ("wrong type", "mass = 4.0e5", "mass = \"heavy\"", "vessel.mass"),
    ("missing key", "mass = 4.0e5\n", "", "vessel.mass"),
    ("non-symmetric inertia", "inertia = [5.0e6, 1.5e7, 1.7e7]",
     "inertia = [[5.0e6, 1.0e5, 0.0], [0.0, 1.5e7, 0.0], [0.0, 0.0, 1.7e7]]", "vessel.inertia"),
    ("non-positive-definite inertia", "inertia = [5.0e6, 1.5e7, 1.7e7]", "inertia = [5.0e6, -1.5e7, 1.7e7]",
     "vessel.inertia"),
    ("unknown scheme", "scheme = \"hht\"", "scheme = \"rk4\"", "simulation.scheme"),
    ("amplifying newmark", "scheme = \"hht\"", "scheme = \"newmark\"", "simulation.alpha"),
    ("negative water density", "water_density = 1025.0", "water_density = -5.0", "environment.water_density"),
]

TANK = """
[[tanks]]
name = "tank"
origin = [-2.0, -1.5, -1.0]
size = [4.0, 3.0, 3.0]
fill_depth = 2.0
mesh = [2, 2, 2]
[[probes]]
name = "A"
tank = "tank"
point = [4.0, 1.5, 0.0]
"""
BAD_TANK = [
    ("fill above height", "fill_depth = 2.0", "fill_depth = 4.5", "tanks[0].fill_depth"),
    ("non-positive fill", "fill_depth = 2.0", "fill_depth = 0.0", "tanks[0].fill_depth"),
    ("mesh below 1", "mesh = [2, 2, 2]", "mesh = [2, 0, 2]", "tanks[0].mesh"),
    ("probe outside", "point = [4.0, 1.5, 0.0]", "point = [4.5, 1.5, 0.0]", "probes[0].point"),
    ("probe of no tank", "tank = \"tank\"\npoint", "tank = \"other\"\npoint", "probes[0].tank"),
    ("duplicate tank", "[[probes]]", "[[tanks]]\nname = \"tank\"\norigin = [0.0, 0.0, 0.0]\nsize = [1.0, 1.0, 1.0]\n"
     "fill_depth = 0.5\nmesh = [1, 1, 1]\n[[probes]]", "tanks[1].name"),
    ("fluid density", "mesh = [2, 2, 2]", "mesh = [2, 2, 2]\n[tanks.fluid]\ndensity = -1.0", "tanks[0].fluid.density"),
]


def _write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


@pytest.mark.parametrize("what,old,new,key", BAD + BAD_TANK, ids=[b[0] for b in BAD + BAD_TANK])
def test_bad_input_exits_2_with_one_line_naming_the_key(tmp_path, capsys, what, old, new, key):
    base = GOOD + TANK if (what, old, new, key) in BAD_TANK else GOOD
    assert old in base
    scene = _write(tmp_path, base.replace(old, new, 1))
    out = tmp_path / "out.h5"
    code = main(["run", scene, "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in err if not line.startswith("warning:")]
    assert code == 2
    assert len(errors) == 1 and key in errors[0], err
    assert "Traceback" not in "\n".join(err)
    assert not out.exists()
    assert main(["check", scene]) == 2


def test_bad_arguments_exit_2(tmp_path, capsys):
    scene = _write(tmp_path, GOOD)
    assert main(["run", scene, "--dt", "-1"]) == 2
    assert main(["run", str(tmp_path / "missing.toml")]) == 2
    assert main(["run", scene, "-o", str(tmp_path / "no" / "such" / "dir.h5")]) == 2
    assert main(["frobnicate"]) == 2
    assert main(["plot", str(tmp_path / "missing.h5")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err


def test_run_writes_result_file_and_plot(tmp_path, capsys):
    scene = _write(tmp_path, GOOD)
    out = tmp_path / "r.h5"
    assert main(["run", scene, "-o", str(out), "--no-progress"]) == 0
    assert "done" in capsys.readouterr().out
    with h5py.File(out) as f:
        assert f.attrs["format"] == "jaxslosh.result" and f.attrs["status"] == "ok"
        assert int(f.attrs["steps_done"]) == 100
        assert f["time"].shape == (101,) and f["vessel/quaternion"].shape == (101, 4)
        assert "[vessel]" in f.attrs["scene"]
    r = load_result(str(out))
    assert np.allclose(np.linalg.norm(r.vessel.quaternion, axis=1), 1.0, atol=1e-13)
    png = tmp_path / "r.png"
    assert main(["plot", str(out), "-o", str(png)]) == 0 and png.stat().st_size > 1000


def test_numerical_failure_exits_3_and_keeps_the_steps_done(tmp_path, capsys):
    """An unstable vessel (GM < 0) capsizes; with one Newton iteration allowed per step the step
    where the motion turns nonlinear cannot converge."""
    text = GOOD.replace("gm_t = 1.5", "gm_t = -1.5").replace("alpha = 0.01", "alpha = 0.01\nmax_iterations = 1\n"
                                                                           "tolerance = 1e-8")
    text = text.replace("duration = 1.0", "duration = 30.0")
    scene = _write(tmp_path, text)
    out = tmp_path / "fail.h5"
    code = main(["run", scene, "-o", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 3, err
    assert "step" in err and "t = " in err and "did not converge" in err
    with h5py.File(out) as f:
        status = f.attrs["status"]
        k = int(f.attrs["steps_done"])
        assert "did not converge" in status
        assert k > 10 and f["time"].shape[0] == k + 1
        assert np.all(np.isfinite(f["vessel/quaternion"][:]))


def test_python_m_jaxslosh_runs_as_a_program(tmp_path):
    scene = _write(tmp_path, GOOD.replace("[vessel]", "[vessel]\nbogus = 1"))
    p = subprocess.run([sys.executable, "-m", "jaxslosh", "check", scene], capture_output=True, text=True)
    assert p.returncode == 2 and "vessel.bogus" in p.stderr and "Traceback" not in p.stderr
    p = subprocess.run([sys.executable, "-m", "jaxslosh", "check", _write(tmp_path, GOOD, "ok.toml")],
                       capture_output=True, text=True)
    assert p.returncode == 0 and "unknowns" in p.stdout


def test_file_of_a_killed_run_is_readable(tmp_path):
    """Kill a long run midway: the file opens and holds the steps written so far."""
    import time
    text = GOOD.replace("duration = 1.0", "duration = 2000.0").replace("alpha = 0.01", "alpha = 0.01\nchunk = 200")
    scene = _write(tmp_path, text)
    out = tmp_path / "killed.h5"
    p = subprocess.Popen([sys.executable, "-m", "jaxslosh", "run", scene, "-o", str(out), "--no-progress"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    n = 0
    while time.time() < deadline and n < 1000:
        time.sleep(0.5)
        try:
            with h5py.File(out, "r", locking=False) as f:
                n = f["time"].shape[0]
        except (OSError, KeyError):
            pass
    p.kill()
    p.wait()
    with h5py.File(out, "r", locking=False) as f:
        n = f["time"].shape[0]
        assert 0 < n < 200001
        assert int(f.attrs["steps_done"]) >= n - 1
        assert np.all(np.isfinite(f["vessel/position"][:n]))


def test_failing_steps_retried_as_substeps_get_further():
    import jaxslosh as js
    text = GOOD.replace("gm_t = 1.5", "gm_t = -1.5").replace(
        "alpha = 0.01", "alpha = 0.01\nmax_iterations = 1\ntolerance = 1e-8").replace("duration = 1.0", "duration = 30.0")
    plain = js.simulate(js.load_scene(text), throw=False)
    retried = js.simulate(js.load_scene(text.replace("tolerance = 1e-8", "tolerance = 1e-8\nsubsteps = 4")), throw=False)
    assert "did not converge" in plain.status and plain.steps_done > 10
    assert retried.steps_done > plain.steps_done
    # up to the first failure both runs are the same run
    n = plain.steps_done + 1
    np.testing.assert_allclose(np.asarray(retried.vessel.quaternion[:n]), np.asarray(plain.vessel.quaternion[:n]),
                               atol=1e-14)


def test_check_describes_a_mesh_file_by_its_counts_and_notes_a_nearly_full_horizontal_cylinder(tmp_path, capsys):
    """Issue 31, item 15: a mesh tank whose file is not a grid is described by its elements and nodes
    (not "mesh 3 x 1 x 1"); a horizontal cylinder filled to 2.999 of 3 m gets a note that its
    sloshing is not resolved (surface elements 13 times taller than wide), one filled to 2.5 m none."""
    meshio = pytest.importorskip("meshio")
    from jaxslosh.fem.mesh import box_mesh
    nodes, elements = box_mesh((2.0, 2.0, 1.0), (2, 2, 1))
    elements = elements[:3]                                   # an L: no grid
    used = np.unique(elements)
    renum = np.full(len(nodes), -1)
    renum[used] = np.arange(used.size)
    path = tmp_path / "ell.msh"
    meshio.write(str(path), meshio.Mesh(nodes[used], [("hexahedron", renum[elements])]), file_format="gmsh22")
    tank = (f'\n[[tanks]]\nname = "ell"\norigin = [-1.0, -1.0, -1.0]\nsize = [2.0, 2.0, 1.0]\nshape = "mesh"\n'
            f'file = "{path}"\n')
    assert main(["check", _write(tmp_path, GOOD + tank)]) == 0
    out = capsys.readouterr().out
    assert f"mesh file of 3 hexahedra on {used.size} nodes" in out and "3 x 1 x 1" not in out and "3x1x1" not in out
    cyl = ('\n[[tanks]]\nname = "cyl"\norigin = [-2.5, -1.5, -1.0]\nsize = [5.0, 3.0, 3.0]\nshape = "cylinder"\n'
           'axis = "x"\nfill_depth = {fill}\nmesh = [5, 6, 6]\n')
    assert main(["check", _write(tmp_path, GOOD + cyl.format(fill=2.999))]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    notes = [i for i, line in enumerate(lines) if line.strip().startswith("note:")]
    assert len(notes) == 1 and lines[notes[0] - 1].startswith("tank 'cyl'")     # under its tank
    assert "nearly full (2.999 of 3 m)" in lines[notes[0]] and "0.11 m wide" in lines[notes[0]]
    assert "spurious" in lines[notes[0]]
    assert main(["check", _write(tmp_path, GOOD + cyl.format(fill=2.5))]) == 0
    assert "note:" not in capsys.readouterr().out
