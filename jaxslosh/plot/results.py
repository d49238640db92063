"""Time histories of a result: roll, pitch, heave and every probe."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def figure(width: float, height: float) -> Figure:
    """A figure on its own Agg canvas: no pyplot, so the caller's backend (a notebook's) is left alone."""
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def plot_result(r, out: str) -> None:
    """Time histories: roll, pitch, heave and the vertical displacement of every probe."""
    t = np.asarray(r.time)
    rpy = np.asarray(r.vessel.roll_pitch_yaw)
    z = np.asarray(r.vessel.position)[:, 2]
    n_probe = len(r.probes)
    rows = 2 + (1 if n_probe else 0)
    fig = figure(9, 2.6 * rows)
    ax = fig.subplots(rows, 1, sharex=True)
    ax[0].plot(t, np.degrees(rpy[:, 0]), label="roll")
    ax[0].plot(t, np.degrees(rpy[:, 1]), label="pitch")
    ax[0].set_ylabel("angle (deg)")
    ax[0].legend(loc="upper right")
    ax[1].plot(t, z, color="C2")
    ax[1].set_ylabel("heave (m)")
    if n_probe:
        for name, p in r.probes.items():
            ax[2].plot(t, np.asarray(p.displacement)[:, 2], label=f"probe {name}")
        ax[2].set_ylabel("vertical displacement (m)")
        ax[2].legend(loc="upper right")
    ax[-1].set_xlabel("time (s)")
    status = "" if r.status == "ok" else f"  [{r.status}]"
    fig.suptitle(f"jaxslosh result{status}", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
