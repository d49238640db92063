"""The multimodal liquid (Faltinsen and Timokha): its modes, expansions and steepness guard
(modes.py, expansion.py, steep.py), the two- and three-dimensional tanks (term.py, tank3d.py) and
their block (build.py, build3d.py)."""
