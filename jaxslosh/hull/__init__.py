"""The hull as a closed surface: its geometry, clipping at a plane, and the large-angle hydrostatics."""
