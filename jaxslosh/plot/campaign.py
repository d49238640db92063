"""The campaign figure: the significant response over the scatter (hs, tp) per heading and
channel, the operability per heading on a polar plot, and one case's response spectra (one axis
per unit). Failed cases are drawn as such and count as not operable, as in the summary line and
the file (campaign/stats.operability)."""
from __future__ import annotations

import re
from typing import Optional

import numpy as np

from ..campaign.stats import operability
from ..io.campaign import PENDING
from ..run.guard import finishing
from ..scene.campaign import unit as channel_unit
from .results import figure, scene_title

#: the spectra are drawn where some channel's density is above this share of its peak (and a
#: quarter beyond), down to SPECTRUM_FLOOR of the largest: below, Welch's window leakage and
#: round-off, not response
SPECTRUM_SHOWN, SPECTRUM_FLOOR = 1e-3, 1e-5


def _groups(chans):
    """The spectra's axes: angles and displacements as always, forces (lines, connections) on a
    third axis where there are any (on the displacements' they would flatten them by 1e10)."""
    groups = [("rad^2 s/rad", [ch for ch in chans if channel_unit(ch) == "rad"]),
              ("m^2 s/rad", [ch for ch in chans if channel_unit(ch) == "m"])]
    forces = [ch for ch in chans if channel_unit(ch) == "N"]
    return groups + ([("N^2 s/rad", forces)] if forces else [])


def case_states(status):
    """(ok, failed) boolean arrays of a campaign's statuses ("pending": neither)."""
    ok = np.array([s == "ok" for s in status], dtype=bool)
    failed = np.array([s not in ("ok", PENDING) for s in status], dtype=bool)
    return ok, failed


def heading_operability(c, limits: dict) -> tuple:
    """(headings (rad), operability (%) per heading, failed share (%) of the judged weight) of a
    campaign file: what the polar plot draws, failed cases counted as not operable."""
    heads = np.asarray(c.cases["heading"], dtype=float)
    uniq = np.unique(heads)
    ok, failed = case_states(c.status)
    dur = float(c.attrs.get("record_duration", 1.0))
    weight = np.asarray(c.cases["weight"], dtype=float)
    per = [operability(_subset(c.statistics, heads == b), weight * (heads == b), ok & (heads == b), limits, dur,
                       failed=failed & (heads == b))["operability"] for b in uniq]
    share = operability(c.statistics, weight, ok, limits, dur, failed=failed)["failed"]
    return uniq, np.asarray(per, dtype=float), share


def _label_colour(cmap, value: float) -> str:
    """Black on light cells, white on dark ones (the cell's relative luminance, ITU-R BT.709)."""
    r, g, b, _ = cmap(value)
    return "k" if 0.2126 * r + 0.7152 * g + 0.0722 * b > 0.5 else "w"


def _title(c, heads) -> str:
    """The campaign's own sea states, then the template scene's title without a parenthesis that
    gives the template's own sea (Hs, Tp): each case has its own."""
    hs, tp = np.asarray(c.cases["hs"], dtype=float), np.asarray(c.cases["tp"], dtype=float)
    seeds = np.unique(np.asarray(c.cases["seed"])).size

    def span(x):
        return f"{x.min():g}" if x.min() == x.max() else f"{x.min():g} to {x.max():g}"
    title = scene_title(c.scene_text, "")
    title = re.sub(r"\s*\([^()]*\b[Hh][Ss]\b[^()]*\)", "", title).strip()
    first = (f"campaign of {hs.size} cases: Hs {span(hs)} m, Tp {span(tp)} s, {np.unique(heads).size} heading(s), "
             f"{seeds} seed(s)")
    return first + (f"\ntemplate scene: {title}" if title else "")


def plot_campaign(c, out: str, limits: Optional[dict] = None, case: Optional[int] = None, title: str = ""):
    """`c`: an io.campaign.Campaign. `limits` {channel: limit} (default: none); `case`: the case
    whose spectra are drawn (default: the first finished one)."""
    chans = list(c.statistics)
    heads = np.asarray(c.cases["heading"], dtype=float)
    uniq = np.unique(heads)
    ok, failed = case_states(c.status)
    rows = len(chans) + 1
    cols = max(len(uniq), 3)
    fig = figure(3.2 * cols + 0.6, 2.6 * rows + 1.0)
    fig.set_layout_engine("constrained")
    gs = fig.add_gridspec(rows, cols)
    hs_all, tp_all = np.asarray(c.cases["hs"], dtype=float), np.asarray(c.cases["tp"], dtype=float)
    from matplotlib import colormaps
    cmap = colormaps["viridis"]
    for r, ch in enumerate(chans):
        sig = np.asarray(c.statistics[ch]["significant"], dtype=float)
        scale, unit = (180.0 / np.pi, "deg") if channel_unit(ch) == "rad" else (1.0, channel_unit(ch))
        finite = sig[ok & np.isfinite(sig)] * scale
        vmax = float(finite.max()) if finite.size and finite.max() > 0 else 1.0
        for k, b in enumerate(uniq):
            ax = fig.add_subplot(gs[r, k])
            here = heads == b
            hu, tu = np.unique(hs_all[here]), np.unique(tp_all[here])
            grid = np.full((hu.size, tu.size), np.nan)
            lost = np.zeros((hu.size, tu.size), dtype=int)      # failed cases of the cell
            for i, h in enumerate(hu):
                for j, t in enumerate(tu):
                    m = here & (hs_all == h) & (tp_all == t)
                    if (m & ok).any():       # the finished seeds' mean
                        grid[i, j] = np.nanmean(sig[m & ok]) * scale
                    lost[i, j] = int(np.count_nonzero(m & failed))
            im = ax.imshow(grid, origin="lower", aspect="auto", cmap=cmap, vmin=0.0, vmax=vmax,
                           interpolation="nearest")
            if grid.size <= 64:
                for i in range(hu.size):
                    for j in range(tu.size):
                        if np.isfinite(grid[i, j]):
                            text = f"{grid[i, j]:.2g}" + ("*" if lost[i, j] else "")
                            ax.text(j, i, text, ha="center", va="center", fontsize=6,
                                    color=_label_colour(cmap, grid[i, j] / vmax))
                        elif lost[i, j]:
                            ax.text(j, i, "failed", ha="center", va="center", fontsize=6, color="tab:red")
            ax.set_xticks(range(tu.size), [f"{t:g}" for t in tu])
            ax.set_yticks(range(hu.size), [f"{h:g}" for h in hu])
            fig.colorbar(im, ax=ax, fraction=0.05)
            ax.set_title(f"{ch} significant ({unit}), heading {np.degrees(b):.0f} deg", fontsize=8)
            ax.set_xlabel("tp (s)", fontsize=7)
            ax.set_ylabel("hs (m)", fontsize=7)
            ax.tick_params(labelsize=7)
    if failed.any():
        fig.supxlabel("failed: every case of the cell failed; *: some of its seeds failed (the mean is of the others)",
                      fontsize=7, color="tab:red")
    lim = dict(limits if limits is not None else {})
    groups = _groups(chans)
    bottom = gs[rows - 1, :].subgridspec(1, 1 + len(groups), width_ratios=[1] + [1.6] * len(groups))
    axp = fig.add_subplot(bottom[0, 0], projection="polar")
    if lim and (ok | failed).any():
        th, per, share = heading_operability(c, lim)
        closed = th.size > 1
        axp.plot(np.append(th, th[0]) if closed else th, np.append(per, per[0]) if closed else per, "o-")
        axp.set_ylim(0, 100)
        note = f"\nfailed cases ({share:.3g} % of the weight)\ncount as not operable" if share > 0 else ""
        axp.set_title("operability (%) per heading\n" + ", ".join(f"{k} <= {v:g}" for k, v in lim.items()) + note,
                      fontsize=7)
    else:
        axp.set_title("operability: no limits given" if not lim else "operability: no case finished yet", fontsize=7)
    axp.tick_params(labelsize=6)
    _spectra(fig, bottom, c, groups, ok, case, heads, hs_all, tp_all)
    fig.suptitle(title or _title(c, heads), fontsize=10)
    with finishing():           # Ctrl-C meanwhile: the figure whole, then exit 130 (run/guard.py)
        fig.savefig(out, dpi=90)
    return fig


def _spectra(fig, bottom, c, groups, ok, case, heads, hs_all, tp_all):
    """The response spectra of one case, each unit's channels (_groups) on their own axes, over
    the frequencies where they hold energy; the frequency resolution in the title."""
    w = np.asarray(c.frequency, dtype=float)
    axes = [fig.add_subplot(bottom[0, 1 + g]) for g in range(len(groups))]
    if not ok.any() and case is None:
        for ax in axes:
            ax.text(0.5, 0.5, "no finished case: no spectra", ha="center", va="center", fontsize=8,
                    transform=ax.transAxes)
            ax.set_xticks([])
            ax.set_yticks([])
        return
    k = case if case is not None else int(np.flatnonzero(ok)[0])
    dw = float(w[1] - w[0]) if w.size > 1 else float("nan")
    for ax, (unit, names) in zip(axes, groups):
        spectra = {ch: np.asarray(c.spectra[ch][k], dtype=float) for ch in names}
        spectra = {ch: s for ch, s in spectra.items() if np.isfinite(s).all() and s.max() > 0}
        top = max((float(s.max()) for s in spectra.values()), default=0.0)
        drawn, reach = 0, 0.0
        for ch, s in spectra.items():
            if s.max() > SPECTRUM_FLOOR * top:       # a channel at round-off level is no response
                ax.semilogy(w, s, label=ch)
                reach = max(reach, float(w[np.flatnonzero(s >= SPECTRUM_SHOWN * s.max())[-1]]))
                drawn += 1
        if drawn:
            ax.set_xlim(0.0, min(float(w[-1]), 1.25 * reach + 2 * dw))
            ax.set_ylim(SPECTRUM_FLOOR * top, 2.0 * top)
            ax.legend(fontsize=7)
        else:
            ax.text(0.5, 0.5, "no response" if names else "no channel", ha="center", va="center", fontsize=8,
                    transform=ax.transAxes)
        ax.set_xlabel("frequency (rad/s)", fontsize=7)
        ax.set_ylabel(f"S ({unit})", fontsize=7)
        ax.tick_params(labelsize=7)
    axes[0].set_title(f"response spectra of case {k} ({c.status[k][:40]}):\nhs {hs_all[k]:g} m, tp {tp_all[k]:g} s, "
                      f"heading {np.degrees(heads[k]):.0f} deg, seed {int(c.cases['seed'][k])}", fontsize=7)
    if w.size > 1:
        seg = 2 * np.pi / dw
        axes[1].set_title(f"resolution {dw:.3g} rad/s\n(Welch segments of {seg:.3g} s: a longer record refines it)",
                          fontsize=7)


def _subset(stats, sel):
    return {ch: {k: np.where(sel, v, np.nan) for k, v in d.items()} for ch, d in stats.items()}
