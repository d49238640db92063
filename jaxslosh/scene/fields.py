"""The field reader of scene tables: types, conversions and per-value checks.

Each table is read by `read`, which takes a field spec `{key: (kind, check)}`: it rejects unknown
keys, missing required keys and wrong types, converts the values (ints are accepted for floats,
booleans are never numbers) and runs the per-value checks. Every error is a `SceneError` that names
the dotted key of the offending value.
"""
from __future__ import annotations

import datetime
import math
from typing import Any, Callable, Iterable, Optional

import numpy as np

from .types import SceneError

Check = Optional[Callable[[Any], Optional[str]]]


def positive(v):
    return None if v > 0 else f"must be positive, got {show(v)}"


def non_negative(v):
    return None if v >= 0 else f"must be >= 0, got {show(v)}"


def at_least(n: int) -> Check:
    return lambda v: None if v >= n else f"must be >= {n}, got {show(v)}"


def one_of(options: tuple[str, ...]) -> Check:
    listed = " | ".join(f'"{o}"' for o in options)
    return lambda v: None if v in options else f"must be one of {listed}, got {show(v)}"


def counts(v):
    return None if all(n >= 1 for n in v) else f"each count must be >= 1, got {show(v)}"


def sizes(v):
    return None if all(x > 0 for x in v) else f"each component must be positive, got {show(v)}"


def valid_name(v):
    if not v.strip():
        return "must be a non-empty string"
    bad = [c for c in ".[]/" if c in v]
    if bad:  # names are parts of dotted parameter keys and of result-file group paths
        return f"{show(v)} may not contain {' or '.join(repr(c) for c in bad)}"
    return None


def poisson_ratio(v):
    return None if -1.0 < v < 0.5 else f"must lie in (-1, 0.5), got {show(v)}"


def read(table, where: str, spec: dict[str, tuple[str, Check]], required: Iterable[str] = ()) -> dict:
    """Check a TOML table against `spec` and return `{key: converted value}` for the keys present.

    Kinds: float, int, str, vec3 (3 numbers), mesh (3 ints), inertia (3 diagonal values or 3x3),
    str_or_table (checked by the caller), table and tables (sub-tables: only their type is checked
    here, the caller reads them). `check(value)` returns an error message or None.
    """
    if not isinstance(table, dict):
        raise SceneError(where, f"must be a table, got {_toml_type(table)} {show(table)}")
    for key in table:
        if key not in spec:
            raise SceneError(_join(where, key), f"unknown key (known: {', '.join(spec)})")
    for key in required:
        if key not in table:
            what = (f"the [{_join(where, key)}] table is required" if spec[key][0] == "table"
                    else "a required key is missing")
            raise SceneError(_join(where, key), what)
    out = {}
    for key, (kind, check) in spec.items():
        if key not in table:
            continue
        name = _join(where, key)
        value = _CONVERT[kind](name, table[key])
        if kind in ("table", "tables", "str_or_table"):
            continue
        if check is not None:
            msg = check(value)
            if msg:
                raise SceneError(name, msg)
        out[key] = value
    return out


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


def _float(name: str, x) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise SceneError(name, f"must be a number, got {_toml_type(x)} {show(x)}")
    x = float(x)
    if not math.isfinite(x):
        raise SceneError(name, f"must be finite, got {show(x)}")
    return x


def _int(name: str, x) -> int:
    if isinstance(x, bool) or not isinstance(x, int):
        raise SceneError(name, f"must be an integer, got {_toml_type(x)} {show(x)}")
    return x


def _bool(name: str, x) -> bool:
    if not isinstance(x, bool):
        raise SceneError(name, f"must be true or false, got {_toml_type(x)} {show(x)}")
    return x


def _str(name: str, x) -> str:
    if not isinstance(x, str):
        raise SceneError(name, f"must be a string, got {_toml_type(x)} {show(x)}")
    return x


def _vec3(name: str, x) -> tuple[float, float, float]:
    if not (isinstance(x, list) and len(x) == 3 and all(_is_number(c) for c in x)):
        raise SceneError(name, f"must be a list of 3 numbers, got {_toml_type(x)} {show(x)}")
    return tuple(_float(f"{name}[{i}]", c) for i, c in enumerate(x))  # type: ignore[return-value]


def _mesh(name: str, x) -> tuple[int, int, int]:
    if not (isinstance(x, list) and len(x) == 3 and all(isinstance(c, int) and not isinstance(c, bool) for c in x)):
        raise SceneError(name, f"must be a list of 3 integers, got {_toml_type(x)} {show(x)}")
    return tuple(x)  # type: ignore[return-value]


def _inertia(name: str, x):
    """3 diagonal values or a 3x3 list; symmetric (to 1e-9 relative, then symmetrized) and positive definite."""
    if isinstance(x, list) and len(x) == 3 and all(_is_number(c) for c in x):
        d = _vec3(name, x)
        if not all(c > 0 for c in d):
            raise SceneError(name, f"the diagonal values must be positive (positive definite), got {show(list(d))}")
        return tuple(tuple(d[i] if i == j else 0.0 for j in range(3)) for i in range(3))
    if not (isinstance(x, list) and len(x) == 3
            and all(isinstance(r, list) and len(r) == 3 and all(_is_number(c) for c in r) for r in x)):
        raise SceneError(name, f"must be 3 diagonal values or a 3x3 list of numbers, got {_toml_type(x)} {show(x)}")
    m = np.array([_vec3(f"{name}[{i}]", r) for i, r in enumerate(x)])
    scale = np.abs(m).max()
    if np.abs(m - m.T).max() > 1e-9 * scale:
        i, j = np.unravel_index(np.argmax(np.abs(m - m.T)), m.shape)
        raise SceneError(name, f"not symmetric: [{i}][{j}] = {show(float(m[i, j]))} but "
                               f"[{j}][{i}] = {show(float(m[j, i]))}")
    m = 0.5 * (m + m.T)
    eig = np.linalg.eigvalsh(m)
    if eig.min() <= 0:
        raise SceneError(name, f"not positive definite: its eigenvalues are {', '.join(f'{e:.6g}' for e in eig)}")
    return tuple(tuple(float(c) for c in row) for row in m)


def _table(name: str, x):
    if not isinstance(x, dict):
        raise SceneError(name, f"must be a table, got {_toml_type(x)} {show(x)}")
    return x


def _tables(name: str, x):
    if not (isinstance(x, list) and all(isinstance(t, dict) for t in x)):
        what = "a table" if isinstance(x, dict) else f"{_toml_type(x)} {show(x)}"
        raise SceneError(name, f"must be an array of tables ([[{name}]]), got {what}")
    return x


def _str_or_table(name: str, x):
    if not isinstance(x, (str, dict)):
        raise SceneError(name, f'must be "rigid", "elastic" or a [{name.split("[")[0]}.walls] table, '
                               f"got {_toml_type(x)} {show(x)}")
    return x


def numbers(name: str, x):
    """A number or a rectangular nested list of numbers (the tables of [vessel.hydrodynamics]), as floats."""
    def conv(e, path):
        if isinstance(e, list):
            return [conv(c, f"{path}[{i}]") for i, c in enumerate(e)]
        return _float(path, e)
    if not (_is_number(x) or isinstance(x, list)):
        raise SceneError(name, f"must be a number or an array of numbers, got {_toml_type(x)} {show(x)}")
    out = conv(x, name)
    if isinstance(out, list):
        try:
            np.asarray(out, dtype=float)
        except ValueError:
            raise SceneError(name, "must be a rectangular array (every row of the same length)") from None
    return out


_CONVERT = {"bool": _bool, "float": _float, "int": _int, "str": _str, "vec3": _vec3, "mesh": _mesh, "inertia": _inertia,
            "table": _table, "tables": _tables, "str_or_table": _str_or_table, "numbers": numbers,
            "any": lambda name, x: x}          # checked by the caller


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


#: the TOML name of a value's type (bool before int: a bool is an int in Python)
_TOML_TYPES = ((bool, "boolean"), (int, "integer"), (float, "float"), (str, "string"), (list, "array"),
               (dict, "table"), ((datetime.date, datetime.time), "date/time"))


def _toml_type(x) -> str:
    return next((name for kind, name in _TOML_TYPES if isinstance(x, kind)), type(x).__name__)


def show(x) -> str:
    """A value as it reads in TOML, shortened."""
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, str):
        return '"' + x.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(x, (list, tuple)):
        s = "[" + ", ".join(show(c) for c in x) + "]"
    elif isinstance(x, dict):
        s = "{" + ", ".join(f"{k} = {show(v)}" for k, v in x.items()) + "}"
    else:
        s = str(x)
    return s if len(s) <= 80 else s[:77] + "..."


def flat_list(v, what: str):
    """(the values of a number or a flat list, None) or (None, the message): `what` names one item."""
    values = v if isinstance(v, list) else [v]
    if not values:
        return None, f"must be {what} or a non-empty list of them"
    if any(isinstance(x, list) for x in values):
        return None, f"must be a number or a flat list of numbers, got {show(v)}"
    return values, None
