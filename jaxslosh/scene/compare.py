"""Two scenes compared value by value and in structure: what `identify` checks before it fits a
scene to a result file that carries the scene which made it (the file's `scene` attribute).

Every field of the validated Scene is flattened to a dotted key close to the TOML path
(`vessel.mass`, `tanks.tank.fluid.density`, `tanks.tank.mesh`, `simulation.dt`), tanks, structures
and probes by name; a table (a tank, `vessel.hydrostatics`, `waves`) that one scene has and the
other lacks is one difference, not one per key under it. Loaded
scenes are compared, not their TOML texts: a value written out in one and left at its default in
the other is the same value.
"""
from __future__ import annotations

import dataclasses
from typing import Any, Iterable

import numpy as np

from .fields import show
from .types import Scene

# what does not change the model a result was made with: the run's length (a fit runs as long as
# its record), the title, the Newton solver's own settings (they change a run within its tolerance),
# and the [campaign] table (a campaign's limits and defaults: no run reads them)
HARMLESS = frozenset(("title", "simulation.duration", "simulation.chunk", "simulation.max_iterations",
                      "simulation.substeps", "simulation.linear_solver", "simulation.tolerance",
                      "campaign", "campaign.limits", "campaign.headings", "campaign.seeds", "campaign.duration"))

# dataclass fields written under another name in the scene file; None: not compared
_TOML_NAME = {("Tank", "wall_spec"): "walls", ("Tank", "walls"): None,      # the [tanks.walls] table says it
              ("Waves", "omega"): "frequency", ("Waves", "omega_range"): "frequency_range",
              ("Hydrodynamics", "base_dir"): None, ("Hull", "base_dir"): None,   # where the scene file lay
              ("Fluid", "element_default"): None,                                 # the loader's note
              ("Tank", "geometry"): None,                                         # the shape keys, as a shape
              ("Tank", "form"): None,                                             # the liquid keys, as a form
              ("MooringLine", "anchor_height"): None,                             # the anchor's z and the depth
              ("Vessel", "cog_height"): None}     # derived from the hull (kg - draft), which is compared

_TABLE = object()      # a table that is present (its keys follow)


def flatten(scene: Scene) -> dict[str, Any]:
    """{dotted key: value} of every field of the scene (text, path and warnings apart); a present
    table maps to a marker, an absent one to None; named items under their names."""
    out: dict[str, Any] = {}

    def walk(prefix: str, x) -> None:
        if dataclasses.is_dataclass(x):
            out[prefix] = _TABLE
            for f in dataclasses.fields(x):
                # a kind (BoxHull, RegularWaves) is named as the class it is a kind of (Hull, Waves)
                name = next((_TOML_NAME[c.__name__, f.name] for c in type(x).__mro__ if (c.__name__, f.name) in _TOML_NAME),
                            f.name)
                if name is not None:
                    walk(f"{prefix}.{name}", getattr(x, f.name))
        elif isinstance(x, tuple) and all(dataclasses.is_dataclass(i) and hasattr(i, "name") for i in x):
            for item in x:          # by name (their order changes nothing); none: no key
                walk(f"{prefix}.{item.name}", item)
        else:
            out[prefix] = x

    for f in dataclasses.fields(scene):
        if f.name not in ("text", "path", "warnings"):
            walk(f.name, getattr(scene, f.name))
    return out


def _same(a, b) -> bool:
    if a is _TABLE or b is _TABLE or a is None or b is None or isinstance(a, str) or isinstance(b, str):
        return a is b or (a == b and type(a) is type(b))
    try:
        x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    except (TypeError, ValueError):
        return a == b
    # the same text loads to the same floats; the tolerance only forgives round-off in derived values
    return x.shape == y.shape and bool(np.allclose(x, y, rtol=1e-9, atol=0.0))


def show_value(x) -> str:
    """A flattened value as a message writes it."""
    if x is None:
        return "absent"
    if x is _TABLE:
        return "present"
    return show(x)


def differences(ours: Scene, theirs: Scene, ignore: Iterable[str] = ()) -> list[tuple[str, Any, Any]]:
    """(key, our value, their value) for every key whose value differs, besides `ignore` (dotted
    keys, canonical form) and HARMLESS; the keys under a table only one scene has (a tank, the
    hydrostatics) are not repeated. Our scene's order, then the keys only theirs has."""
    a, b = flatten(ours), flatten(theirs)
    skip = HARMLESS | frozenset(ignore)
    out: list[tuple[str, Any, Any]] = []
    for key in list(a) + [k for k in b if k not in a]:
        if key in skip or any(key.startswith(d + ".") for d, x, y in out if x is None or y is None):
            continue
        x, y = a.get(key), b.get(key)
        if not _same(x, y):
            out.append((key, x, y))
    return out
