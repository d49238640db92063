"""jaxslosh's benchmarks: `speed/` (what a run costs) and `validation/` (the physics against references).
Run a script as a module from the repository root: `python -m benchmarks.speed.bench_paper --quick`
(benchmarks/README.md). Importing the package switches JAX to float64, as jaxslosh's command line
does, before any script's own imports create an array."""
import jax

jax.config.update("jax_enable_x64", True)
