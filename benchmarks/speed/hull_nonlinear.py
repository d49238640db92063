"""The step of the nonlinear hydrostatics (`vessel.hydrostatics.model = "nonlinear"`) against the linear
GM springs: the paper example's vessel (with and without its tank), as a 12-triangle box, as a
closed mesh of about 2,000 panels, and the parametric-roll scene (waves on the wetted hull).

    python -m benchmarks.speed.hull_nonlinear [--steps 1000] [--repeat 3] [--panels 2028] [--cases paper,...]
        [--quick] [--markdown]

Issue 32 item 7: the nonlinear step on a hull of about 2,000 panels should cost at most 1.5 times
the linear step of the paper example. Prints a table; no assertion (speed is measured here, never
in tests). Each step is timed twice: the wall clock and this process's CPU time. On a shared
machine the wall clock counts the other jobs' time slices and moved by factors of two to four
between rounds; the CPU time counts this process's work alone (and every thread of it: XLA runs
these small programs on one), so the ratios are taken from it.

Run with another checkout first on PYTHONPATH to time its package with the same cases (the script
uses only the public API, benchmarks/harness.py, hull/box.py and hull/surface.write_hull_mesh: the
box hull's panels and its mesh file).
"""
import os
import tempfile

import jaxslosh as js
from jaxslosh.hull.box import box_hull
from jaxslosh.hull.surface import write_hull_mesh
from benchmarks.harness import Table, machine, parser, scene, time_scenes

# the paper's ship as a box: 16 x 10 m waterplane, 400 m^3 (draft 2.5 m), GM_T 1.67 m with the liquid
# frozen: KG = KB + BM - GM = 1.25 + 10^2 / (12 * 2.5) - 1.67 m above the keel
L, B, T, D = 16.0, 10.0, 2.5, 5.0
KG = T / 2 + B ** 2 / (12 * T) - 1.67


def nonlinear(sc: js.Scene, hull: dict) -> js.Scene:
    """The scene with the hull's keys and the nonlinear hydrostatics in place of its GM springs."""
    return js.scene_with(sc, {"vessel.hydrostatics": None, "vessel.hydrostatics.model": "nonlinear",
                              **{f"vessel.hull.{k}": v for k, v in hull.items()}})


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3, help="rounds over the cases; the best of each is shown")
    ap.add_argument("--panels", type=int, default=2028, help="triangles of the mesh hull (12 n^2 for the box)")
    ap.add_argument("--cases", default="", help="comma-separated prefixes of the case names to run (default all; "
                                                "the paper example's linear case, the ratios' reference, always runs)")
    a = ap.parse_args()
    if a.quick:             # a few steps, one round, the vessel alone's cases and the paper example's linear one
        a.steps, a.repeat, a.cases = 10, 1, a.cases or "vessel alone"
    n = max(1, round((a.panels / 12) ** 0.5))
    paper = scene("paper_ship_tank")
    alone = js.scene_with(scene("vessel_only"), {"vessel.hydrostatics.waterplane_area": 160.0})
    box = {"length": L, "beam": B, "draft": T, "kg": KG, "depth": D}
    tmp = tempfile.mkdtemp()
    mesh = os.path.join(tmp, "hull.obj")
    tris = box_hull(L, B, KG, D, n)            # in the file's coordinates: waterline at z = 0
    write_hull_mesh(mesh, tris + [0.0, 0.0, KG - T])
    meshed = {"type": "mesh", "file": mesh, "cog": [0.0, 0.0, KG - T]}
    cases = [("vessel alone, linear", alone),
             ("vessel alone, box 12", nonlinear(alone, box)),
             (f"vessel alone, mesh {len(tris)}", nonlinear(alone, meshed)),
             ("paper example, linear", paper),
             ("paper example, box 12", nonlinear(paper, box)),
             (f"paper example, mesh {len(tris)}", nonlinear(paper, meshed)),
             ("parametric roll (waves)", scene("parametric_roll"))]
    if a.cases:
        keep = tuple(x.strip() for x in a.cases.split(",") if x.strip()) + ("paper example, linear",)
        cases = [(name, sc) for name, sc in cases if name.startswith(keep)]
    print(f"jaxslosh from {os.path.dirname(os.path.dirname(js.__file__))}")
    print(f"{machine()}; best of {a.repeat}; {a.steps} steps\n")
    # rounds over all the cases, the best of each kept: on a shared machine the load moves between
    # rounds, and the ratios of cases timed minutes apart in one pass move with it
    records = time_scenes(cases, a.steps, a.repeat)
    ref = next(r.cpu_us_per_step for r in records if r.name == "paper example, linear")
    table = Table(("case", "{}"), ("compile s", "{:.2f}"), ("wall us", "{:.1f}"), ("CPU us", "{:.1f}"),
                  ("CPU / paper linear", "{:.2f}"), ("status", "{}"))
    for r in records:
        table.add(r.name, r.compile_s, r.us_per_step, r.cpu_us_per_step, r.cpu_us_per_step / ref,
                  "ok" if r.ok else "FAILED")
    table.print(a.markdown)


if __name__ == "__main__":
    main()
