"""A tank beside a structure in the vessel's frame (`frame = "vessel"`), with the face-normal liquid
("rt") and with the stabilized element: the coupled natural frequencies (`jaxslosh modes --coupled`)
of the floating ship, its 3 x 2 m tank filled to 1.2 m (plain, or with a standing baffle 0.6 m
high at mid-length) and a 4 m mast (E = 2.1e9 Pa) standing on deck.

    python -m benchmarks.validation.rt_vessel_structures [--mesh 8,4,6] [-n 12] [--quick]

On the plain box neither element locks, so the two give the same coupled system within the liquid's
discretisation; with the baffle the stabilized element stiffens the modes the plate touches. Prints
a table (rad/s): the modes by their dominant group (`CoupledModes.dominant`); the mast's bending
(about 10 rad/s) lies above the 12 lowest on 8x4x6 (`-n 40` finds it). No assertion. The scene is
the test's (tests/physics/test_rt_vessel_structures.py; run from the repository root); the modes
are jaxslosh/analysis/coupled.coupled_modes, what `jaxslosh modes --coupled` prints (no Python API
names it). `--quick`: mesh 4,2,3, 6 modes.
"""
import numpy as np

import jaxslosh as js
from jaxslosh.analysis.coupled import coupled_modes
from benchmarks.harness import Table, parser
from tests.physics.test_rt_vessel_structures import _text


def case_scene(mesh, element, baffle):
    keys = {"tanks[0].mesh": list(mesh), "tanks[0].fluid.element": element}
    if not baffle:
        keys["tanks[0].baffles"] = None
    return js.scene_with(js.load_scene(_text(young=2.1e9)), keys)


def main():
    ap = parser(__doc__)
    ap.add_argument("--mesh", default="8,4,6")
    ap.add_argument("-n", type=int, default=12)
    a = ap.parse_args()
    if a.quick:
        a.mesh, a.n = "4,2,3", 6
    mesh = tuple(int(x) for x in a.mesh.split(","))
    table = Table((f"tank, {'x'.join(map(str, mesh))}", "{}"), ("element", "{}"), ("roll, pitch, heave", "{}"),
                  ("first 4 liquid modes", "{}"), ("mast's first 2", "{}"))
    for baffle in (False, True):
        for element in ("rt", "stabilized"):
            cm = coupled_modes(case_scene(mesh, element, baffle), n=a.n)
            dom = np.asarray(cm.dominant)
            cols = [cm.omega[np.isin(dom, ("roll", "pitch", "heave"))][:3], cm.omega[dom == "liquid"][:4],
                    cm.omega[dom == "structure mast"][:2]]
            table.add("baffle" if baffle else "plain", f'`"{element}"`',
                      *(", ".join(f"{w:.4f}" for w in c) or f"above the {a.n} modes" for c in cols))
    table.print(a.markdown)


if __name__ == "__main__":
    main()
