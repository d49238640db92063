"""Finite elements, built once per scene on the host: meshes, element matrices (Hessians of
element energies taken with JAX), natural modes and modal bases. Nothing here is traced in the
time loop; `physics/` holds what is."""
