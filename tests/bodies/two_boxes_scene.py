"""Scenes of the two boxes of tests/data/bodies (a barge and a tender, solved by Capytaine: see its
generate.py): the masses, inertias and restoring that Capytaine's own RAOs used."""
from __future__ import annotations

import os

import numpy as np

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data", "bodies")
RHO, G = 1025.0, 9.81


def reference(stem="two_boxes"):
    """Capytaine's post_pro.rao of a dataset (f, h, 6 n), in our e^{+i w t} convention, with its inputs."""
    r = np.load(os.path.join(DATA, f"{stem}_rao.npz"))
    return {k: r[k] for k in r.files} | {"rao": np.conj(r["rao"])}


def box(table: str, name: str, k: int, file: str, extra: str = "", ref=None, damped: bool = False) -> str:
    """The TOML of the k-th box of two_boxes as `[vessel]` or `[[bodies]]`, its tables from `file`;
    `damped`: with viscous damping in sway (a decay time of 8 s: the transient's drift dies out) and
    roll (about 10 % of critical), so that a run settles to its steady state in a few periods."""
    r = ref or reference()
    C, M = r["stiffness"][6 * k:6 * k + 6, 6 * k:6 * k + 6], r["inertia"][6 * k:6 * k + 6, 6 * k:6 * k + 6]
    m = float(M[0, 0])
    V = m / RHO
    I = [float(x) for x in np.diag(M)[3:]]
    head = "[vessel]" if table == "vessel" else "[[bodies]]"
    return f"""{head}
name = "{name}"
mass = {m!r}
inertia = {I!r}
cog_height = -0.5
{extra}
[{table}.hydrostatics]
waterplane_area = {float(C[2, 2] / (RHO * G))!r}
displaced_volume = {V!r}
gm_t = {float(C[3, 3] / (RHO * G * V))!r}
gm_l = {float(C[4, 4] / (RHO * G * V))!r}
[{table}.hydrodynamics]
file = "{os.path.join(DATA, file)}"
""" + (f"viscous_damping = [0.0, {m / 8.0!r}, 0.0, {0.2 * float(np.sqrt(C[3, 3] * 2.0 * M[3, 3]))!r}, 0.0, 0.0]\n"
       if damped else "")


def two_boxes(gap_y=14.0, files=("two_boxes.nc", "two_boxes.nc"), waves="", duration=10.0, dt=0.05,
              damped=False) -> str:
    # tolerance: the radiation memory's fast poles leave the step's residual at about 1e-8 of its
    # scale (the vessel alone on one of these files as well)
    return (f"[simulation]\nduration = {duration!r}\ndt = {dt!r}\ntolerance = 1e-8\n\n{waves}\n"
            + box("vessel", "barge", 0, files[0], damped=damped)
            + box("bodies", "tender", 1, files[1], f"position = [0.0, {gap_y!r}]", damped=damped))
