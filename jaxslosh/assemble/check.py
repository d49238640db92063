"""The effects `jaxslosh check` lists: the assembled model's own description. Each term of the
model (physics/terms.py `describe`) says what it adds; an effect is listed exactly when its term is
in the model, since the list is read from the model that assemble/system.py assembles (its outline:
the same terms without their arrays, so that a scene of any size is checked at once)."""
from __future__ import annotations

import dataclasses

from ..physics.about import holder
from ..physics.system import System
from ..physics.terms import AbstractTerm
from ..scene.types import Scene
from .effects import count_unknowns, switched_off
from .system import outline

#: the System's own line, for the one switch it holds itself (System.gravity_body)
GRAVITY_TURNING = ("gravity turning with the body", "load of eq. (32) on the liquid")


#: what describes itself: the terms (the structures in their own frames and a prescribed motion
#: among them)
DESCRIBED = (AbstractTerm,)


def model_parts(system: System) -> tuple:
    """Every part of the model that describes itself, in the System's order: its fields, a tuple's
    members in turn (the terms); each part once."""
    parts = []
    for f in dataclasses.fields(system):
        value = getattr(system, f.name)
        for part in value if isinstance(value, tuple) else (value,):
            if isinstance(part, DESCRIBED) and all(part is not p for p in parts):
                parts.append(part)
    return tuple(parts)


def model_effects(system: System) -> list[tuple[str, str, object]]:
    """(effect, text, its owner) for every line the model's parts give; the owner is the term (or
    the System itself for gravity turning with the body)."""
    out = [(effect, text, part) for part in model_parts(system) for effect, text in part.describe()]
    if system.gravity_turning and not system.liquid.empty and float(system.gravity) > 0:
        out.append((*GRAVITY_TURNING, system))
    return out


def _body_named(text: str, names) -> str:
    """Which of `names` a "floating body" line (assemble/bodies.py: "'<name>': ...") is about; "" if none."""
    return next((n for n in names if text.startswith(f"{n!r}:")), "")


def effects_summary(scene: Scene) -> str:
    """`check`'s effects: the model's own lines, what `[effects]` switched off, and the unknowns."""
    lines = ["effects simulated:"]
    effects = model_effects(outline(scene))
    # a line a term adds for a [[bodies]] body (a mooring line it holds) goes under that body's own line
    held: dict = {}
    for name, why, _ in effects:
        body, text = holder(why)
        if body is not None:
            held.setdefault(body, []).append(f"      - {name}: {text}")
    for name, why, _ in effects:
        if holder(why)[0] is None:
            lines.append(f"  - {name}: {why}")
            if name == "floating body":
                lines += held.pop(_body_named(why, held), [])
    lines += [line for rest in held.values() for line in rest]      # a body check did not list (none expected)
    off = switched_off(scene)
    if off:
        lines.append("switched off in [effects]: " + ", ".join(off))
    lines.append(f"unknowns per step: {count_unknowns(scene)}")
    return "\n".join(lines)
