"""Mooring lines (docs/guide/moorings.md): the quasi-static elastic catenary (catenary.py), the lines'
term of the residual (term.py) and the static analysis of `jaxslosh mooring` (statics.py)."""
