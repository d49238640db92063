import jax
import pytest
from threadpoolctl import threadpool_limits

jax.config.update("jax_enable_x64", True)

# The suite runs on two xdist workers (pyproject addopts), one per core. OpenBLAS (NumPy's and
# SciPy's, which jaxlib's LAPACK calls also use) would start a thread per core in each worker as
# well, and oversubscribed cores slow dense factorizations many times over: one BLAS thread each.
threadpool_limits(limits=1, user_api="blas")


@pytest.fixture(autouse=True, scope="module")
def _free_compiled_code():
    """Each test module compiles its own scenes; dropping the compiled executables after a module
    keeps the suite's memory flat (a whole run otherwise grows past several GB)."""
    yield
    jax.clear_caches()
