"""The lumped-only keys of a `[[mooring]]` table with `model = "lumped"` (docs/guide/moorings-lumped.md),
read and checked for the scene loader (plain Python, as the loader: no JAX)."""
from __future__ import annotations

from .fields import at_least, non_negative, positive, read
from .types import SceneError

#: the lumped-only keys of a `[[mooring]]` table and their defaults (mass: from weight and diameter)
LUMPED_KEYS = {"segments": 20, "diameter": 0.09, "mass": None, "cd": (1.6, 0.1), "ca": (1.0, 0.0),
               "internal_damping": -0.8, "seabed_stiffness": 3.0e6, "seabed_damping": 3.0e5}
#: the values of a lumped line that params, a sweep or a fit may trace (its rest shape is solved from
#: them in the trace; the sub-step stays the scene's); a lumped line's seabed has no friction to trace
LUMPED_TRACEABLE = ("length", "weight", "ea")


def read_lumped(table: dict, where: str) -> tuple[dict, tuple]:
    """A `[[mooring]]` table with `model = "lumped"`, split for the loader: (the table without its
    lumped-only keys, for the lines' common reader; the lumped values as sorted (key, value) pairs,
    checked: SceneError naming the key). Keys left out take LUMPED_KEYS' defaults when built."""
    rest = {k: v for k, v in table.items() if k not in LUMPED_KEYS}
    mine = {k: v for k, v in table.items() if k in LUMPED_KEYS}
    v = read(mine, where, {"segments": ("int", at_least(2)), "diameter": ("float", positive),
                           "mass": ("float", positive), "internal_damping": ("float", None),
                           "seabed_stiffness": ("float", non_negative), "seabed_damping": ("float", non_negative),
                           "cd": ("any", None), "ca": ("any", None)})
    for key in ("cd", "ca"):
        if key in v:
            x = v[key]
            ok = (isinstance(x, list) and len(x) == 2
                  and all(isinstance(c, (int, float)) and not isinstance(c, bool) and c >= 0 for c in x))
            if not ok:
                raise SceneError(f"{where}.{key}", f"must be [normal, tangential], two numbers >= 0, got {x!r}")
            v[key] = (float(x[0]), float(x[1]))
    return rest, tuple(sorted(v.items()))
