"""The sea on the host: wave spectra and components, the Froude-Krylov forces of a box hull,
hydrodynamic tables (the scene's, Capytaine's) and the state-space fit of the radiation memory.
NumPy, run once per build; `physics/seakeeping.py` holds what the time loop evaluates."""
