import jax
import pytest

jax.config.update("jax_enable_x64", True)


@pytest.fixture(autouse=True, scope="module")
def _free_compiled_code():
    """Each test module compiles its own scenes; dropping the compiled executables after a module
    keeps the suite's memory flat (a whole run otherwise grows past several GB)."""
    yield
    jax.clear_caches()
