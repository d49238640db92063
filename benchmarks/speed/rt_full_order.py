"""The face-normal liquid ("rt") at full order: its dense blocks against the blocks without dense
matrices on the faces (liquid/face/schur.py, liquid/face/inverse.py), and the stabilized element, on the
shipped shaped scenes and on larger prismatic tanks.

    python -m benchmarks.speed.rt_full_order [--steps 100] [--cases lng_carrier,type_c_tank,...]
        [--solvers rt-dense,rt-sparse,stabilized] [--chebyshev-tol 1e-15] [--quick] [--markdown]

Each (case, solver) runs in a new process (its peak memory is that process's): the build (the
model and the Newton blocks), the compile, the step's time after compilation (best of two runs of
`--steps` steps: benchmarks/harness.py's time_scene), the unknowns and the peak resident memory.
`--chebyshev-tol` sets jaxslosh/liquid/face/inverse.MASS_TOL, an internal (the tolerance of the
faces' mass inverse has no scene key).
`rt-dense`: `simulation.linear_solver = "dense"` (the dense M, K and inverses; refused above 4,000
free faces); `rt-sparse`: "sparse"; `stabilized`: the nodal element with the scene's default solver.
Prints a table; no assertion.
"""
import argparse
import json
import resource
import subprocess
import sys

import jaxslosh as js
from benchmarks.harness import ROOT, Table, parser, scene, time_scene

def case_scene(name: str) -> js.Scene:
    """The scene of a case, every tank's element left to the solver's row."""
    if name in ("lng_carrier", "type_c_tank"):
        return scene(name)
    # a prismatic LNG tank 20 m x 8 m x 8 m (hopper and top chamfers 2 x 2 m) filled to 5 m, on the
    # paper ship; mesh names the hexahedra along x, y, z
    mesh = {"prismatic_8k": [10, 20, 14], "prismatic_12k": [12, 24, 14], "prismatic_16k": [12, 24, 20],
            "prismatic_small": [4, 12, 8]}[name]
    return js.scene_with(scene("paper_ship_tank"), {
        "tanks[0].size": [8.0, 8.0, 8.0], "tanks[0].mesh": mesh, "tanks[0].fill_depth": 5.0,
        "tanks[0].origin": [-4.0, -4.0, -3.0], "tanks[0].shape": "prismatic",
        "tanks[0].chamfers": [[2.0, 2.0], [2.0, 2.0]], "tanks[0].fluid.density": 450.0,
        "probes.A.point": [4.0, 4.0, 0.5], "probes.B.point": [4.0, 7.0, 5.0]})


def with_solver(sc: js.Scene, solver: str) -> js.Scene:
    keys = {f"tanks[{i}].fluid.element": "stabilized" if solver == "stabilized" else "rt" for i in range(len(sc.tanks))}
    if solver != "stabilized":
        keys["simulation.linear_solver"] = solver[3:]
    return js.scene_with(sc, keys)


def one(name: str, solver: str, steps: int, tol: float) -> dict:
    """In this process: build, compile and time the case."""
    from jaxslosh.liquid.face import inverse as face_inverse
    face_inverse.MASS_TOL = tol
    r = time_scene(name, with_solver(case_scene(name), solver), steps, repeat=2)
    return dict(case=name, solver=solver, unknowns=r.unknowns, build=r.build_s, compile=r.compile_s,
                us=r.us_per_step, ok=r.ok, rss=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--cases", default="lng_carrier,type_c_tank,prismatic_small,prismatic_8k,prismatic_16k")
    ap.add_argument("--solvers", default="rt-dense,rt-sparse,stabilized")
    ap.add_argument("--chebyshev-tol", type=float, default=1e-15, help="liquid/face/inverse.MASS_TOL")
    ap.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.quick:             # the small prismatic tank, the sparse faces, a few steps
        a.steps, a.cases, a.solvers = 5, "prismatic_small", "rt-sparse"
    if a.one:
        print("RESULT " + json.dumps(one(a.one[0], a.one[1], a.steps, a.chebyshev_tol)), flush=True)
        return
    print(f"{a.steps} steps, best of 2 after compilation; Chebyshev tolerance {a.chebyshev_tol:g}\n")
    table = Table(("case", "{}"), ("solver", "{}"), ("unknowns", "{:,}"), ("build s", "{:.1f}"),
                  ("compile s", "{:.1f}"), ("ms/step", "{}"), ("peak RSS MB", "{}"))
    for name in a.cases.split(","):
        for solver in a.solvers.split(","):
            p = subprocess.run([sys.executable, "-m", "benchmarks.speed.rt_full_order", "--steps", str(a.steps),
                                "--chebyshev-tol", str(a.chebyshev_tol), "--one", name, solver],
                               capture_output=True, text=True, cwd=ROOT)
            line = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")]
            if not line:
                err = (p.stderr.strip().splitlines() or ["?"])[-1]
                table.add(name, solver, "-", "-", "-", "-", err[:90])
                continue
            r = json.loads(line[0][7:])
            table.add(name, solver, r["unknowns"], r["build"], r["compile"],
                      f"{r['us'] / 1e3:.2f}" + ("" if r["ok"] else " FAILED"), f"{r['rss']:.0f}")
    table.print(a.markdown)


if __name__ == "__main__":
    main()
