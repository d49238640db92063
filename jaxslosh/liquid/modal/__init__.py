"""The liquid reduced to modes: the Ritz bases (reduction.py), the term on modal coordinates
(term.py) and its block (build.py)."""
