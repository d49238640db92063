"""The cases of a campaign: the scatter table (CSV), its cells x headings x seeds, and each case's
scene (the template's TOML with its `[waves]` keys set: `jaxslosh run` of that text is the case)."""
from __future__ import annotations

import csv
import functools
import io
import math
import os
import re
from typing import NamedTuple, Optional

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from ..assemble.hull import hull_waves, incident_waves
from ..assemble.seakeeping import excitation_arrays, linear_excitation_rao
from ..hydro.spectra import components
from ..scene.load import parse_scene
from ..scene.types import Scene, SceneError

#: the [waves] keys a scatter column may set besides hs and tp (each case's sea; the rest of the
#: scene is shared by every case, so that one compiled loop runs them all)
SEA_COLUMNS = ("gamma", "spreading", "directions", "depth")
INT_COLUMNS = ("directions",)


class ScatterError(ValueError):
    """A scatter table that cannot be read: the message names the column (or the row)."""


class Scatter(NamedTuple):
    hs: np.ndarray            # (c,) m
    tp: np.ndarray            # (c,) s
    weight: np.ndarray        # (c,) probability of the cell (occurrences normalised to sum 1)
    extra: dict               # {waves key: (c,) values}


class Cases(NamedTuple):
    """Every case of a campaign, cell-major: cell, heading, seed (one row per case)."""
    cell: np.ndarray
    hs: np.ndarray
    tp: np.ndarray
    heading: np.ndarray
    seed: np.ndarray
    weight: np.ndarray        # the cell's probability shared equally by its headings and seeds
    extra: dict

    @property
    def n(self) -> int:
        return int(self.hs.size)


def read_scatter(path_or_text: str) -> Scatter:
    """A scatter CSV (a header row with hs, tp and probability or occurrences; more columns set
    the [waves] keys of SEA_COLUMNS). ScatterError names the bad column or row."""
    if "\n" not in path_or_text and os.path.exists(path_or_text):
        with open(path_or_text, newline="", encoding="utf-8-sig") as f:     # a spreadsheet's byte-order mark
            text = f.read()
    elif "\n" in path_or_text:
        text = path_or_text
    else:
        raise ScatterError(f"{path_or_text}: no such file")
    rows = list(csv.reader(io.StringIO(text)))
    rows = [r for r in rows if any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    if not rows:
        raise ScatterError("the scatter table is empty: give a header row with hs, tp and probability or occurrences")
    head = [h.strip().lower() for h in rows[0]]
    for col in ("hs", "tp"):
        if col not in head:
            raise ScatterError(f"column {col!r} is missing (the header has {', '.join(head)})")
    has_p, has_n = "probability" in head, "occurrences" in head
    if has_p == has_n:
        raise ScatterError("give exactly one of the columns 'probability' or 'occurrences'")
    for col in head:
        if col not in ("hs", "tp", "probability", "occurrences") + SEA_COLUMNS:
            raise ScatterError(f"column {col!r}: not a scatter column (hs, tp, probability or occurrences, and the "
                               f"[waves] keys {', '.join(SEA_COLUMNS)})")
    if len(set(head)) != len(head):
        raise ScatterError(f"a column is given twice: {', '.join(head)}")
    data = {c: [] for c in head}
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(head):
            raise ScatterError(f"row {i}: {len(r)} values for {len(head)} columns")
        for c, v in zip(head, r):
            try:
                x = float(v)
            except ValueError:
                raise ScatterError(f"column {c!r}, row {i}: {v.strip()!r} is not a number") from None
            if not math.isfinite(x):
                raise ScatterError(f"column {c!r}, row {i}: {v.strip()!r} is not finite")
            data[c].append(x)
    if not data["hs"]:
        raise ScatterError("the scatter table has no rows")
    arr = {c: np.asarray(v, dtype=float) for c, v in data.items()}
    for c in ("hs", "tp"):
        bad = np.flatnonzero(arr[c] <= 0)
        if bad.size:
            raise ScatterError(f"column {c!r}, row {bad[0] + 2}: must be positive, got {arr[c][bad[0]]:g}")
    wcol = "probability" if has_p else "occurrences"
    w = arr[wcol]
    bad = np.flatnonzero(w < 0)
    if bad.size:
        raise ScatterError(f"column {wcol!r}, row {bad[0] + 2}: must be >= 0, got {w[bad[0]]:g}")
    if w.sum() <= 0:
        raise ScatterError(f"column {wcol!r}: the weights sum to zero")
    for c in INT_COLUMNS:
        if c in arr and np.any(arr[c] != np.round(arr[c])):
            raise ScatterError(f"column {c!r}: must hold whole numbers")
    extra = {c: arr[c] for c in head if c in SEA_COLUMNS}
    return Scatter(arr["hs"], arr["tp"], w / w.sum(), extra)


def make_cases(scatter: Scatter, headings, seeds: int, base_seed: int = 0) -> Cases:
    """Cells x headings x seeds, cell-major. Seed k of a case is base_seed + k (the template's
    `waves.seed` plus k), whatever cell or heading: a case's sea depends on its own values only."""
    heads = np.asarray(headings, dtype=float).ravel()
    c, h, s = np.meshgrid(np.arange(scatter.hs.size), np.arange(heads.size), np.arange(seeds), indexing="ij")
    c, h, s = c.ravel(), h.ravel(), s.ravel()
    return Cases(c, scatter.hs[c], scatter.tp[c], heads[h], base_seed + s,
                 scatter.weight[c] / (heads.size * seeds), {k: v[c] for k, v in scatter.extra.items()})


def case_values(cases: Cases, i: int) -> dict:
    """The [waves] values of case i."""
    v = {"hs": float(cases.hs[i]), "tp": float(cases.tp[i]), "heading": float(cases.heading[i]),
         "seed": int(cases.seed[i])}
    for k, x in cases.extra.items():
        v[k] = int(x[i]) if k in INT_COLUMNS else float(x[i])
    return v


_HEADER = re.compile(r"^\s*\[\s*waves\s*\]\s*(#.*)?$")
_ANY_HEADER = re.compile(r"^\s*\[")


def case_text(template_text: str, values: dict) -> str:
    """The template's TOML with the [waves] keys of `values` set (their lines replaced, in the
    table's place): a scene file that `jaxslosh run` runs as the case."""
    lines = template_text.splitlines()
    start = next((i for i, ln in enumerate(lines) if _HEADER.match(ln)), None)
    if start is None:
        raise SceneError("waves", "a campaign needs the scene's [waves] table (its sea template)")
    end = next((i for i in range(start + 1, len(lines)) if _ANY_HEADER.match(lines[i])), len(lines))
    keys = re.compile(r"^\s*(" + "|".join(map(re.escape, values)) + r")\s*=")
    body = [ln for ln in lines[start + 1:end] if not keys.match(ln)]
    new = [f"{k} = {v!r}" if isinstance(v, float) else f"{k} = {v}" for k, v in values.items()]
    return "\n".join(lines[:start + 1] + new + body + lines[end:]) + "\n"


def case_scene(template: Scene, values: dict, duration: Optional[float] = None) -> Scene:
    """The scene of a case (its text is case_text's; `duration` replaces the simulation's).

    The scene is read from the template's TOML mapping (parsed once per template, kept) with the
    case's [waves] keys and duration set: the mapping that parsing the case's text gives (floats
    written with repr read back exactly), without parsing its large hydrodynamic tables again for
    every case (two TOML parses a case took longer than drawing its sea)."""
    text = template.text
    base = _mapping(text)
    if duration is not None:
        if "simulation" not in base:
            raise SceneError("simulation", "a campaign needs the scene's [simulation] table")
        text = _set_duration(text, duration)
    text = case_text(text, values)
    mapping = dict(base)
    if duration is not None:
        mapping["simulation"] = {**base["simulation"], "duration": float(duration)}
    if not isinstance(base.get("waves"), dict):
        return parse_scene(tomllib.loads(text), text=text, path=template.path)
    waves = {k: v for k, v in base["waves"].items() if k not in values}
    mapping["waves"] = {**values, **waves}
    return parse_scene(mapping, text=text, path=template.path)


@functools.lru_cache(maxsize=4)
def _mapping(text: str) -> dict:
    """The template's parsed TOML (read only: a case's mapping copies the tables it changes)."""
    return tomllib.loads(text)


def _set_duration(text: str, duration: float) -> str:
    lines = text.splitlines()
    start = next(i for i, ln in enumerate(lines) if re.match(r"^\s*\[\s*simulation\s*\]", ln))
    end = next((i for i in range(start + 1, len(lines)) if _ANY_HEADER.match(lines[i])), len(lines))
    body = [ln for ln in lines[start + 1:end] if not re.match(r"^\s*duration\s*=", ln)]
    return "\n".join(lines[:start + 1] + [f"duration = {float(duration)!r}"] + body + lines[end:]) + "\n"


def sea_arrays(scene: Scene) -> tuple:
    """(omega (N,), amp (6, N) per unit Hs, phase (6, N), Hs, incident): the wave excitation the
    build of `scene` makes (assemble/seakeeping.py), as the arrays a batch of seas runs on (zero
    amplitudes where the scene has no linear excitation term); `incident` the components that the
    nonlinear hydrostatics integrate on the wetted hull, (k, amp per unit Hs, phase, cos heading,
    sin heading) each (N,) (assemble/hull.incident_waves), None for other scenes."""
    waves = scene.waves
    c = components(waves)
    X = linear_excitation_rao(scene, c)
    omega, amp, phase = excitation_arrays(waves, c, np.zeros((c.omega.size, 6)) if X is None else X)
    incident = None
    if hull_waves(scene):
        w = incident_waves(scene, {})
        incident = tuple(np.asarray(x) for x in (w.k, w.amp, w.phase, w.cb, w.sb))
    return np.asarray(omega), np.asarray(amp), np.asarray(phase), float(waves.hs), incident