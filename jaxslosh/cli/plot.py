"""`jaxslosh plot`: time histories of a result (or of a sweep file's runs overlaid), its free
surface, an animation (its frames counted on stderr as they are written)."""
from __future__ import annotations

import os

from ..io.campaign import CAMPAIGN_FORMAT, file_limits, load_campaign
from ..io.paraview import no_fields_why
from ..io.result import FORMAT, ResultFileError, file_format, load_result, open_h5
from ..io.sweep import SWEEP_FORMAT, load_sweep
from ..plot.campaign import plot_campaign
from ..plot.results import plot_result, plot_sweep
from ..plot.surface import animate_free_surface, plot_free_surface
from ..run.progress import Progress, wanted
from .campaign import parse_limits
from .common import COMMANDS, EXIT_OK, InputError, figure_file, read, output_folder, positive


def add_parsers(sub):
    pl = sub.add_parser("plot", help=COMMANDS["plot"][1])
    pl.add_argument("result")
    pl.add_argument("-o", "--output", help="figure file: .png, .pdf, .svg, ... (default: the result's name with "
                                           ".png; a name without an extension gets .png)")
    pl.add_argument("--surface", metavar="FIG", help="also draw the deformed free surface at a few instants to FIG "
                                                     "(an image name, as -o)")
    pl.add_argument("--animate", metavar="GIF", help="also write an animated GIF of the tanks and their free surface")
    pl.add_argument("--scale", type=float, default=1.0,
                    help="magnify liquid displacements in --surface and --animate (default 1)")
    pl.add_argument("--fps", type=float, default=10.0, help="--animate: frames per second (default 10)")
    pl.add_argument("--every", type=int, help="--animate: show every n-th saved frame (default: at most 100 frames)")
    pl.add_argument("--case", type=int, help="a campaign file: the case whose response spectra are drawn")
    pl.add_argument("--limits", metavar="KEY=VALUE,...",
                    help="a campaign file: limits of its operability plot (default: the campaign's own)")
    pl.add_argument("--no-progress", action="store_true",
                    help="--animate: no progress on stderr (drawn only on a terminal unless JAXSLOSH_PROGRESS=1)")


def _format(path) -> str:
    try:
        with open_h5(path) as f:
            return file_format(f, path)
    except ResultFileError as e:
        raise InputError(str(e)) from None


def cmd_plot(a):
    fmt = _format(a.result)
    positive("scale", a.scale)
    positive("fps", a.fps)
    positive("every", a.every)
    out = figure_file("-o", a.output or os.path.splitext(a.result)[0] + ".png")
    a.surface = figure_file("--surface", a.surface)
    if a.animate and not a.animate.lower().endswith(".gif"):
        raise InputError(f"--animate: writes a GIF, the file name must end in .gif, got {a.animate!r}")
    output_folder("--animate", a.animate)
    if fmt == SWEEP_FORMAT:
        return _plot_sweep(a, out)
    if fmt == CAMPAIGN_FORMAT:
        return _plot_campaign(a, out)
    for flag in ("case", "limits"):
        if getattr(a, flag) is not None:
            raise InputError(f"--{flag}: only for a campaign file ({CAMPAIGN_FORMAT!r}); {a.result} is {fmt!r}")
    if fmt != FORMAT:
        raise InputError(f"{a.result}: not a jaxslosh result file "
                         f"({'format ' + repr(fmt) if fmt else 'no format attribute'})")
    r = read(load_result, a.result)
    for flag, path in (("--surface", a.surface), ("--animate", a.animate)):
        if path and not r.tanks:
            raise InputError(f"{flag}: {a.result} holds no liquid fields: {no_fields_why(r)}")
    plot_result(r, out)
    print(f"wrote {out}")
    if a.surface:
        plot_free_surface(r, a.surface, scale=a.scale)
        print(f"wrote {a.surface}")
    if a.animate:
        bar = Progress(enabled=wanted(a.no_progress))
        bar.phase("frames", "writing the animation", unit="frame")
        try:
            n = animate_free_surface(r, a.animate, scale=a.scale, fps=a.fps, every=a.every,
                                     progress=lambda done, total: bar.update(done, total))
        finally:
            bar.close()
        print(f"wrote {a.animate} ({n} frames)")
    return EXIT_OK


def _plot_sweep(a, out):
    """A sweep file: its runs overlaid. Its runs keep no liquid meshes, so no surface figures."""
    for flag, path in (("--surface", a.surface), ("--animate", a.animate)):
        if path:
            raise InputError(f"{flag}: {a.result} is a sweep file (format {SWEEP_FORMAT!r}), which keeps no liquid "
                             f"meshes; run one of its scenes with `jaxslosh run` to draw its free surface")
    sw = read(load_sweep, a.result)
    plot_sweep(sw.params, sw.result, sw.statuses, out, sw.scene_text)
    print(f"wrote {out} ({len(sw.statuses)} runs of a sweep)")
    return EXIT_OK


def _plot_campaign(a, out):
    """A campaign file: significant responses over the scatter per heading, operability, spectra."""
    for flag, path in (("--surface", a.surface), ("--animate", a.animate)):
        if path:
            raise InputError(f"{flag}: {a.result} is a campaign file, which keeps statistics, not liquid fields")
    c = read(load_campaign, a.result)
    n = len(c.status)
    if a.case is not None and not 0 <= a.case < n:
        raise InputError(f"--case: {a.case} is not a case of {a.result} (0 to {n - 1})")
    limits = parse_limits(a.limits, list(c.statistics)) if a.limits is not None else file_limits(c)
    plot_campaign(c, out, limits=limits, case=a.case)
    print(f"wrote {out} ({n} cases of a campaign)")
    return EXIT_OK
