"""jaxslosh's benchmarks: `speed/` (what a run costs) and `validation/` (the physics against references).
Run a script as a module from the repository root: `python -m benchmarks.speed.bench_paper --quick`
(benchmarks/README.md)."""
