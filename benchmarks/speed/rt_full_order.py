"""The face-normal liquid ("rt") at full order: its dense blocks against the blocks without dense
matrices on the faces (fem/face_schur.py, solve/face_inverse.py), and the stabilized element, on the
shipped shaped scenes and on larger prismatic tanks.

    PYTHONPATH=. python benchmarks/rt_full_order.py [--steps 100] [--cases lng_carrier,type_c_tank,...]
        [--solvers rt-dense,rt-sparse,stabilized] [--chebyshev-tol 1e-15]

Each (case, solver) runs in a new process (its peak memory is that process's): the build (the
model and the Newton blocks), the compile, the step's time after compilation (best of two runs of
`--steps` steps), Newton iterations per step, the liquid's unknowns and the peak resident memory.
`rt-dense`: `simulation.linear_solver = "dense"` (the dense M, K and inverses; refused above 4,000
free faces); `rt-sparse`: "sparse"; `stabilized`: the nodal element with the scene's default solver.
Prints a table; no assertion.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

BASE = os.path.join(ROOT, "scenes", "paper_ship_tank.toml")


def case_text(name: str) -> str:
    """The scene of a case, every tank's element left to the solver's row."""
    if name in ("lng_carrier", "type_c_tank"):
        return open(os.path.join(ROOT, "scenes", f"{name}.toml")).read()
    # a prismatic LNG tank 20 m x 8 m x 8 m (hopper and top chamfers 2 x 2 m) filled to 5 m, on the
    # paper ship; mesh names the hexahedra along x, y, z
    mesh = {"prismatic_8k": "[10, 20, 14]", "prismatic_12k": "[12, 24, 14]", "prismatic_16k": "[12, 24, 20]",
            "prismatic_small": "[4, 12, 8]"}[name]
    t = open(BASE).read()
    t = t.replace("size = [5.0, 5.0, 4.0]", "size = [8.0, 8.0, 8.0]").replace("mesh = [5, 5, 5]", f"mesh = {mesh}")
    t = t.replace("fill_depth = 3.0", "fill_depth = 5.0").replace("origin = [-2.5, -2.5, -1.0]", "origin = [-4.0, -4.0, -3.0]")
    t = t.replace('walls = "rigid"\n', 'walls = "rigid"\nshape = "prismatic"\nchamfers = [[2.0, 2.0], [2.0, 2.0]]\n')
    t = t.replace("point = [4.5, 2.5, 0.0]", "point = [4.0, 4.0, 0.5]").replace("point = [4.5, 2.5, 3.0]", "point = [4.0, 7.0, 5.0]")
    t = t.replace("density = 1000.0", "density = 450.0")
    return t


def with_solver(text: str, solver: str) -> str:
    element = "stabilized" if solver == "stabilized" else "rt"
    text = text.replace("[tanks.fluid]\n", f'[tanks.fluid]\nelement = "{element}"\n')
    if solver != "stabilized":
        text = text.replace("[simulation]", f'[simulation]\nlinear_solver = "{solver[3:]}"', 1)
    return text


def one(name: str, solver: str, steps: int, tol: float) -> dict:
    """In this process: build, compile and time the case."""
    import jax
    jax.config.update("jax_enable_x64", True)
    import numpy as np
    import jaxslosh as js
    from jaxslosh.run.loop import advance, core, start
    from jaxslosh.run.simulate import prepare
    from jaxslosh.scene.keys import with_overrides
    from jaxslosh.solve import face_inverse
    face_inverse.MASS_TOL = tol
    scene = js.load_scene(with_solver(case_text(name), solver))
    t0 = time.perf_counter()
    setup = prepare(with_overrides(scene, duration=steps * scene.simulation.dt))
    b, solver_ = core(setup.built), setup.solver
    t1 = time.perf_counter()
    carry, f0 = start(b, solver_)
    jax.block_until_ready(f0)
    t2 = time.perf_counter()
    c, fr = advance(b, solver_, carry, steps, 1)
    jax.block_until_ready(fr)
    t3 = time.perf_counter()
    runs = []
    for _ in range(2):
        s = time.perf_counter()
        c, fr = advance(b, solver_, carry, steps, 1)
        jax.block_until_ready(fr)
        runs.append(time.perf_counter() - s)
    run = min(runs)
    return dict(case=name, solver=solver, unknowns=int(b.system.n), build=t1 - t0, compile=(t3 - t2) - run + (t2 - t1),
                us=1e6 * run / steps, iters=float(np.asarray(fr.iterations).mean()), ok=not bool(c.failed),
                rss=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--cases", default="lng_carrier,type_c_tank,prismatic_small,prismatic_8k,prismatic_16k")
    ap.add_argument("--solvers", default="rt-dense,rt-sparse,stabilized")
    ap.add_argument("--chebyshev-tol", type=float, default=1e-15, help="solve/face_inverse.MASS_TOL")
    ap.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        print("RESULT " + json.dumps(one(a.one[0], a.one[1], a.steps, a.chebyshev_tol)), flush=True)
        return
    print(f"{a.steps} steps, best of 2 after compilation; Chebyshev tolerance {a.chebyshev_tol:g}")
    print("| case | solver | unknowns | build s | compile s | ms/step | Newton its/step | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|")
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    for name in a.cases.split(","):
        for solver in a.solvers.split(","):
            p = subprocess.run([sys.executable, __file__, "--steps", str(a.steps), "--chebyshev-tol",
                                str(a.chebyshev_tol), "--one", name, solver], capture_output=True, text=True, env=env)
            line = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")]
            if not line:
                err = (p.stderr.strip().splitlines() or ["?"])[-1]
                print(f"| {name} | {solver} | - | - | - | - | - | {err[:90]} |", flush=True)
                continue
            r = json.loads(line[0][7:])
            print(f"| {name} | {solver} | {r['unknowns']:,} | {r['build']:.1f} | {r['compile']:.1f} | {r['us'] / 1e3:.2f} "
                  f"| {r['iters']:.2f} | {r['rss']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
