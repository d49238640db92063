"""Parameter identification: scene values fitted to a measured result (identify.py)."""
