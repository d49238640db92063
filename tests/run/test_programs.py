"""Exported programs kept across processes (jaxslosh/cache/programs.py): a program read back from its file
computes what the traced one does, and a change of anything the trace depends on (a static value,
a shape) names another file."""
import json
import os
import pickle
import subprocess
import sys

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxslosh.cache import executables, programs


class Model(eqx.Module):
    k: jax.Array
    power: int = eqx.field(static=True)


def energy(m: Model, x, label):
    assert label in ("a", "b")
    return {"e": 0.5 * m.k * jnp.sum(x ** m.power), "grad": jax.grad(lambda y: jnp.sum(y ** m.power))(x)}


@pytest.fixture
def folder(tmp_path):
    programs.use(str(tmp_path))
    yield tmp_path
    programs.use(None)


def test_a_program_read_back_computes_what_the_traced_one_does(folder):
    m, x = Model(jnp.asarray(3.0), 3), np.linspace(0.0, 1.0, 7)
    f1, loaded1 = programs.compile_program("energy", energy, (m, x, "a"))
    files = os.listdir(folder)
    f2, loaded2 = programs.compile_program("energy", energy, (m, x, "a"))
    assert (loaded1, loaded2) == (False, True) and len(files) == 1 and os.listdir(folder) == files
    ref = jax.jit(energy, static_argnums=2)(m, x, "a")
    for f in (f1, f2):
        out = f(Model(jnp.asarray(2.0), 3), x + 1.0, "a")        # new values, the same structure
        want = jax.jit(energy, static_argnums=2)(Model(jnp.asarray(2.0), 3), x + 1.0, "a")
        np.testing.assert_array_equal(out["e"], want["e"])
        np.testing.assert_array_equal(out["grad"], want["grad"])
    np.testing.assert_allclose(ref["e"], 0.5 * 3.0 * np.sum(x ** 3), rtol=1e-15)


def test_what_the_trace_depends_on_names_another_file(folder):
    m, x = Model(jnp.asarray(3.0), 3), np.linspace(0.0, 1.0, 7)
    programs.compile_program("energy", energy, (m, x, "a"))
    for args in [(Model(jnp.asarray(3.0), 2), x, "a"),       # a static field
                 (m, x, "b"),                               # a static leaf
                 (m, np.linspace(0.0, 1.0, 8), "a"),        # a shape
                 (m, x.astype(np.float32), "a")]:           # a type
        _, loaded = programs.compile_program("energy", energy, args)
        assert not loaded
    assert len(os.listdir(folder)) == 5


def test_a_damaged_file_is_traced_again(folder):
    m, x = Model(jnp.asarray(3.0), 3), np.linspace(0.0, 1.0, 7)
    programs.compile_program("energy", energy, (m, x, "a"))
    (path,) = [folder / f for f in os.listdir(folder)]
    path.write_bytes(path.read_bytes()[:100])
    f, loaded = programs.compile_program("energy", energy, (m, x, "a"))
    assert not loaded
    np.testing.assert_allclose(f(m, x, "a")["e"], 0.5 * 3.0 * np.sum(x ** 3), rtol=1e-15)


def test_without_a_folder_nothing_is_written(tmp_path):
    programs.use(None)
    m, x = Model(jnp.asarray(3.0), 3), np.linspace(0.0, 1.0, 7)
    f, loaded = programs.compile_program("energy", energy, (m, x, "a"))
    assert not loaded and os.listdir(tmp_path) == []
    np.testing.assert_allclose(f(m, x, "a")["e"], 0.5 * 3.0 * np.sum(x ** 3), rtol=1e-15)


def test_a_cached_value_is_computed_once_per_key_and_read_back(folder):
    calls = []

    def compute(k):
        calls.append(k)
        return {"k": k, "a": np.arange(3.0) * k, "j": jnp.ones(2) * k}

    first = programs.cached("model", ("scene", 2), lambda: compute(2))
    again = programs.cached("model", ("scene", 2), lambda: compute(2))
    other = programs.cached("model", ("scene", 3), lambda: compute(3))
    assert calls == [2, 3] and len(os.listdir(folder)) == 2
    np.testing.assert_array_equal(again["a"], first["a"])
    np.testing.assert_array_equal(np.asarray(again["j"]), [2.0, 2.0])
    assert other["k"] == 3
    # a damaged file is computed again; a value that does not pickle is returned, not kept
    for path in folder.iterdir():
        path.write_bytes(path.read_bytes()[:10])
    assert programs.cached("model", ("scene", 2), lambda: compute(2))["k"] == 2 and calls == [2, 3, 2]
    f = programs.cached("model", ("scene", 4), lambda: (lambda: 4))
    assert f() == 4 and len(os.listdir(folder)) == 2


def test_an_executable_compiled_on_another_host_is_not_loaded(folder, monkeypatch):
    """The file keeps the executable XLA compiled, for this host alone (its instruction set): on
    another, the exported program is compiled again, and its executable replaces the first."""
    # a program no other test compiles (power 5, 11 points): XLA's in-process cache holds none of it
    m, x = Model(jnp.asarray(3.0), 5), np.linspace(0.0, 1.0, 11)
    programs.compile_program("energy", energy, (m, x, "a"))
    (path,) = [folder / f for f in os.listdir(folder)]
    here = pickle.loads(path.read_bytes())["host"]
    monkeypatch.setattr(executables, "host", lambda: "another machine")
    p = programs.lower_program("energy", energy, (m, x, "a"))
    assert p.loaded and p._lowered is not None          # from the exported program, lowered again
    f = p.compile()
    np.testing.assert_allclose(f(m, x, "a")["e"], 0.5 * 3.0 * np.sum(x ** 5), rtol=1e-15)
    assert pickle.loads(path.read_bytes())["host"] == "another machine" != here


def test_the_cache_folder_is_trimmed_to_its_limit_least_recently_used_first(folder):
    """Past its limit, the folder loses the files least recently written or read (a read marks a
    file used) until three quarters of the limit remain; under the limit nothing is removed."""
    sub = folder / "xla"
    sub.mkdir()
    paths = [folder / "model-a.pickle", sub / "entry-b", folder / "model-c.pickle", sub / "entry-d"]
    for t, p in enumerate(paths):
        p.write_bytes(b"x" * 1000)
        os.utime(p, (1e9 + t, 1e9 + t))
    assert programs.trim(str(folder), 4000) == 0 and all(p.exists() for p in paths)
    calls = []
    programs.cached("model", "a", lambda: calls.append(1))       # names its own file; written now
    (kept,) = [f for f in folder.iterdir() if f.name.startswith("model-") and f not in paths]
    os.utime(kept, (1e9 - 1, 1e9 - 1))          # the oldest ...
    programs.cached("model", "a", lambda: calls.append(2))       # ... until read
    assert calls == [1]
    size = sum(p.stat().st_size for p in paths) + kept.stat().st_size
    removed = programs.trim(str(folder), 2000)
    assert [p.exists() for p in paths] == [False, False, False, True] and kept.exists()
    assert removed == 3000 and size - removed <= 0.75 * 2000


CACHED_SOLVE = r"""
import json, os, sys
import jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
jax.config.update("jax_compilation_cache_dir", os.path.join(sys.argv[1], "xla"))
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
jax.config.update("jax_persistent_cache_min_entry_size_bytes", -1)
from jaxslosh.cache import programs
if sys.argv[2:] == ["new"]:           # another version of jaxslosh: every file's name changes
    programs._code_hash = lambda: b"another version"
programs.use(os.path.join(sys.argv[1], "programs"))
a = np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]])
p = programs.lower_program("solve", lambda a, b: jnp.linalg.solve(a, b) * 2.0, (a, np.ones(3)))
x = p.compile()(a, np.arange(3.0))
print(json.dumps({"from": "executable" if p._lowered is None else "export" if p.loaded else "trace",
                  "x": np.asarray(x).tolist()}))
"""


def test_an_executable_read_back_runs_and_one_from_xla_cache_is_not_kept(tmp_path):
    """A fresh process loads the executable the first compiled, and it runs (LAPACK, which jaxlib's
    kernels find when a program is lowered, is found without). Where JAX's persistent cache gave the
    executable back (the exported program's file lost), it is not kept: such a one serialises
    without its code; the next process compiles from the exported program. Another version of
    jaxslosh (new files' names) does not find its programs in JAX's cache: it compiles them, and keeps
    their executables."""
    def run(*extra):
        p = subprocess.run([sys.executable, "-c", CACHED_SOLVE, str(tmp_path), *extra], capture_output=True,
                           text=True, timeout=120)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout.strip().splitlines()[-1])
    want = 2.0 * np.linalg.solve([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]], np.arange(3.0))
    seen = [run(), run()]
    for f in os.listdir(tmp_path / "programs"):
        os.remove(tmp_path / "programs" / f)
    seen += [run(), run(), run("new"), run("new")]
    assert [s["from"] for s in seen] == ["trace", "executable", "trace", "export", "trace", "executable"]
    for s in seen:
        np.testing.assert_allclose(s["x"], want, rtol=1e-14)


SCENES = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "scenes")


@pytest.mark.parametrize("name, extra", [
    ("paper_ship_mast.toml", ""),                  # structures: frames and multipliers in the state
    ("paper_ship_waves.toml", ""),                 # radiation memory states
    ("anti_roll_tank.toml", ""),                   # a modal liquid
    ("vessel_only.toml", "energy_projection = true"),     # the initial energy in the state
])
def test_the_chunk_is_lowered_for_the_shapes_of_the_initial_state(name, extra):
    """run/compiled.compile_run lowers the chunk for loop.carry_shapes before `start` is traced: they
    must be the shapes and types of start's carry (else the chunk is lowered twice)."""
    from jaxslosh.run.loop import carry_shapes, core, traced_init
    from jaxslosh.run.simulate import prepare
    from jaxslosh.run.compiled import same_shapes
    from jaxslosh.scene import load_scene
    with open(os.path.join(SCENES, name)) as f:
        text = f.read()
    if extra:      # a conservative scheme, which the projection needs
        text = text.replace('scheme = "hht"\nalpha = 0.01', f'scheme = "newmark"\nalpha = 0.0\n{extra}', 1)
    setup = prepare(load_scene(text))
    b = core(setup.built)
    like = carry_shapes(b, setup.solver)
    carry = eqx.filter_eval_shape(traced_init, b, setup.solver)[0]
    assert (setup.solver.project if extra else True)
    assert same_shapes(like, carry)
    assert jax.tree_util.tree_structure(like) == jax.tree_util.tree_structure(carry)
    assert len(jax.tree_util.tree_leaves(carry)) >= 12


def test_the_command_line_hint_names_what_is_computed(tmp_path, monkeypatch):
    """jaxslosh/entry.py loads ahead what the last run of the same command line used: the output
    file and the reporting options do not change the name, an override or the scene's text does."""
    from jaxslosh.entry import command_hint
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text("a = 1\n")
    h = command_hint(["run", "s.toml", "-o", "a.h5"])
    assert h == command_hint(["run", "s.toml", "--output", "b.h5", "--no-progress"]) == command_hint(
        ["run", "--force", "s.toml", "-oc.h5"])
    assert h != command_hint(["run", "s.toml", "--dt", "0.02"])
    (tmp_path / "s.toml").write_text("a = 2\n")
    assert h != command_hint(["run", "s.toml"])
