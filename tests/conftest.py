import os
import sys

# The tests live in folders by sub-package (tests/fem, tests/hull, ...); their shared helpers
# (helpers.py, sloshing_reference.py, section_meshes.py) here, and a few test files import another's
# scenes: every folder is on the path, as pytest's default import mode puts a test file's own
# (test file names are unique across the folders).
_HERE = os.path.dirname(os.path.abspath(__file__))
for _d in sorted(os.listdir(_HERE)):
    if os.path.isdir(os.path.join(_HERE, _d)) and _d not in ("data", "__pycache__"):
        sys.path.append(os.path.join(_HERE, _d))
if _HERE not in sys.path:
    sys.path.insert(0, _HERE)

# Most of the suite's time is JAX tracing and XLA compiling programs that then run for seconds at
# most, so the tests ask XLA for quick machine code (set before jax starts its backend, and
# inherited by the subprocesses and notebook kernels the tests start): LLVM's optimisation passes
# off; XLA's classic CPU loop emitters, which compile the many small fusions of a step faster than
# its fusion emitters (as staging.XLA_OPTIONS does for the command line's runs); and one LLVM
# module per program, not several compiled on threads: the two xdist workers already keep both
# cores busy. XLA's graph passes are untouched: the tests run the same XLA programs, only as less
# optimised machine code. The CLI, the notebooks run by users and the benchmarks keep their own
# settings. (README "Tests" has the suite's times.)
_FAST_COMPILE = ("--xla_backend_optimization_level=0 --xla_llvm_disable_expensive_passes=true "
                 "--xla_cpu_use_fusion_emitters=false --xla_cpu_parallel_codegen_split_count=1")
if "xla_backend_optimization_level" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + _FAST_COMPILE).strip()

# the command line keeps JAX's persistent compilation cache in the user's cache folder; tests that
# call it in process would fill it: off here (a test of the cache gives its subprocess a folder)
os.environ.setdefault("JAXSLOSH_CACHE_DIR", "")

import jax  # noqa: E402
import pytest  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

jax.config.update("jax_enable_x64", True)
_CACHE_THRESHOLDS = (jax.config.jax_persistent_cache_min_compile_time_secs,
                     jax.config.jax_persistent_cache_min_entry_size_bytes)

# the tests stand for the entry points (the command line, `js.simulate`), which install the compile
# cache's hooks (jaxslosh/staging.py): a test that imports a module below them gets the same staging
from jaxslosh.cache.programs import install as _install_cache  # noqa: E402

_install_cache()

# The suite runs on two xdist workers (pyproject addopts), one per core. OpenBLAS (NumPy's and
# SciPy's, which jaxlib's LAPACK calls also use) would start a thread per core in each worker as
# well, and oversubscribed cores slow dense factorizations many times over: one BLAS thread each.
threadpool_limits(limits=1, user_api="blas")


@pytest.fixture(autouse=True)
def _cache_folder_off():
    """A test that calls the command line in process with JAXSLOSH_CACHE_DIR set turns JAX's
    persistent cache on for the whole worker (jax.config is global): a later test would then be
    given executables from that folder, which cache/programs.py does not keep. Off again after each."""
    yield
    from jax._src import compilation_cache
    from jaxslosh.cache import programs
    programs.use(None)
    # a campaign's in-process worker sets XLA's cache thresholds to zero (and restores them);
    # the defaults again after every test, so that no test's compiles depend on an earlier one's
    jax.config.update("jax_persistent_cache_min_compile_time_secs", _CACHE_THRESHOLDS[0])
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", _CACHE_THRESHOLDS[1])
    if jax.config.jax_compilation_cache_dir is not None:
        jax.config.update("jax_compilation_cache_dir", None)
        compilation_cache.reset_cache()


@pytest.fixture(autouse=True, scope="module")
def _free_compiled_code():
    """Dropping the compiled executables after a module keeps the suite's memory flat (a whole run
    otherwise grows past several GB), but costs every later module its compiles again, the many
    small programs of eager operations during model building included (seconds per module). So
    they are dropped only once the worker holds more than _KEEP_BYTES: at 3 GB both workers passed it
    a quarter into the suite and cleared after nearly every later module (a module that clears after
    itself recompiles about 20 programs more, 1 s of CPU); at 5 GB two workers still fit a 24 GB
    machine with room for a module's peak."""
    yield
    if _resident_bytes() > _KEEP_BYTES:
        jax.clear_caches()


#: a worker's resident memory above which the compiled executables are dropped after a module
_KEEP_BYTES = 5 << 30


def _resident_bytes():
    """The worker's resident memory; where /proc is not there (not Linux), as if above the limit (the
    executables are dropped after every module, as before)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:
        return _KEEP_BYTES + 1
