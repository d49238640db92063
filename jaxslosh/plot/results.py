"""Time histories of a result: roll, pitch, heave and every probe, with the [[bodies]]' roll, pitch
and heave and the [[connections]]' forces; of a sweep, every run overlaid."""
from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..scene.load import tomllib
from ..run.guard import finishing

#: a sweep's figure names each run in its legend up to this many runs (more would hide the curves)
MAX_LEGEND = 12


def figure(width: float, height: float) -> Figure:
    """A figure on its own Agg canvas: no pyplot, so the caller's backend (a notebook's) is left alone."""
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def scene_title(scene_text: str, default: str = "jaxslosh result") -> str:
    """The scene's `title` from the TOML text a result file keeps (attribute `scene`), else `default`."""
    try:
        title = tomllib.loads(scene_text or "").get("title")
    except (tomllib.TOMLDecodeError, TypeError, ValueError):
        return default
    return title.strip() if isinstance(title, str) and title.strip() else default


def _axes(r, links: bool = False, bodies=()):
    """The panels: angles, heave, the probes' (where any), one of angles per body in `bodies` (a
    sweep's), the connections' forces (`links`)."""
    rows = 2 + (1 if r.probes else 0) + len(bodies) + (1 if links else 0)
    fig = figure(9, 2.6 * rows)
    ax = fig.subplots(rows, 1, sharex=True)
    ax[0].set_ylabel("angle (deg)")
    ax[1].set_ylabel("heave (m)")
    if r.probes:
        ax[2].set_ylabel("vertical displacement (m)")
    for k, name in enumerate(bodies):
        ax[2 + bool(r.probes) + k].set_ylabel(f"{name}: roll (solid),\npitch (dashed) (deg)")
    if links:
        ax[-1].set_ylabel("connection force (kN)")
    ax[-1].set_xlabel("time (s)")
    return fig, ax


def _finish(fig, title: str, out: str) -> Figure:
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    with finishing():           # Ctrl-C meanwhile: the figure whole, then exit 130 (run/guard.py)
        fig.savefig(out, dpi=110)
    return fig


def plot_result(r, out: str) -> Figure:
    """Time histories: roll, pitch, heave and the vertical displacement of every probe, titled with
    the scene's title (and the status of a run that failed); each [[bodies]] body's roll and pitch
    beside the vessel's (named), its heave (its COG's offset from rest) beside the vessel's, and a
    panel of the [[connections]]' forces (positive when they pull). Returns the figure written."""
    t = np.asarray(r.time)
    rpy = np.asarray(r.vessel.roll_pitch_yaw)
    bodies, links = r.bodies or {}, r.connections or {}
    fig, ax = _axes(r, bool(links))
    ax[0].plot(t, np.degrees(rpy[:, 0]), label="roll")
    ax[0].plot(t, np.degrees(rpy[:, 1]), label="pitch")
    ax[1].plot(t, np.asarray(r.vessel.position)[:, 2], color="C2", label="vessel" if bodies else None)
    for i, (name, b) in enumerate(bodies.items()):        # the vessel's colours first, then one per body
        c = f"C{(i + 3) % 10}"
        brpy = np.degrees(np.asarray(b.roll_pitch_yaw))
        ax[0].plot(t, brpy[:, 0], color=c, label=f"{name} roll")
        ax[0].plot(t, brpy[:, 1], color=c, ls="--", label=f"{name} pitch")
        ax[1].plot(t, np.asarray(b.position)[:, 2], color=c, label=name)
    ax[0].legend(loc="upper right", fontsize=7 if bodies else None)
    if bodies:
        ax[1].legend(loc="upper right", fontsize=7)
    if r.probes:
        for name, p in r.probes.items():
            ax[2].plot(t, np.asarray(p.displacement)[:, 2], label=f"probe {name}")
        ax[2].legend(loc="upper right")
    for name, c in links.items():
        ax[-1].plot(t, 1e-3 * np.asarray(c.force), label=name)
    if links:
        ax[-1].legend(loc="upper right", fontsize=7)
    status = "" if r.status == "ok" else f"  [{r.status}]"
    return _finish(fig, scene_title(r.scene_text) + status, out)


def _short_keys(keys):
    """The swept keys by their last dotted part where that names them uniquely (gm_t, not
    vessel.hydrostatics.gm_t), else in full."""
    last = [k.rsplit(".", 1)[-1] for k in keys]
    return [s if last.count(s) == 1 else k for s, k in zip(last, keys)]


def plot_sweep(params: dict, r, statuses, out: str, scene_text: str = "") -> Figure:
    """A sweep file's runs overlaid (one colour per run, the same in every panel): roll (solid) and
    pitch (dashed), heave, and each probe's vertical displacement (one line style per probe); each
    [[bodies]] body's roll and pitch in a panel of its own and its heave beside the vessel's (one line
    style per body), and the [[connections]]' forces (one line style per connection); the legend
    names each run's swept values (up to MAX_LEGEND runs), a failed run is marked. Returns the figure
    written."""
    keys = list(params)
    names = _short_keys(keys)
    t = np.asarray(r.time)
    rpy = np.degrees(np.asarray(r.vessel.roll_pitch_yaw))
    z = np.asarray(r.vessel.position)[..., 2]
    runs = t.shape[0]
    bodies, links = r.bodies or {}, r.connections or {}
    fig, ax = _axes(r, bool(links), tuple(bodies))
    first = 2 + bool(r.probes)         # the bodies' panels
    # up to ten runs the default colour cycle (easiest told apart); more: a colour map in run order
    cmap = colormaps["viridis"] if runs > 10 else None
    styles = ["-", "--", ":", "-."]
    for i in range(runs):
        c = cmap(i / max(1, runs - 1)) if cmap is not None else f"C{i % 10}"
        label = ", ".join(f"{n} = {params[k][i]:.4g}" for n, k in zip(names, keys))
        if statuses[i] != "ok":
            label += " [failed]"
        ax[0].plot(t[i], rpy[i, :, 0], color=c, label=label if runs <= MAX_LEGEND else None)
        ax[0].plot(t[i], rpy[i, :, 1], color=c, ls="--", lw=0.9)
        ax[1].plot(t[i], z[i], color=c)
        for j, (pname, p) in enumerate(r.probes.items()):
            ax[2].plot(t[i], np.asarray(p.displacement)[i, :, 2], color=c, ls=styles[j % len(styles)],
                       label=f"probe {pname}" if i == 0 else None)
        for k, (bname, b) in enumerate(bodies.items()):
            brpy = np.degrees(np.asarray(b.roll_pitch_yaw)[i])
            ax[first + k].plot(t[i], brpy[:, 0], color=c)
            ax[first + k].plot(t[i], brpy[:, 1], color=c, ls="--", lw=0.9)
            ax[1].plot(t[i], np.asarray(b.position)[i, :, 2], color=c, ls=styles[(k + 1) % len(styles)],
                       label=bname if i == 0 else None)
        for k, (lname, link) in enumerate(links.items()):
            ax[-1].plot(t[i], 1e-3 * np.asarray(link.force)[i], color=c, ls=styles[k % len(styles)],
                        label=lname if i == 0 else None)
    ax[0].set_ylabel("roll (solid), pitch (dashed) (deg)")
    if runs <= MAX_LEGEND:             # beside the panel: a legend of many runs would cover their curves
        ax[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, borderaxespad=0.0)
    if r.probes:
        ax[2].legend(loc="upper right", fontsize=7)
    if bodies:                         # the vessel's heave solid, each body's in its style
        ax[1].lines[0].set_label("vessel")
        ax[1].legend(loc="upper right", fontsize=7)
    if links:
        ax[-1].legend(loc="upper right", fontsize=7)
    ranges = ", ".join(f"{n} {np.min(params[k]):.4g} to {np.max(params[k]):.4g}" for n, k in zip(names, keys))
    failed = sum(s != "ok" for s in statuses)
    return _finish(fig, f"{scene_title(scene_text, 'jaxslosh sweep')}: {runs} runs ({ranges})"
            + (f"  [{failed} failed]" if failed else ""), out)
