"""The staging hooks (jaxslosh/staging.py): without the compile cache a program is traced and
compiled in the process and nothing is named or kept; the entry points install the cache's hooks."""
import jax
import jax.numpy as jnp
import numpy as np
from jax._src import monitoring

from jaxslosh import staging
from jaxslosh.cache import programs


def test_without_the_cache_a_program_compiles_in_the_process_and_nothing_is_kept():
    staging.install()
    try:
        assert not staging.installed()
        fn, loaded = staging.compile_program("square", lambda x: x * x, (jnp.arange(3.0),))
        np.testing.assert_allclose(np.asarray(fn(jnp.arange(3.0))), [0.0, 1.0, 4.0], rtol=0, atol=0)
        assert not loaded and staging.program_key("square", (jnp.arange(3.0),)) is None
        assert staging.cached("x", "key", lambda: 42) == 42 and staging.folder() is None
        assert staging.lower_program("square", lambda x: x * x, (jnp.arange(3.0),)).compile_in_background().path is None
    finally:
        programs.install()
    assert staging.installed() and staging.program_key("square", (jnp.arange(3.0),)) is not None


def test_on_device_is_jnp_asarray_without_a_compile():
    compiles = []
    monitoring.register_event_duration_secs_listener(
        lambda e, d, **k: compiles.append(e) if e == "/jax/core/compile/backend_compile_duration" else None)
    values = [np.linspace(0.0, 1.0, 7).reshape(7, 1) ** 3, np.float64(2.5), np.arange(5), np.ones(3, np.float32)]
    n0 = len(compiles)
    got = [staging.on_device(v) for v in values]
    assert len(compiles) == n0           # jnp.asarray compiles one program per new shape and dtype
    for v, g in zip(values, got):
        ref = jnp.asarray(v)
        assert isinstance(g, jax.Array) and g.dtype == ref.dtype and g.weak_type == ref.weak_type
        np.testing.assert_array_equal(np.asarray(g), np.asarray(ref))
    # traced values and lists go to jnp.asarray; inside a trace a NumPy array is the same constant
    assert jax.jit(lambda x: staging.on_device(x) * 2.0)(jnp.ones(2)).tolist() == [2.0, 2.0]
    assert jax.jit(lambda x: x + staging.on_device(values[0][:, 0]))(jnp.zeros(7)).tolist() == values[0][:, 0].tolist()
    assert staging.on_device([1.0, 2.0]).tolist() == [1.0, 2.0]
