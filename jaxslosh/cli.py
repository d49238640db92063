"""The `jaxslosh` command (SPEC section 2). Exit status: 0 done, 2 bad input, 3 numerical failure."""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

EXIT_OK, EXIT_INPUT, EXIT_NUMERICAL = 0, 2, 3


class InputError(Exception):
    """Bad command-line input: one line on stderr, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage block
        raise InputError(f"{self.prog}: {message}")


def _parser():
    p = _Parser(prog="jaxslosh", description="Floating vessels carrying sloshing liquid (Gonzalez & Park 2013).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    r = sub.add_parser("run", help="simulate a scene, write the result file")
    r.add_argument("scene")
    r.add_argument("-o", "--output", help="result file (default: the scene's name with .h5, here)")
    r.add_argument("--duration", type=float, help="override simulation.duration (s)")
    r.add_argument("--dt", type=float, help="override simulation.dt (s)")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.add_argument("--no-fields", action="store_true", help="do not store the liquid displacement fields")
    c = sub.add_parser("check", help="validate a scene; list what it will simulate")
    c.add_argument("scene")
    pl = sub.add_parser("plot", help="time histories of a result: roll, pitch, heave and every probe")
    pl.add_argument("result")
    pl.add_argument("-o", "--output", help="figure file (default: the result's name with .png)")
    pl.add_argument("--surface", metavar="FIG", help="also draw the deformed free surface at a few instants to FIG")
    pl.add_argument("--animate", metavar="GIF", help="also write an animated GIF of the tanks and their free surface")
    pl.add_argument("--scale", type=float, default=1.0,
                    help="magnify liquid displacements in --surface and --animate (default 1)")
    pl.add_argument("--fps", type=float, default=10.0, help="--animate: frames per second (default 10)")
    pl.add_argument("--every", type=int, help="--animate: show every n-th saved frame (default: at most 100 frames)")
    m = sub.add_parser("modes", help="natural frequencies of a tank's liquid, or of a flexible structure, with the "
                                     "vessel held fixed")
    m.add_argument("scene")
    g = m.add_mutually_exclusive_group()
    g.add_argument("--tank")
    g.add_argument("--structure")
    m.add_argument("-n", type=int, default=10, help="number of modes (default 10)")
    m.add_argument("--json", action="store_true", help="print one JSON object")
    from .identify import add_identify_parser
    add_identify_parser(sub)
    from .sweep import add_sweep_parser
    add_sweep_parser(sub)
    hy = sub.add_parser("hydro", help="hull hydrostatics and hydrodynamic tables from Capytaine, as scene TOML")
    hy.add_argument("scene", help="a scene with a [vessel.hull] table")
    hy.add_argument("-o", "--output", help="write the TOML tables here (default: print them)")
    hy.add_argument("--frequencies", default="0.1:2.5:25", help="LOW:HIGH:COUNT rad/s (default 0.1:2.5:25)")
    hy.add_argument("--headings", help="comma-separated rad (default: the scene's wave heading, or 0)")
    hy.add_argument("--panel-size", type=float, help="panel size of the box mesh, m")
    return p


def _enable_x64():
    import jax
    jax.config.update("jax_enable_x64", True)


def _load(path):
    from .scene import load_scene
    scene = load_scene(path)
    for w in scene.warnings:
        print(f"warning: {w}", file=sys.stderr)
    return scene


def _positive(name, value):
    if value is not None and not (value > 0):
        raise InputError(f"--{name}: must be positive, got {value}")


def cmd_run(a):
    _positive("duration", a.duration)
    _positive("dt", a.dt)
    scene = _load(a.scene)
    dt = a.dt if a.dt is not None else scene.simulation.dt
    duration = a.duration if a.duration is not None else scene.simulation.duration
    if dt > duration:
        raise InputError(f"--dt: {dt} s is longer than the duration {duration} s")
    out = a.output or os.path.splitext(os.path.basename(a.scene))[0] + ".h5"
    d = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(d):
        raise InputError(f"-o: the folder {d} does not exist")
    _enable_x64()
    from .run import run_to_file
    t0 = time.perf_counter()
    status, steps, wall = run_to_file(scene, out, duration=a.duration, dt=a.dt,
                                      progress=not a.no_progress, save_fields=False if a.no_fields else None)
    total = time.perf_counter() - t0
    if status != "ok":
        print(f"jaxslosh: numerical failure at {status}; {steps} steps kept in {out}", file=sys.stderr)
        return EXIT_NUMERICAL
    print(f"done: {steps} steps to t = {steps * dt:.6g} s in {total:.2f} s wall, compilation included "
          f"({wall:.2f} s after the first chunk) -> {out}")
    return EXIT_OK


def cmd_check(a):
    scene = _load(a.scene)
    from .scene import describe
    print(describe(scene))
    from .effects import effects_summary
    print(effects_summary(scene))
    return EXIT_OK


def cmd_plot(a):
    if not os.path.exists(a.result):
        raise InputError(f"{a.result}: no such file")
    _positive("fps", a.fps)
    _positive("every", a.every)
    for flag, path in (("--surface", a.surface), ("--animate", a.animate)):
        d = os.path.dirname(os.path.abspath(path)) if path else None
        if d is not None and not os.path.isdir(d):
            raise InputError(f"{flag}: the folder {d} does not exist")
    if a.animate and not a.animate.lower().endswith(".gif"):
        raise InputError(f"--animate: writes a GIF, the file name must end in .gif, got {a.animate!r}")
    out = a.output or os.path.splitext(a.result)[0] + ".png"
    from .plot import plot_result
    from .result import load_result
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
        from .plot import plot_free_surface
        plot_free_surface(r, a.surface, scale=a.scale)
        print(f"wrote {a.surface}")
    if a.animate:
        from .plot import animate_free_surface
        n = animate_free_surface(r, a.animate, scale=a.scale, fps=a.fps, every=a.every)
        print(f"wrote {a.animate} ({n} frames)")
    return EXIT_OK


def cmd_modes(a):
    if a.n < 1:
        raise InputError(f"-n: must be at least 1, got {a.n}")
    scene = _load(a.scene)
    _enable_x64()
    if a.structure is not None:
        return _structure_modes(scene, a)
    from .analysis import sloshing_modes
    tank = a.tank
    if tank is None:
        if not scene.tanks:
            raise InputError(f"{a.scene}: the scene has no tanks")
        tank = scene.tanks[0].name
    modes = sloshing_modes(scene, tank=tank, n=a.n)
    if a.json:
        print(json.dumps({"tank": tank, "omega": [float(w) for w in modes.omega], "kind": list(modes.kind),
                          "free_surface_share": [float(s) for s in modes.free_surface_share]}))
    else:
        print(f"liquid modes of tank {tank!r} (vessel held fixed):")
        print(f"{'#':>3} {'omega rad/s':>12} {'f Hz':>10} {'period s':>10} {'surface share':>14}  kind")
        import math
        for i, (w, k, s) in enumerate(zip(modes.omega, modes.kind, modes.free_surface_share)):
            f = w / (2 * math.pi)
            print(f"{i + 1:>3} {w:12.5f} {f:10.5f} {1 / f if f > 0 else float('inf'):10.4f} {s:14.3f}  {k}")
    return EXIT_OK


def _structure_modes(scene, a):
    from .analysis import structure_modes
    names = [s.name for s in scene.structures]
    if a.structure not in names:
        raise InputError(f"--structure: no structure named {a.structure!r} (structures: {', '.join(names) or 'none'})")
    modes = structure_modes(scene, a.structure, n=a.n)
    if a.json:
        print(json.dumps({"structure": a.structure, "omega": [float(w) for w in modes.omega], "kind": list(modes.kind),
                          "shares": {k: [float(x) for x in v] for k, v in modes.shares.items()}}))
        return EXIT_OK
    import math
    print(f"modes of structure {a.structure!r} (held at its attachment, vessel fixed):")
    print(f"{'#':>3} {'omega rad/s':>12} {'f Hz':>10} {'period s':>10} {'share':>6}  kind")
    for i, (w, k) in enumerate(zip(modes.omega, modes.kind)):
        f = w / (2 * math.pi)
        print(f"{i + 1:>3} {w:12.5f} {f:10.5f} {1 / f if f > 0 else float('inf'):10.4f} {modes.shares[k][i]:6.3f}  {k}")
    return EXIT_OK


def cmd_hydro(a):
    """Capytaine's hydrostatics and tables for the scene's hull, printed as the [vessel.hydrostatics]
    and [vessel.hydrodynamics] tables of a scene (paste them in, drop [vessel.hull]'s capytaine)."""
    scene = _load(a.scene)
    hull = scene.vessel.hull
    if hull is None:
        raise InputError(f"{a.scene}: the scene has no [vessel.hull] table")
    try:
        lo, hi, n = a.frequencies.split(":")
        lo, hi, n = float(lo), float(hi), int(n)
    except ValueError:
        raise InputError(f"--frequencies: expected LOW:HIGH:COUNT, got {a.frequencies!r}") from None
    if not (0 < lo < hi and n >= 4):
        raise InputError(f"--frequencies: need 0 < LOW < HIGH and COUNT >= 4, got {a.frequencies!r}")
    if a.headings:
        try:
            heads = tuple(float(x) for x in a.headings.split(","))
        except ValueError:
            raise InputError(f"--headings: expected comma-separated numbers, got {a.headings!r}") from None
    else:
        heads = (scene.waves.heading if scene.waves is not None else 0.0,)
    from .hydrodynamics import have_capytaine, hull_hydrodynamics, to_toml, CAPYTAINE_MISSING
    if not have_capytaine():
        raise InputError(f"hydro: {CAPYTAINE_MISSING}")
    import numpy as np
    hd = scene.vessel.hydrodynamics
    data = hull_hydrodynamics(hull, rho=scene.environment.water_density, g=scene.environment.gravity,
                              depth=scene.waves.depth if scene.waves is not None else None,
                              frequencies=tuple(np.linspace(lo, hi, n)), headings=heads,
                              panel_size=a.panel_size, base_dir=hd.base_dir if hd is not None else os.path.dirname(os.path.abspath(a.scene)))
    text = (f"# Capytaine {__import__('capytaine').__version__}: hull of {a.scene}, about the COG; "
            f"BM_T {data['bm_t']:.6g} m, BM_L {data['bm_l']:.6g} m\n" + to_toml(data))
    if a.output:
        with open(a.output, "w") as f:
            f.write(text)
        print(f"wrote {a.output}")
    else:
        print(text, end="")
    return EXIT_OK


def main(argv=None) -> int:
    from .scene_types import SceneError
    try:
        a = _parser().parse_args(argv)
        from .identify import cmd_identify
        from .sweep import cmd_sweep
        return {"run": cmd_run, "check": cmd_check, "plot": cmd_plot, "modes": cmd_modes,
                "identify": cmd_identify, "sweep": cmd_sweep, "hydro": cmd_hydro}[a.command](a)
    except (InputError, SceneError) as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
