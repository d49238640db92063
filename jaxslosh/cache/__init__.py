"""The compile cache, above the runs that use it: programs exported and kept across processes
(programs.py) and their executables loaded ahead of use (executables.py). Nothing below it imports
it: the modules that compile (run/compiled.py: the run's two programs compiled ahead of time) call
jaxslosh/staging.py, and the entry points install the cache's hooks there (programs.install).
Importing this package imports nothing (the command line's entry point loads executables before
JAX is imported)."""
