"""Lumped lines seen as their quasi-static limit, the catenary (docs/guide/moorings-lumped.md); the
lumped-only keys' reader is the loader's (scene/lumped_keys.py)."""
from __future__ import annotations

import dataclasses

from ..scene.lumped_keys import LUMPED_KEYS, LUMPED_TRACEABLE, read_lumped  # noqa: F401

def quasi_static_lines(scene):
    """The scene with its lumped lines as catenary lines, their quasi-static limit (within 0.13 % at
    20 segments for the OC3-Hywind line: docs/guide/moorings-lumped.md): what the static analysis
    (`jaxslosh mooring`) and the frequency domain's linearisation about rest take. Linearised with
    its nodes held where they are, a lumped line would give its last segment's axial stiffness
    instead of the line's. The scene as it is without lumped lines."""
    lines = getattr(scene, "mooring", ())
    if not any(getattr(m, "model", "catenary") == "lumped" for m in lines):
        return scene
    return dataclasses.replace(scene, mooring=tuple(
        dataclasses.replace(m, model="catenary", lumped=()) if m.model == "lumped" else m for m in lines))
