"""`jaxslosh identify SCENE --data MEASURED.h5 --fit KEY[,KEY...] [-o FIT.json]`."""
from __future__ import annotations

import math
import os
import sys

from ..fit.identify import METHODS, identify
from ..fit.params import fit_keys
from ..fit.quality import data_scene_mismatch
from ..io.result import ResultFileError, load_result
from ..plot.fit import format_value, plot_fit
from ..scene.types import SceneError
from .common import COMMANDS, EXIT_NUMERICAL, EXIT_OK, InputError, figure_file, load, output_folder, setup_jax


def add_parsers(subparsers):
    """Add the `identify` subcommand to the `jaxslosh` sub-parsers; returns its parser."""
    p = subparsers.add_parser("identify", help=COMMANDS["identify"][1])
    p.add_argument("scene")
    p.add_argument("--data", required=True, metavar="MEASURED.h5", help="the measured result file")
    p.add_argument("--fit", required=True, metavar="KEY[,KEY...]",
                   help="dotted scene keys to fit, comma-separated, e.g. "
                        "vessel.hydrostatics.gm_t,vessel.hydrostatics.gm_l, or vessel.hull.kg (a mesh hull: "
                        "vessel.hull.cog) with the nonlinear hydrostatics (the implied GM0 is printed too)")
    p.add_argument("-o", "--output", metavar="FIT.json",
                   help="the fit as JSON (default: the scene's name with _fit.json, here)")
    p.add_argument("--method", default="gauss-newton", choices=METHODS, help="optimiser (default gauss-newton)")
    p.add_argument("--max-iter", type=int, default=50, dest="max_iter", help="iterations at most (default 50)")
    p.add_argument("--start", metavar="KEY=VALUE[,...]", help="start values (default: the scene's values)")
    p.add_argument("--noise", metavar="CHANNEL=STD[,...]",
                   help="the measurement noise of channels (roll, pitch, heave, probes.NAME, bodies.NAME.roll, "
                        "..., connections.NAME; standard deviations in the channel's units, rad, m or N): "
                        "weight 1 / STD, with which the standard errors are exact for independent Gaussian noise")
    p.add_argument("--weights", metavar="CHANNEL=W[,...]",
                   help="weights of channels (0 leaves one out); channels named by neither --noise nor --weights "
                        "keep the default 1 / std of the measured signal")
    p.add_argument("--plot", metavar="FIG.png", help="also draw measured against fitted time histories")
    p.add_argument("--data-scene", default="check", choices=("check", "ignore"), dest="data_scene",
                   help="when the data file carries a scene that differs from SCENE (besides the fitted keys): "
                        "check (default) refuses with exit 2, ignore fits anyway")
    return p


def _split_keys(text):
    return [k.strip() for k in str(text).split(",") if k.strip()]


def _channel_weights(a) -> dict:
    """{channel: weight} of --noise (1 / STD) and --weights; InputError naming the flag and the item."""
    weights = {}
    for flag, text in (("--noise", getattr(a, "noise", None)), ("--weights", getattr(a, "weights", None))):
        for item in _split_keys(text or ""):
            k, sep, v = item.partition("=")
            k = k.strip()
            try:
                x = float(v)
            except ValueError:
                x = None
            if not sep or not k or x is None:
                raise InputError(f"{flag}: expected CHANNEL=VALUE, got {item!r}")
            if k in weights:
                raise InputError(f"{flag}: channel {k} is given twice (in --noise and --weights together)")
            if flag == "--noise":
                if not (math.isfinite(x) and x > 0):
                    raise InputError(f"{flag}: {k}: the noise's standard deviation must be finite and > 0, got {v}")
                x = 1.0 / x
            elif not (math.isfinite(x) and x >= 0):
                raise InputError(f"{flag}: {k}: a weight must be finite and >= 0, got {v}")
            weights[k] = (x, flag)
    return weights


def cmd_identify(a) -> int:
    """`jaxslosh identify`: returns the exit status; bad input raises jaxslosh.cli.InputError."""


    method = getattr(a, "method", None) or "gauss-newton"
    data_scene = getattr(a, "data_scene", None) or "check"
    if data_scene not in ("check", "ignore"):
        raise InputError(f"--data-scene: unknown choice {data_scene!r} (choose from check, ignore)")
    if method not in METHODS:
        raise InputError(f"--method: unknown method {method!r} (choose from {', '.join(METHODS)})")
    max_iter = getattr(a, "max_iter", None)
    max_iter = 50 if max_iter is None else int(max_iter)
    if max_iter < 0:
        raise InputError(f"--max-iter: must be >= 0, got {max_iter}")
    keys = _split_keys(a.fit or "")
    if not keys:
        raise InputError("--fit: give at least one dotted key, e.g. vessel.hydrostatics.gm_t")
    if not os.path.exists(a.scene):
        raise InputError(f"{a.scene}: no such scene file")
    if not a.data or not os.path.exists(a.data):
        raise InputError(f"--data: {a.data}: no such file")
    out = getattr(a, "output", None) or os.path.splitext(os.path.basename(a.scene))[0] + "_fit.json"
    if getattr(a, "plot", None):
        a.plot = figure_file("--plot", a.plot)
    for flag, path in (("-o", out), ("--plot", getattr(a, "plot", None))):
        output_folder(flag, path)
        if path and os.path.abspath(path) in (os.path.abspath(a.scene), os.path.abspath(a.data)):
            raise InputError(f"{flag}: {path} is an input of this fit; write the output elsewhere")
    x0 = {}
    for item in _split_keys(getattr(a, "start", None) or ""):
        k, sep, v = item.partition("=")
        try:
            x0[k.strip()] = float(v)
        except ValueError:
            raise InputError(f"--start: expected KEY=VALUE, got {item!r}")
        if not sep:
            raise InputError(f"--start: expected KEY=VALUE, got {item!r}")

    weights = _channel_weights(a)

    setup_jax()
    scene = load(a.scene)            # SceneError (exit 2, naming the key) for a bad scene
    try:
        canon = fit_keys(scene, keys)
    except SceneError as e:
        raise InputError(f"--fit: {e}")
    try:
        measured = load_result(a.data)
    except ResultFileError as e:         # one line naming the file and the fault
        raise InputError(f"--data: {e}") from None
    except (OSError, ValueError, KeyError) as e:
        msg = str(e).replace("\n", " ")
        raise InputError(f"--data: {a.data}: not a jaxslosh result file ({msg})")
    # data made with another scene: the fitted keys would absorb the difference and report it as a
    # tight, converged fit; refuse before compiling anything unless told to fit anyway
    mismatch = data_scene_mismatch(scene, measured, canon)
    if mismatch and data_scene == "check":
        raise InputError(f"--data: {a.data}: {mismatch}; to fit anyway: --data-scene ignore")
    if mismatch:
        print(f"jaxslosh identify: note: {mismatch}; fitting anyway (--data-scene ignore)", file=sys.stderr)
    try:
        fr = identify(scene, measured, keys, method=method, max_iter=max_iter, x0=x0 or None, data_scene="ignore",
                      weights={k: w for k, (w, _) in weights.items()} or None)
    except SceneError as e:
        msg = str(e).replace("\n", " ")
        flag = "--start" if ("the start" in msg or "given in x0" in msg) else "--data" if e.key == "measured" else None
        if e.key.startswith("weights.") and e.key[len("weights."):] in weights:
            flag = weights[e.key[len("weights."):]][1]
        raise InputError(f"{flag}: {msg}" if flag else msg)
    if not fr.loss_history or not math.isfinite(fr.loss_history[0]):
        print(f"jaxslosh identify: numerical failure: {fr.message}", file=sys.stderr)
        return EXIT_NUMERICAL
    width = max(len(k) for k in list(fr.values) + list(fr.implied))
    for k, v in fr.values.items():
        s = fr.standard_errors[k]
        print(f"{k:<{width}} = {format_value(v)} +- {format_value(s)}   (start {format_value(fr.start[k])})")
    for k, v in fr.implied.items():       # not fitted: what the fitted values imply (GM0 = KM - KG)
        s = fr.implied_standard_errors[k]
        print(f"{k:<{width}} = {format_value(v)} +- {format_value(s)}   (implied: KM - KG of the hull at rest)")
    for k, spread in fr.no_signal.items():     # weight 0 by default: said, so that no one wonders
        unit = "rad" if k in ("roll", "pitch") else "m"
        print(f"{k}: left out (weight 0): its spread, {spread:.3g} {unit}, is round-off, no signal to fit "
              f"(--weights {k}=W weighs it anyway)")
    print(f"{fr.method}: {fr.status} after {fr.iterations} iterations ({fr.evaluations} simulations, "
          f"{fr.wall_time:.1f} s); loss {fr.loss_history[0]:.4g} -> {fr.loss_history[-1]:.4g} ({fr.message})")
    fr.to_json(out)
    print(f"wrote {out}")
    if getattr(a, "plot", None):
        plot_fit(scene, measured, fr, a.plot)
        print(f"wrote {a.plot}")
    if not fr.converged:
        print(f"warning: the fit did not converge ({fr.message})", file=sys.stderr)
    if fr.quality:
        ratio = ", ".join(f"{k} {v:.3g}" for k, v in fr.residual_to_noise.items())
        print(f"warning: {fr.quality}: the model leaves much of the record unexplained (residual / noise "
              f"estimated from the data: {ratio}); the standard errors assume the model is right: check the "
              f"scene against the measurement", file=sys.stderr)
    return EXIT_OK
