"""The face-normal ("rt") liquid: the element on face fluxes (element.py, mesh.py, schur.py), its
blocks, term and inverse (blocks.py, term.py, inverse.py), elastic walls (walls.py) and its block
(build.py, stack.py)."""
