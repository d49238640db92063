"""Small scenes and measurements shared by the tests."""
from __future__ import annotations

import numpy as np

import jaxslosh as js

VESSEL = """
title = "test vessel"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
dt = {dt}
scheme = "{scheme}"
alpha = {alpha}
[vessel]
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 390.0
gm_t = 1.5
gm_l = 15.0
[vessel.initial]
angular_velocity = {omega}
position = {position}
"""


def vessel_scene(duration=10.0, dt=0.01, scheme="hht", alpha=0.01, omega=(0.0, 0.0, 0.0), position=(0.0, 0.0, 0.0),
                 extra=""):
    text = VESSEL.format(duration=duration, dt=dt, scheme=scheme, alpha=alpha, omega=list(omega),
                         position=list(position)) + extra
    return js.load_scene(text)


# ------------------------------------------------------------------------------------------------
# scenes with elastic structures (test_multibody.py, test_multibody_parts.py): TOML text to concatenate

STEEL = "[structures.material]\nyoung = {young!r}\npoisson = 0.3\ndensity = 7850.0\n"


def mast(name="mast", origin=(-0.15, -0.15, 1.0), size=(0.3, 0.3, 4.0), mesh=(1, 1, 8), attach="z-", to=None,
         young=2.1e11):
    s = (f'[[structures]]\nname = "{name}"\norigin = {list(origin)}\nsize = {list(size)}\nmesh = {list(mesh)}\n'
         f'attach = "{attach}"\n')
    if to:
        s += f'attach_to = "{to}"\n'
    return s + STEEL.format(young=young)


def multibody_vessel(duration=1.0, dt=0.01, scheme="newmark", extra_sim="", gravity=9.81, hydro=True, initial="",
           extra_vessel="", mass=3.25e5, displaced=None):
    hyd = ""
    if hydro:
        hyd = (f"[vessel.hydrostatics]\nwaterplane_area = 200.0\ndisplaced_volume = {displaced or mass / 1025.0!r}\n"
               "gm_t = 1.67\ngm_l = 14.2\n")
    return (f'title = "multibody test"\n[environment]\ngravity = {gravity!r}\n'
            f'[simulation]\nduration = {duration!r}\ndt = {dt!r}\nscheme = "{scheme}"\n{extra_sim}\n'
            f"[vessel]\nmass = {mass!r}\ninertia = [4.9e6, 1.45e7, 1.6e7]\n{hyd}"
            f"[vessel.initial]\n{initial}\n{extra_vessel}\n")


MULTIBODY_TANK = ('[[tanks]]\nname = "tank"\norigin = [-1.5, -1.0, -2.0]\nsize = [3.0, 2.0, 2.0]\nfill_depth = 1.2\n'
        'mesh = [3, 2, 2]\n')


def zero_crossing_period(t, x):
    """Mean period from upward zero crossings (linear interpolation between samples)."""
    t, x = np.asarray(t), np.asarray(x)
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    assert len(tc) >= 3, "too few oscillations to measure a period"
    return (tc[-1] - tc[0]) / (len(tc) - 1)


def run_notebook(name: str, env: dict | None = None, timeout: int = 900) -> list:
    """Execute notebooks/NAME (its stored outputs dropped first) in its folder with the environment variables
    `env` set for the run; no cell may raise. Returns the outputs of its code cells."""
    import os
    from pathlib import Path

    import nbclient
    import nbformat
    folder = Path(__file__).resolve().parents[1] / "notebooks"

    def fresh():
        # run from a clean slate: a notebook may be committed with its outputs (the site shows them)
        nb = nbformat.read(folder / name, as_version=4)
        for c in nb.cells:
            if c.cell_type == "code":
                c.outputs, c.execution_count = [], None
        return nb

    nb = fresh()
    env = env or {}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        try:
            nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                    resources={"metadata": {"path": str(folder)}}).execute()
        except nbclient.exceptions.DeadKernelError:
            # the kernel process died (seen once in a CI run of the quickstart, never again on the
            # same commit): a second one runs it afresh; a crash of ours would kill it again
            nb = fresh()
            nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                    resources={"metadata": {"path": str(folder)}}).execute()
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    return outputs


def printed(outputs: list) -> str:
    return "".join(o.get("text", "") for o in outputs)


# independent section geometry for the large-angle references (tests of GZ and of the free roll)

def clip_polygon(P, level):
    """Sutherland-Hodgman: the part of polygon P (k, 2: y, z) with z <= level."""
    out = []
    for i in range(len(P)):
        a, b = P[i], P[(i + 1) % len(P)]
        ina, inb = a[1] <= level, b[1] <= level
        if ina:
            out.append(a)
        if ina != inb:
            s = (level - a[1]) / (b[1] - a[1])
            out.append(a + s * (b - a))
    return np.array(out)


def area_centroid(P):
    """Shoelace area and centroid of polygon P (k, 2); a polygon of no area (the section clear of
    the water line) has no centroid: NaN."""
    if len(P) < 3:
        return 0.0, np.full(2, np.nan)
    y, z = P[:, 0], P[:, 1]
    y1, z1 = np.roll(y, -1), np.roll(z, -1)
    c = y * z1 - y1 * z
    A = 0.5 * c.sum()
    if A == 0.0:
        return 0.0, np.full(2, np.nan)
    return A, np.array([((y + y1) * c).sum(), ((z + z1) * c).sum()]) / (6.0 * A)
