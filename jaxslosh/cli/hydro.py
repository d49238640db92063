"""`jaxslosh hydro`: Capytaine's hydrostatics and tables of the scene's hull, as scene TOML."""
from __future__ import annotations

import os

import numpy as np

from ..hydro.capytaine import (CAPYTAINE_MISSING, capytaine_dataset, capytaine_version, have_capytaine,
                               hull_hydrodynamics, save_capytaine_dataset, to_toml)
from ..run.progress import Progress, wanted
from ..scene.campaign import not_radians
from .common import COMMANDS, EXIT_OK, InputError, load, output_folder


def add_parsers(sub):
    hy = sub.add_parser("hydro", help=COMMANDS["hydro"][1])
    hy.add_argument("scene", help="a scene with a [vessel.hull] table")
    hy.add_argument("-o", "--output", help="write the TOML tables here (default: print them)")
    hy.add_argument("--frequencies", default="0.1:2.5:25", help="LOW:HIGH:COUNT rad/s (default 0.1:2.5:25)")
    hy.add_argument("--headings", help="comma-separated rad (default: the scene's wave heading, or 0)")
    hy.add_argument("--panel-size", type=float, help="panel size of the box mesh, m")
    hy.add_argument("--netcdf", metavar="OUT.nc",
                    help="also write Capytaine's dataset as Capytaine exports it (NetCDF), for "
                         "[vessel.hydrodynamics] file = ... or other tools")
    hy.add_argument("--no-progress", action="store_true", help="no progress display on stderr")


def cmd_hydro(a):
    """Capytaine's hydrostatics and tables for the scene's hull, printed as the [vessel.hydrostatics]
    and [vessel.hydrodynamics] tables of a scene (paste them in, drop [vessel.hull]'s capytaine)."""
    scene = load(a.scene)
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
        bad = not_radians(heads)
        if bad:
            raise InputError(f"--headings: {bad}")
    else:
        heads = (scene.waves.heading if scene.waves is not None else 0.0,)
    if not have_capytaine():
        raise InputError(f"hydro: {CAPYTAINE_MISSING}")
    output_folder("-o", a.output, scene=a.scene)
    if a.netcdf:
        output_folder("--netcdf", a.netcdf, scene=a.scene)
    hd = scene.vessel.hydrodynamics
    kw = dict(rho=scene.environment.water_density, g=scene.environment.gravity,
              depth=scene.waves.depth if scene.waves is not None else None, frequencies=tuple(np.linspace(lo, hi, n)),
              headings=heads, panel_size=a.panel_size,
              base_dir=hd.base_dir if hd is not None else os.path.dirname(os.path.abspath(a.scene)))
    bar = Progress(enabled=wanted(a.no_progress))     # Capytaine's solve: per frequency, on stderr
    try:
        data = hull_hydrodynamics(hull, progress=bar, **kw)
    finally:
        bar.close()
    if a.netcdf:       # the same (cached) solve, as Capytaine's own dataset
        save_capytaine_dataset(capytaine_dataset(hull, **kw), a.netcdf)
        print(f"wrote {a.netcdf}")
    text = (f"# Capytaine {capytaine_version()}: hull of {a.scene}, about the COG; "
            f"BM_T {data['bm_t']:.6g} m, BM_L {data['bm_l']:.6g} m\n" + to_toml(data))
    if a.output:       # a temporary name beside the target, renamed when complete
        tmp = os.path.join(os.path.dirname(os.path.abspath(a.output)), f".{os.path.basename(a.output)}.part")
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, a.output)
        print(f"wrote {a.output}")
    else:
        print(text, end="")
    return EXIT_OK
