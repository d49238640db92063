"""What the time loop traces: the system's residual (the virtual work of eq. 26) and energy, as
equinox modules built once from the scene (assemble/), evaluated inside the jitted step."""
