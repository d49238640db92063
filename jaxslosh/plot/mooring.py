"""The figure of `jaxslosh mooring -o`: each line's shape in its vertical plane at the equilibrium,
and the offset curve (restoring force and the most loaded line's tension)."""
from __future__ import annotations

import numpy as np

from .results import figure


def plot_mooring(r, out: str, title: str = ""):
    """`r`: a mooring.statics.MooringAnalysis."""
    fig = figure(11, 4.8)
    ax = fig.add_axes([0.07, 0.12, 0.4, 0.76])
    for line, (x, z) in zip(r.lines, r.shapes):
        ax.plot(x, z, label=f"{line['name']}: {line['fairlead_tension'] / 1e3:.4g} kN")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("horizontal distance from the anchor (m)")
    ax.set_ylabel("height above the anchor (m)")
    ax.set_title("lines at the equilibrium", fontsize=10)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    bx = fig.add_axes([0.57, 0.12, 0.34, 0.76])
    bx.plot(r.offsets, np.asarray(r.restoring) / 1e3, color="C0", marker=".")
    bx.set_xlabel(f"offset along {np.degrees(r.direction):g} deg (m)")
    bx.set_ylabel("restoring force (kN)", color="C0")
    cx = bx.twinx()
    cx.plot(r.offsets, np.asarray(r.max_tension) / 1e3, color="C1", ls="--", marker=".")
    cx.set_ylabel("most loaded line's fairlead tension (kN)", color="C1")
    bx.grid(alpha=0.3)
    bx.set_title("offset curve", fontsize=10)
    fig.suptitle(title or "mooring", fontsize=11)
    fig.savefig(out, dpi=100)
