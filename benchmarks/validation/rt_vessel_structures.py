"""A tank beside a structure in the vessel's frame (`frame = "vessel"`), with the face-normal liquid
("rt") and with the stabilized element: the coupled natural frequencies (`jaxslosh modes --coupled`)
of the floating ship, its 3 x 2 m tank filled to 1.2 m (plain, or with a standing baffle 0.6 m
high at mid-length) and a 4 m mast (E = 2.1e9 Pa) standing on deck.

    PYTHONPATH=. python benchmarks/rt_vessel_structures.py [--mesh 8,4,6] [-n 12]

On the plain box neither element locks, so the two give the same coupled system within the liquid's
discretisation; with the baffle the stabilized element stiffens the modes the plate touches. Prints
a table (rad/s): the modes by their dominant group (`CoupledModes.dominant`); the mast's bending
(about 10 rad/s) lies above the 12 lowest on 8x4x6 (`-n 40` finds it). No assertion.
"""
import argparse
import os
import sys

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests"))
sys.path.insert(0, os.path.join(ROOT, "tests", "physics"))

import jaxslosh as js  # noqa: E402
from jaxslosh.analysis.coupled import coupled_modes  # noqa: E402
from test_rt_vessel_structures import _text  # noqa: E402


def scene_text(mesh, element, baffle):
    t = _text(young=2.1e9).replace("mesh = [4, 2, 3]\n", f'mesh = {list(mesh)}\n[tanks.fluid]\nelement = "{element}"\n')
    if not baffle:
        t = t[:t.index("[[tanks.baffles]]")] + t[t.index("[[probes]]"):]
    return t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesh", default="8,4,6")
    ap.add_argument("-n", type=int, default=12)
    a = ap.parse_args()
    mesh = tuple(int(x) for x in a.mesh.split(","))
    print(f"| tank, {'x'.join(map(str, mesh))} | element | roll, pitch, heave | first 4 liquid modes | mast's first 2 |")
    print("|---|---|---|---|---|")
    for baffle in (False, True):
        for element in ("rt", "stabilized"):
            cm = coupled_modes(js.load_scene(scene_text(mesh, element, baffle)), n=a.n)
            dom = np.asarray(cm.dominant)
            cols = [cm.omega[np.isin(dom, ("roll", "pitch", "heave"))][:3], cm.omega[dom == "liquid"][:4],
                    cm.omega[dom == "structure mast"][:2]]
            cells = " | ".join(", ".join(f"{w:.4f}" for w in c) or f"above the {a.n} modes" for c in cols)
            print(f"| {'baffle' if baffle else 'plain'} | `\"{element}\"` | {cells} |", flush=True)


if __name__ == "__main__":
    main()
