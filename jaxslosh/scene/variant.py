"""Variants of a scene: `js.scene_with(scene, {"tanks.tank.mesh": [8, 8, 8], ...})` sets any keys of
the scene file (strings, booleans, numbers, lists; None removes a key) and loads the result as the
file with those values would load, so a study or a benchmark varies a scene through its keys, with
the loader's checks and messages, instead of rewriting TOML text. The variant's `text` is the TOML
it was loaded from (what its result files store as their scene)."""
from __future__ import annotations

import copy
import math
from typing import Any, Mapping

from .load import parse_scene, tomllib
from .types import Scene, SceneError

#: the arrays of tables whose items a key names by `name` (`tanks.tank.fill_depth`) or index (`tanks[0].fill_depth`)
NAMED = ("tanks", "structures", "probes", "mooring", "bodies", "connections")


def scene_with(scene: Scene, values: Mapping[str, Any]) -> Scene:
    """The scene with the dotted keys of `values` set, validated as a scene file (SceneError naming
    the key). A table's new keys are created; `None` removes a key."""
    if not scene.text:
        raise SceneError("", "this scene was built in Python, not from a file: it has no keys to set")
    mapping = copy.deepcopy(tomllib.loads(scene.text))
    forms = {}
    for key, value in values.items():
        path = _path(mapping, key)
        if len(path) > 1 and isinstance(path[1], int):      # how the loader names it
            forms[f"{path[0]}[{path[1]}]." + ".".join(str(p) for p in path[2:])] = key
        node = mapping
        for part in path[:-1]:
            if isinstance(part, int):
                node = node[part]
            else:
                node = node.setdefault(part, {})
                if not isinstance(node, (dict, list)):
                    raise SceneError(key, f"{part!r} is a value, not a table")
        if value is None:
            node.pop(path[-1], None)
        else:
            node[path[-1]] = _plain(key, value)
    text = toml_text(mapping)
    try:
        return parse_scene(tomllib.loads(text), text=text, path=scene.path)
    except SceneError as e:          # named as the caller named it
        for form, key in forms.items():
            if e.key == form or e.key.startswith((form + ".", form + "[")):
                raise SceneError(key + e.key[len(form):], str(e)[len(e.key) + 2:]) from None
        raise


def _path(mapping: dict, key: str) -> list:
    """A dotted key's path in the mapping: `tanks.tank.mesh` or `tanks[0].mesh` -> ["tanks", 0, "mesh"]."""
    head, _, rest = key.partition(".")
    if "[" in head and head.endswith("]"):
        group, index = head[:-1].split("[", 1)
        items = mapping.get(group, [])
        try:
            i = int(index)
            items[i]
        except (ValueError, IndexError):
            raise SceneError(key, f"the scene has no {group}[{index}]") from None
        return [group, i] + (rest.split(".") if rest else [])
    if head in NAMED and isinstance(mapping.get(head), list) and rest:
        name, _, tail = rest.partition(".")
        for i, item in enumerate(mapping[head]):
            if item.get("name") == name:
                return [head, i] + (tail.split(".") if tail else [])
        known = ", ".join(str(item.get("name")) for item in mapping[head])
        raise SceneError(key, f"the scene has no {head} named {name!r} (its {head}: {known})")
    return key.split(".")


def _plain(key: str, value):
    """A value as TOML holds it (NumPy and JAX scalars and arrays as Python numbers and lists; a
    mapping as a table, for keys a dotted name cannot spell: `{"campaign.limits": {"probe.B": 0.5}}`)."""
    if isinstance(value, (str, bool, int, float)):
        return value
    if isinstance(value, Mapping):
        return {str(k): _plain(f"{key}.{k}", v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(key, v) for v in value]
    if hasattr(value, "tolist"):
        return value.tolist()
    raise SceneError(key, f"{value!r} is not a value a scene file can hold")


def toml_text(mapping: Mapping[str, Any]) -> str:
    """A TOML document of a parsed mapping (tables, arrays of tables, strings, numbers, booleans and
    lists of them: what a scene file holds), so that tomllib.loads(toml_text(m)) == m."""
    lines: list[str] = []
    _table(mapping, [], lines)
    return "\n".join(lines).strip() + "\n"


def _table(table: Mapping[str, Any], where: list, lines: list) -> None:
    subtables, arrays = [], []
    for k, v in table.items():
        if isinstance(v, dict):
            subtables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            arrays.append((k, v))
        else:
            lines.append(f"{_key(k)} = {_value(v)}")
    for k, v in subtables:
        lines.append("")
        lines.append(f"[{'.'.join(_key(p) for p in where + [k])}]")
        _table(v, where + [k], lines)
    for k, items in arrays:
        for item in items:
            lines.append("")
            lines.append(f"[[{'.'.join(_key(p) for p in where + [k])}]]")
            _table(item, where + [k], lines)


def _key(k: str) -> str:
    return k if k and all(c.isalnum() or c in "_-" for c in k) else _string(k)


def _string(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n").replace("\t", "\\t") + '"'


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):      # an inline table inside an array
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"not a TOML value: {v!r}")
