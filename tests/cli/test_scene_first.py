"""A bad scene is refused before JAX is imported (jaxslosh/entry.py): `jaxslosh check` or `run` of
one answers in about a second with one line and exit status 2, not after JAX's seconds of import.
`python -X importtime` lists every module the process imported: JAX must not be among them."""
import os
import re
import subprocess
import sys

import pytest

from jaxslosh.entry import scene_argument

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def bad_scene(folder):
    with open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")) as f:
        text = f.read()
    assert re.search(r"^mass = ", text, re.M)
    path = os.path.join(folder, "bad.toml")
    with open(path, "w") as f:
        f.write(re.sub(r"^mass = .*$", "mass = -1.0", text, count=1, flags=re.M))
    return path


def imported(stderr):
    """Top-level modules a `python -X importtime` process imported."""
    return set(re.findall(r"^import time:\s+\d+ \|\s+\d+ \|\s+([A-Za-z_][\w]*)\s*$", stderr, re.M))


@pytest.mark.parametrize("command", [["check"], ["run", "-o", "out.h5"], ["check", "missing"]])
def test_bad_scene_is_refused_before_jax(tmp_path, command):
    path = bad_scene(tmp_path)
    expected = "error: vessel.mass: must be positive, got -1.0"
    if command[-1] == "missing":
        command, path = command[:1], str(tmp_path / "missing.toml")
        expected = f"error: {path}: no such file"
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    p = subprocess.run([sys.executable, "-X", "importtime", "-m", "jaxslosh", command[0], path, *command[1:]],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    errors = [ln for ln in p.stderr.splitlines() if not ln.startswith("import time:")]
    assert p.returncode == 2, p.stderr[-2000:]
    assert errors == [expected]
    mods = imported(p.stderr)
    assert "numpy" in mods and "jaxslosh" in mods        # the parse of importtime's lines works
    assert not mods & {"jax", "jaxlib", "equinox"}
    assert not os.path.exists(tmp_path / "out.h5")


def test_a_good_scene_is_read_once(tmp_path):
    """The scene read before JAX is the command's: its warnings are printed once."""
    with open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")) as f:
        text = f.read()
    path = tmp_path / "warn.toml"
    path.write_text(re.sub(r"^gm_t = .*$", "gm_t = -0.5", text, count=1, flags=re.M))
    assert "gm_t = -0.5" in path.read_text()
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    p = subprocess.run([sys.executable, "-m", "jaxslosh", "check", str(path)], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    warned = [ln for ln in p.stderr.splitlines() if "gm_t" in ln]
    assert len(warned) == 1 and warned[0].startswith("warning: vessel.hydrostatics.gm_t")


def test_scene_argument(tmp_path):
    s = tmp_path / "s.toml"
    s.write_text("")
    s = str(s)
    assert scene_argument(["check", s]) == s
    assert scene_argument(["run", "--duration", "5", s, "-o", "x.h5"]) == s
    assert scene_argument(["run", s, "--dt=0.1", "--no-progress"]) == s
    assert scene_argument(["identify", s, "--data", s, "--fit", "vessel.mass"]) == s
    # not plain: left to the command's parser
    assert scene_argument(["run", "--no-progress", s]) is None       # a flag, or an option's value?
    assert scene_argument(["run", s, "--help"]) is None
    assert scene_argument(["plot", s]) is None                          # a result file, not a scene
    assert scene_argument(["check", str(tmp_path / "absent.toml")]) == str(tmp_path / "absent.toml")
    assert scene_argument(["run", s, "extra"]) is None                  # the parser's to refuse
    assert scene_argument([]) is None
