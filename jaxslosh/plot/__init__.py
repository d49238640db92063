"""Figures of results, fits and free surfaces (matplotlib, on their own Agg canvases: a notebook's
backend is left alone)."""
