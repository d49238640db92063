"""The GZ figure of `jaxslosh stability -o`: both curves, GM0's tangent and the IS Code criteria."""
from __future__ import annotations

import numpy as np

from ..run.guard import finishing
from .results import figure


def plot_stability(s, out: str, title: str = ""):
    """`s`: an analysis.stability.Stability. Heels in degrees, levers in m."""
    fig = figure(9, 5.5)
    ax = fig.add_axes([0.08, 0.11, 0.6, 0.8])
    deg = np.degrees(np.asarray(s.angle))
    linear = getattr(s, "model", "hull") == "linear"
    ax.plot(deg, s.gz, color="C0", label="vessel, linear hydrostatics" if linear else "liquids level (b)")
    if not linear:
        ax.plot(deg, s.gz_frozen, color="C1", ls="--", label="liquids frozen (a)")
    for i, b in enumerate(getattr(s, "bodies", {}).values()):      # [[bodies]]: their linear or hull curves
        ax.plot(np.degrees(np.asarray(b.angle)), b.gz, color=f"C{i + 4}", lw=1.2,
                label=f"{b.name}, {b['model']} (GM0 = {b.gm0:.3f} m)")
    # GM0 as the tangent at the origin, drawn to one radian
    ax.plot([0, np.degrees(1.0)], [0, s.gm0], color="C0", lw=0.7, ls=":", label=f"GM0 = {s.gm0:.3f} m at 1 rad")
    ax.axhline(0.0, color="k", lw=0.6)
    if s.criteria:
        eps = 1e-9                          # degrees from radians: 30 may come back as 29.999...
        sel = (deg >= -eps) & (deg <= 40 + eps)
        ax.fill_between(deg[sel], 0, np.asarray(s.gz)[sel], where=deg[sel] <= 30 + eps, color="C0", alpha=0.12,
                        label="areas 0-30, 30-40 deg")
        ax.fill_between(deg[sel], 0, np.asarray(s.gz)[sel], where=deg[sel] >= 30 - eps, color="C0", alpha=0.25)
        ax.plot([30, max(deg.max(), 30)], [0.20, 0.20], color="C3", lw=0.8, label="GZ 0.20 m at >= 30 deg")
        ax.axvline(25, color="C3", lw=0.8, ls=":", label="max GZ at >= 25 deg")
        lines = [f"{'pass' if c.passed else 'FAIL'}  {c.name}\n      {c.value:.4f} (>= {c.limit:.4g})"
                 for c in s.criteria]
        fig.text(0.7, 0.9, "IS Code 2008 A 2.2\n(liquids level)\n\n" + "\n".join(lines), va="top", fontsize=7.5,
                 family="monospace")
    if s.vanishing_angle is not None:
        ax.axvline(np.degrees(s.vanishing_angle), color="k", lw=0.7, ls="--")
        ax.annotate(f"vanishing {np.degrees(s.vanishing_angle):.1f} deg", (np.degrees(s.vanishing_angle), 0),
                    xytext=(-4, 8), textcoords="offset points", fontsize=8, ha="right")
    ax.set_xlabel(f"heel about the {s.axis} axis (deg)")
    ax.set_ylabel("GZ (m)")
    fig.legend(*ax.get_legend_handles_labels(), fontsize=7, loc="lower left", bbox_to_anchor=(0.69, 0.02))
    ax.grid(alpha=0.3)
    ax.set_title(title or "righting lever", fontsize=10)
    with finishing():           # Ctrl-C meanwhile: the figure whole, then exit 130 (run/guard.py)
        fig.savefig(out, dpi=100)
    return fig
