"""The campaign figure: the significant response over the scatter (hs, tp) per heading and
channel, the operability per heading on a polar plot, and one case's response spectra."""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..campaign.stats import operability
from .results import figure, scene_title


def plot_campaign(c, out: str, limits: Optional[dict] = None, case: Optional[int] = None, title: str = ""):
    """`c`: an io.campaign.Campaign. `limits` {channel: limit} (default: the file's); `case`: the
    case whose spectra are drawn (default: the first finished one)."""
    chans = list(c.statistics)
    heads = np.asarray(c.cases["heading"], dtype=float)
    uniq = np.unique(heads)
    ok = np.array([s == "ok" for s in c.status])
    rows = len(chans) + 1
    cols = max(len(uniq), 2)
    fig = figure(3.2 * cols + 0.6, 2.6 * rows + 0.8)
    gs = fig.add_gridspec(rows, cols)
    hs_all, tp_all = np.asarray(c.cases["hs"], dtype=float), np.asarray(c.cases["tp"], dtype=float)
    for r, ch in enumerate(chans):
        sig = np.asarray(c.statistics[ch]["significant"], dtype=float)
        scale, unit = (180.0 / np.pi, "deg") if ch in ("roll", "pitch") else (1.0, "m")
        finite = sig[ok & np.isfinite(sig)] * scale
        vmax = float(finite.max()) if finite.size else 1.0
        for k, b in enumerate(uniq):
            ax = fig.add_subplot(gs[r, k])
            sel = ok & (heads == b)
            hu, tu = np.unique(hs_all[sel]), np.unique(tp_all[sel])
            grid = np.full((hu.size, tu.size), np.nan)
            for i, h in enumerate(hu):
                for j, t in enumerate(tu):
                    m = sel & (hs_all == h) & (tp_all == t)
                    if m.any():        # the seeds' mean
                        grid[i, j] = np.nanmean(sig[m]) * scale
            if grid.size:
                im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis", vmin=0.0, vmax=vmax,
                               interpolation="nearest")
                if grid.size <= 64:
                    for i in range(hu.size):
                        for j in range(tu.size):
                            if np.isfinite(grid[i, j]):
                                ax.text(j, i, f"{grid[i, j]:.2g}", ha="center", va="center", fontsize=6, color="w")
                ax.set_xticks(range(tu.size), [f"{t:g}" for t in tu])
                ax.set_yticks(range(hu.size), [f"{h:g}" for h in hu])
                fig.colorbar(im, ax=ax, fraction=0.05)
            ax.set_title(f"{ch} significant ({unit}), heading {np.degrees(b):.0f} deg", fontsize=8)
            ax.set_xlabel("tp (s)", fontsize=7)
            ax.set_ylabel("hs (m)", fontsize=7)
            ax.tick_params(labelsize=7)
    lim = dict(limits if limits is not None else {})
    axp = fig.add_subplot(gs[rows - 1, 0], projection="polar")
    if lim and ok.any():
        dur = float(c.attrs.get("record_duration", 1.0))
        per = [operability(_subset(c.statistics, heads == b), np.asarray(c.cases["weight"]) * (heads == b),
                           ok & (heads == b), lim, dur)["operability"] for b in uniq]
        th = np.append(uniq, uniq[0]) if uniq.size > 1 else uniq
        axp.plot(th, np.append(per, per[0]) if uniq.size > 1 else per, "o-")
        axp.set_ylim(0, 100)
        axp.set_title("operability (%) per heading: " + ", ".join(f"{k} <= {v:g}" for k, v in lim.items()),
                      fontsize=7)
    else:
        axp.set_title("operability: no --limits given", fontsize=7)
    axp.tick_params(labelsize=6)
    k = case if case is not None else (int(np.flatnonzero(ok)[0]) if ok.any() else 0)
    axs = fig.add_subplot(gs[rows - 1, 1:])
    w = np.asarray(c.frequency)
    for ch in chans:
        s = np.asarray(c.spectra[ch][k], dtype=float)
        if np.isfinite(s).all() and s.max() > 0:
            axs.semilogy(w, s, label=ch)
    axs.set_xlabel("frequency (rad/s)", fontsize=7)
    axs.set_ylabel("S (unit^2 s/rad)", fontsize=7)
    axs.set_title(f"response spectra of case {k}: hs {hs_all[k]:g} m, tp {tp_all[k]:g} s, heading "
                  f"{np.degrees(heads[k]):.0f} deg, seed {int(c.cases['seed'][k])} ({c.status[k]})", fontsize=8)
    axs.legend(fontsize=7)
    axs.tick_params(labelsize=7)
    fig.suptitle(title or f"campaign: {scene_title(c.scene_text, 'jaxslosh scene')}", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    return fig


def _subset(stats, sel):
    return {ch: {k: np.where(sel, v, np.nan) for k, v in d.items()} for ch, d in stats.items()}
