"""The compile cache, a wing above the time loop: programs exported and kept across processes
(programs.py), their executables loaded ahead of use (executables.py), the run's two programs
compiled ahead of time (compiled.py). Nothing below it imports it: the modules that compile call
jaxslosh/staging.py, and the cache installs itself there when imported. Importing this package
imports nothing (the command line's entry point loads executables before JAX is imported)."""
