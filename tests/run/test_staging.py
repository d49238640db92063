"""The staging hooks (jaxslosh/staging.py): without the compile cache a program is traced and
compiled in the process and nothing is named or kept; the entry points install the cache's hooks."""
import jax.numpy as jnp
import numpy as np

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
