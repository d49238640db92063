"""Measured against fitted time histories (`identify --plot`)."""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..fit.identify import FitResult
from ..fit.params import param_value
from ..fit.problem import as_result, channel_unit, channels_of
from ..run.simulate import simulate
from ..scene.types import Scene
from ..run.guard import finishing
from .results import figure


def plot_fit(scene: Scene, measured, fit_result: FitResult, out_png: Optional[str] = None, *, start: bool = True):
    """Measured against fitted time histories, one panel per channel that carries weight (and the
    start's history, dashed, when `start`). Writes `out_png` when given; returns the figure."""

    measured = as_result(measured)
    t_m = np.asarray(measured.time)
    T = float(t_m[-1])
    meas = {k: np.asarray(v) for k, v in channels_of(measured).items()}
    names = [k for k, w in fit_result.channels.items() if w > 0] or [
        k for k in ("roll", "pitch", "heave") if np.std(meas[k]) > 0]
    params_of = lambda vals: {k: param_value(scene, k, v) for k, v in vals.items()}  # noqa: E731
    fitted = simulate(scene, params=params_of(fit_result.values), duration=max(T, scene.simulation.dt), throw=False)
    ch_fit = {k: np.asarray(v) for k, v in channels_of(fitted).items()}
    ch_start = None
    if start and fit_result.start:
        r0 = simulate(scene, params=params_of(fit_result.start), duration=max(T, scene.simulation.dt), throw=False)
        ch_start = {k: np.asarray(v) for k, v in channels_of(r0).items()}
    t_f = np.asarray(fitted.time)

    if out_png is None:
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(len(names), 1, figsize=(9, 2.4 * len(names) + 0.6), sharex=True, squeeze=False)
    else:
        fig = figure(9, 2.4 * len(names) + 0.6)
        axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)
    units = {"rad": ("deg", np.degrees), "m": ("m", lambda x: x), "N": ("N", lambda x: x)}
    for ax, k in zip(axes[:, 0], names):
        unit, conv = units[channel_unit(k)]         # a body's roll in degrees too
        ax.plot(t_m, conv(meas[k]), ".", ms=3, color="k", alpha=0.35, label="measured")
        if ch_start is not None and k in ch_start:
            ax.plot(np.asarray(r0.time), conv(ch_start[k]), "--", lw=0.9, color="C1", label="start")
        if k in ch_fit:
            ax.plot(t_f, conv(ch_fit[k]), "-", lw=1.0, color="C0", label="fitted")
        ax.set_ylabel(f"{k} ({unit})")
        ax.legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    vals = ", ".join(f"{k.split('.')[-1]} = {format_value(v)}" for k, v in fit_result.values.items())
    quality = f"; {fit_result.quality}" if getattr(fit_result, "quality", "") else ""   # a poor fit says so
    fig.suptitle(f"identify ({fit_result.method}, {fit_result.iterations} iterations): {vals}{quality}", fontsize=9)
    fig.tight_layout()
    if out_png is not None:
        with finishing():           # Ctrl-C meanwhile: the figure whole, then exit 130 (run/guard.py)
            fig.savefig(out_png, dpi=110)
    return fig


def format_value(v):
    return f"{v:.5g}" if isinstance(v, float) else "[" + ", ".join(f"{x:.5g}" for x in v) + "]"
