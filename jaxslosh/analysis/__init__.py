"""Analyses of a scene besides its time history: the natural modes of its liquid and structures."""
