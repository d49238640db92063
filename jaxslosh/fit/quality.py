"""What `identify` checks around a fit: that the record was made with the scene being fitted
(result files carry their scene's TOML), and how well the fitted model explains the record.

The data's scene
    A result file's `scene` attribute holds the TOML of the scene that made it (empty for data from
    elsewhere). Fitting a scene to data made with another one answers a different question than it
    seems to: the fitted keys soak up whatever else differs and the standard errors, which assume
    the model is right, come out tight anyway. `data_scene_mismatch` names every value and every
    part of the structure (tanks, probes, meshes, dt, save_every, ...) that differs, apart from the
    fitted keys and those that do not change the model (scene/compare.py HARMLESS: the duration,
    the Newton solver's settings). The data's text is loaded like a scene file (defaults filled in),
    so a value written out in one scene and left at its default in the other is no difference.
    A caveat: `simulate(params=...)` and the command line's --dt/--duration do not rewrite the
    scene text a result carries, so a record made with overrides shows its scene file's values.

Goodness of fit
    Per channel c, on the weighted residual r_c = w_c (model_c - measured_c) at the returned
    parameters: R^2_c = 1 - sum r_c^2 / sum (w_c (measured_c - mean))^2, the share of the measured
    signal's variance the model explains (the weight cancels; with the default weights 1 / std the
    loss is the mean over channels of 1 - R^2_c). A low R^2 alone does not make a fit poor: noisy
    data cap it at 1 - noise^2 / variance; nor does a high one make it good: a clean record fitted
    1 % off keeps R^2 at 0.99. So the noise is estimated from the record itself, from
    its second differences (white noise of standard deviation s gives differences of standard
    deviation s sqrt(6); a signal sampled well above its frequencies adds little; the median
    absolute deviation ignores a few outliers), and a channel is a poor fit when R^2_c < R2_POOR
    and its residual's RMS exceeds NOISE_FACTOR times that noise: the model leaves out structure,
    not noise; and whatever R^2, when its residual exceeds NOISE_FAR times the noise. On smooth,
    noise-free records the estimate is the signal's own curvature (larger than the noise, so the
    test errs towards "good"); on sparse ones it may be zero and the test is R^2 alone.
"""
from __future__ import annotations

import math

import numpy as np

from ..io.result import Result
from ..scene.compare import differences, show_value
from ..scene.load import load_scene
from ..scene.types import Scene, SceneError
from .params import implied_keys

R2_POOR = 0.9          # below: the model explains less than 90 % of the channel's variance
NOISE_FACTOR = 3.0     # ... and the residual is this many times the noise estimated from the record
NOISE_FAR = 10.0       # a residual this many times the noise is poor whatever R^2: a fit 1 % off leaves
#                        R^2 at 0.99 on a clean record, its residual far above the noise floor
MAX_LISTED = 8         # differences named in the message, the rest counted


def data_scene_mismatch(scene: Scene, measured: Result, fitted) -> str:
    """"" when the record carries no scene text or one that equals `scene` apart from the `fitted`
    keys (canonical form) and harmless ones; else one line naming each difference and both values."""
    text = getattr(measured, "scene_text", "") or ""
    if not text.strip():
        return ""
    try:
        theirs = load_scene(text if "\n" in text else text + "\n")
    except SceneError as e:
        msg = str(e).replace("\n", " ")
        return f"the scene stored with the data does not load, so it cannot be compared with this one ({msg})"
    diff = differences(scene, theirs, ignore=tuple(fitted) + implied_keys(fitted))
    if not diff:
        return ""
    items = [f"{k} = {show_value(theirs_v)} in the data's scene, {show_value(ours_v)} here"
             for k, ours_v, theirs_v in diff[:MAX_LISTED]]
    more = f"; and {len(diff) - MAX_LISTED} more" if len(diff) > MAX_LISTED else ""
    fit_note = f" (fitted: {', '.join(fitted)})" if fitted else ""
    return f"the data was made with another scene: {'; '.join(items)}{more}{fit_note}"


def noise_level(x) -> float:
    """The standard deviation of white noise on a uniformly sampled signal, from its second
    differences (median absolute deviation, scaled for a Gaussian); 0 for fewer than 5 samples."""
    x = np.asarray(x, dtype=float)
    if x.size < 5:
        return 0.0
    d2 = x[2:] - 2.0 * x[1:-1] + x[:-2]
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def goodness(res, measured, weights, names) -> tuple[dict, dict, str]:
    """From the weighted residual `res` ((channels x samples) flattened, the Problem's order) and
    the measured channels (channels, samples): ({channel: R^2}, {channel: residual RMS / noise}, the
    quality: "" or "poor fit: R^2 0.12 on roll")."""
    meas = np.asarray(measured, dtype=float)
    r = np.asarray(res, dtype=float).reshape(meas.shape)
    r2, ratio, poor = {}, {}, []
    for c, name in enumerate(names):
        w = float(weights[c])
        sst = float(np.sum((w * (meas[c] - meas[c].mean())) ** 2))
        r2[name] = 1.0 - float(np.sum(r[c] ** 2)) / sst if sst > 0 else float("nan")
        rms = float(np.sqrt(np.mean(r[c] ** 2))) / w
        s = noise_level(meas[c])
        ratio[name] = rms / s if s > 0 else (math.inf if rms > 0 else 0.0)
        if r2[name] < R2_POOR and ratio[name] > NOISE_FACTOR:
            poor.append(f"{r2[name]:.2f} on {name}")
        elif s > 0 and ratio[name] > NOISE_FAR:
            poor.append(f"{r2[name]:.4f} on {name} (residual {ratio[name]:.3g} times the noise)")
    return r2, ratio, ("poor fit: R^2 " + ", ".join(poor)) if poor else ""
