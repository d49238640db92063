"""Exported programs kept across processes (jaxslosh/programs.py): a program read back from its file
computes what the traced one does, and a change of anything the trace depends on (a static value,
a shape) names another file."""
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxslosh import programs


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


SCENES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scenes")


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
