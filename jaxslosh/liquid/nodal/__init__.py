"""The nodal liquid: the stabilized and paper elements (element.py, model.py), its term (term.py),
its large meshes' solves (sparse.py, boxsolve.py) and its block (build.py)."""
