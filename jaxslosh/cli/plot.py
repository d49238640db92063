"""`jaxslosh plot`: time histories of a result, its free surface, an animation."""
from __future__ import annotations

import os

from ..io.result import load_result
from ..plot.results import plot_result
from ..plot.surface import animate_free_surface, plot_free_surface
from .common import EXIT_OK, InputError, positive


def add_parsers(sub):
    pl = sub.add_parser("plot", help="time histories of a result: roll, pitch, heave and every probe")
    pl.add_argument("result")
    pl.add_argument("-o", "--output", help="figure file (default: the result's name with .png)")
    pl.add_argument("--surface", metavar="FIG", help="also draw the deformed free surface at a few instants to FIG")
    pl.add_argument("--animate", metavar="GIF", help="also write an animated GIF of the tanks and their free surface")
    pl.add_argument("--scale", type=float, default=1.0,
                    help="magnify liquid displacements in --surface and --animate (default 1)")
    pl.add_argument("--fps", type=float, default=10.0, help="--animate: frames per second (default 10)")
    pl.add_argument("--every", type=int, help="--animate: show every n-th saved frame (default: at most 100 frames)")


def cmd_plot(a):
    if not os.path.exists(a.result):
        raise InputError(f"{a.result}: no such file")
    positive("fps", a.fps)
    positive("every", a.every)
    for flag, path in (("--surface", a.surface), ("--animate", a.animate)):
        d = os.path.dirname(os.path.abspath(path)) if path else None
        if d is not None and not os.path.isdir(d):
            raise InputError(f"{flag}: the folder {d} does not exist")
    if a.animate and not a.animate.lower().endswith(".gif"):
        raise InputError(f"--animate: writes a GIF, the file name must end in .gif, got {a.animate!r}")
    out = a.output or os.path.splitext(a.result)[0] + ".png"
    try:
        r = load_result(a.result)
    except (OSError, ValueError) as e:
        raise InputError(f"{a.result}: not a readable jaxslosh result ({e})")
    for flag, path in (("--surface", a.surface), ("--animate", a.animate)):
        if path and not r.tanks:
            raise InputError(f"{flag}: {a.result} holds no liquid fields (a scene with tanks, run without --no-fields)")
    plot_result(r, out)
    print(f"wrote {out}")
    if a.surface:
        plot_free_surface(r, a.surface, scale=a.scale)
        print(f"wrote {a.surface}")
    if a.animate:
        n = animate_free_surface(r, a.animate, scale=a.scale, fps=a.fps, every=a.every)
        print(f"wrote {a.animate} ({n} frames)")
    return EXIT_OK
