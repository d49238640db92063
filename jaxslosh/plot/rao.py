"""The RAO figure: amplitude and phase over frequency of each rigid dof and each probe's vertical
displacement, one line per heading."""
from __future__ import annotations

import numpy as np

from ..scene.types import DOFS
from ..run.guard import finishing
from .results import figure, scene_title

UNITS = ("m/m", "m/m", "m/m", "deg/m", "deg/m", "deg/m")


def plot_rao(r, out: str, title: str = ""):
    """`r`: an analysis.rao.RAO or an io.rao.RaoData. Rotations are drawn in degrees per metre;
    phases in degrees, of x = Re(X e^{i w t}) for eta = cos(w t) at the COG. Probes: the vertical
    component of their displacement (the free surface's elevation where they sit on it)."""
    channels = [(f"{d} ({u})", r.vessel[:, :, j] * (180.0 / np.pi if j >= 3 else 1.0))
                for j, (d, u) in enumerate(zip(DOFS, UNITS))]
    channels += [(f"probe {name} vertical (m/m)", v[:, :, 2]) for name, v in r.probes.items()]
    rows = len(channels)
    fig = figure(10, 1.9 * rows + 0.8)
    ax = np.atleast_2d(fig.subplots(rows, 2, sharex=True))
    w = np.asarray(r.frequency)
    for k, (label, x) in enumerate(channels):
        for h, beta in enumerate(np.asarray(r.heading)):
            name = f"heading {np.degrees(beta):.0f} deg"
            ax[k, 0].plot(w, np.abs(x[:, h]), label=name)
            ax[k, 1].plot(w, np.degrees(np.angle(x[:, h])), label=name)
        ax[k, 0].set_ylabel(label, fontsize=8)
        ax[k, 1].set_ylim(-185, 185)
        ax[k, 1].set_yticks([-180, -90, 0, 90, 180])
    ax[0, 0].set_title("amplitude")
    ax[0, 1].set_title("phase (deg)")
    ax[0, 0].legend(fontsize=7)
    ax[-1, 0].set_xlabel("frequency (rad/s)")
    ax[-1, 1].set_xlabel("frequency (rad/s)")
    fig.suptitle(title or f"RAOs: {scene_title(r.scene_text, 'jaxslosh scene')}", fontsize=10)
    fig.tight_layout()
    with finishing():           # Ctrl-C meanwhile: the figure whole, then exit 130 (run/guard.py)
        fig.savefig(out, dpi=100)
    return fig
