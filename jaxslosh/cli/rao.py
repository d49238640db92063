"""`jaxslosh rao`: the scene's RAOs from its linearisation about rest (docs/guide/frequency-domain.md)."""
from __future__ import annotations

import os
import sys
import time

import numpy as np

from ..analysis.rao import across_tank_warnings, contact_warnings, rao
from ..io.output import OutputError, check_output
from ..io.rao import RAO_FORMAT, write_rao
from ..plot.rao import plot_rao
from ..scene.campaign import not_radians
from ..scene.types import DOFS
from .common import COMMANDS, EXIT_OK, InputError, figure_file, load, setup_jax


def add_parsers(sub):
    r = sub.add_parser("rao", help=COMMANDS["rao"][1])
    r.add_argument("scene")
    r.add_argument("--frequencies", help="LOW:HIGH:COUNT or a list W1,W2,... rad/s (default: the radiation "
                                         "tables' range, else 0.1:4:200)")
    r.add_argument("--headings", help="comma-separated rad, the direction the waves travel to (default: the "
                                      "scene's wave heading, else the excitation tables', else 0,pi/2,pi)")
    r.add_argument("-o", "--output", help="RAO file (default: the scene's name with _rao.h5)")
    r.add_argument("--plot", help="a figure of amplitudes and phases (PNG)")


def parse_frequencies(text):
    """LOW:HIGH:COUNT, or a list W1,W2,... -> an array (rad/s), or None."""
    if text is None:
        return None
    if ":" not in text:
        try:
            w = np.array([float(x) for x in text.split(",")])
        except ValueError:
            raise InputError(f"--frequencies: expected LOW:HIGH:COUNT or W1,W2,... (rad/s), got {text!r}") from None
        if not (np.all(np.isfinite(w)) and np.all(w > 0)):
            raise InputError(f"--frequencies: must be positive finite numbers (rad/s), got {text!r}")
        return w
    try:
        lo, hi, n = text.split(":")
        lo, hi, n = float(lo), float(hi), int(n)
    except ValueError:
        raise InputError(f"--frequencies: expected LOW:HIGH:COUNT, got {text!r}") from None
    if not (0 < lo <= hi and np.isfinite(hi) and n >= 1 and (n == 1 or lo < hi)):
        raise InputError(f"--frequencies: need 0 < LOW < HIGH and COUNT >= 1, got {text!r}")
    return np.linspace(lo, hi, n)


def parse_headings(text):
    if text is None:
        return None
    try:
        heads = np.array([float(x) for x in text.split(",")])
    except ValueError:
        raise InputError(f"--headings: expected comma-separated numbers (rad), got {text!r}") from None
    if not np.all(np.isfinite(heads)):
        raise InputError(f"--headings: must be finite numbers (rad), got {text!r}")
    bad = not_radians(heads.tolist())
    if bad:
        raise InputError(f"--headings: {bad}")
    return heads


def checked_output(flag, path, inputs, formats):
    try:
        return check_output(path, inputs, formats) is not None
    except OutputError as e:
        raise InputError(f"{flag}: {e.strerror}") from None


def cmd_rao(a):
    w = parse_frequencies(a.frequencies)
    heads = parse_headings(a.headings)
    scene = load(a.scene)
    out = a.output or os.path.splitext(os.path.basename(a.scene))[0] + "_rao.h5"
    replaced = checked_output("-o", out, (a.scene,), (RAO_FORMAT,))
    a.plot = figure_file("--plot", a.plot)
    setup_jax()
    t0 = time.perf_counter()
    r = rao(scene, w, heads)
    wall = time.perf_counter() - t0
    write_rao(out, r.frequency, r.heading, r.vessel, r.probes, scene.text, r.bodies)
    if replaced:
        print(f"note: replaced {out}", file=sys.stderr)
    for line in across_tank_warnings(scene, r.heading) + contact_warnings(scene):
        print(f"warning: {line}", file=sys.stderr)
    print(f"{'heading deg':>11} {'channel':>14} {'peak amplitude':>15} {'at rad/s':>9}")
    for h, beta in enumerate(r.heading):
        rows = [(d, r.vessel[:, h, j] * (180 / np.pi if j >= 3 else 1.0), "deg/m" if j >= 3 else "m/m")
                for j, d in enumerate(DOFS)]
        rows += [(f"probe {k} z", v[:, h, 2], "m/m") for k, v in r.probes.items()]
        rows += [(f"{k} {d}", v[:, h, j] * (180 / np.pi if j >= 3 else 1.0), "deg/m" if j >= 3 else "m/m")
                 for k, v in (r.bodies or {}).items() for j, d in enumerate(DOFS)]
        for name, x, unit in rows:
            i = int(np.argmax(np.abs(x)))
            print(f"{np.degrees(beta):11.1f} {name:>14} {abs(x[i]):11.4g} {unit:<5} {r.frequency[i]:7.4f}")
    if a.plot:
        plot_rao(r, a.plot)
    print(f"done: RAOs at {r.frequency.size} frequencies x {r.heading.size} headings in {wall:.1f} s -> {out}"
          + (f", {a.plot}" if a.plot else ""))
    return EXIT_OK
