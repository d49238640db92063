"""Shaped tanks in pure JAX (issue 35 item 1): their step against the floor of pre-factored dense
solves, the JAX factors against the host's sparse LU, and the compile phase of a first and a second
`jaxslosh run` in new processes.

    python -m benchmarks.speed.shaped_tanks [--steps 400] [--repeat 2] [--only NAME]
        [--no-compile | --no-steps] [--no-host] [--no-dense] [--quick] [--markdown]

Rows: the two shaped scenes of scenes/ (lng_carrier: two prismatic tanks; type_c_tank: a horizontal
cylinder), and the shapes of benchmarks/speed/shapes.py at full order (prismatic 4x12x8, vertical cylinder
8x8x5, horizontal cylinder 6x12x6), each forced onto the sparse path (`simulation.linear_solver`):

* `jax`: "sparse", the liquid block's solves by the factors of jaxslosh/solve/factored.py;
* `host`: "sparse-host", SciPy's SuperLU called from the step (the path before issue 35);
* `dense`: "dense", the whole liquid's dense matrices and inverses (what "auto" gives below 1,500
  liquid unknowns: the three shapes of benchmarks/speed/shapes.py);
* `floor`: three solves per step with a pre-factored dense matrix of the scene's unknowns (the
  issue's floor; a solve is a product with the pre-computed inverse), in one compiled loop of as
  many steps; the ratio is the step's time over it.

Compile: `python -m jaxslosh run SCENE --duration 0.5` twice, each in a new process, with a fresh
cache folder; the summary line's compile phase of each (the second should compile nothing).
In-process times are the best of `repeat` after compilation (benchmarks/harness.py). Prints tables;
no assertion.
"""
import os
import re
import subprocess
import sys
import tempfile
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxslosh as js
from benchmarks.harness import ROOT, Table, best_of, machine, parser, scene, time_scene
from benchmarks.speed.shapes import shape_scene


#: the rows' names for the values of `simulation.linear_solver`
SOLVERS = {"jax": "sparse", "host": "sparse-host", "dense": "dense"}


def with_solver(sc: js.Scene, solver: str) -> js.Scene:
    return js.scene_with(sc, {"simulation.linear_solver": solver})


def scenes():
    base = scene("paper_ship_tank")
    return [
        ("lng_carrier", scene("lng_carrier")),
        ("type_c_tank", scene("type_c_tank")),
        ("prismatic 4x12x8", shape_scene(base, {"shape": "prismatic", "chamfers": [[1.5, 1.0], [1.5, 1.0]]},
                                         [4.0, 6.0, 4.0], [4, 12, 8], 3.5, [-2.0, -3.0, -1.0])),
        ("vertical cylinder 8x8x5", shape_scene(base, {"shape": "cylinder", "axis": "z"}, [5.6, 5.6, 4.0], [8, 8, 5],
                                                3.0, [-2.8, -2.8, -1.0])),
        ("horizontal cylinder 6x12x6", shape_scene(base, {"shape": "cylinder", "axis": "x"}, [6.0, 4.0, 4.0],
                                                   [6, 12, 6], 2.0, [-3.0, -2.0, -1.0])),
    ]


def floor_us(n, steps, repeat):
    """us per step of three pre-factored dense solves of n unknowns per step (a solve: a product with
    the pre-computed inverse, as the dense path applies its blocks), in one compiled loop."""
    rng = np.random.default_rng(0)
    Ainv = jnp.asarray(np.linalg.inv(rng.standard_normal((n, n)) + n * np.eye(n)))

    @jax.jit
    def loop(Ainv, x):
        def one(x, _):
            for _ in range(3):
                x = Ainv @ x * 1.0001
            return x, None
        return jax.lax.scan(one, x, None, length=steps)[0]
    x = jnp.asarray(rng.standard_normal(n))
    loop(Ainv, x).block_until_ready()
    best = best_of(lambda: loop(Ainv, x), repeat)[0]
    return 1e6 * best / steps


def compile_phases(sc: js.Scene):
    """The summary line's compile phase (s) of two `jaxslosh run`s in new processes, one cache."""
    tmp = tempfile.mkdtemp()
    scene = os.path.join(tmp, "scene.toml")
    with open(scene, "w") as f:
        f.write(sc.text)
    env = dict(os.environ, JAXSLOSH_CACHE_DIR=os.path.join(tmp, "cache"),
               PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = []
    for k in range(2):
        t = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "jaxslosh", "run", scene, "-o", os.path.join(tmp, f"r{k}.h5"),
                            "--duration", "0.5", "--no-progress"], capture_output=True, text=True, env=env)
        wall = time.perf_counter() - t
        m = re.search(r"compile ([0-9.]+) s", p.stderr + p.stdout)
        out.append((float(m.group(1)) if m else float("nan"), wall))
    return out


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--repeat", type=int, default=2, help="timings per case; the best is shown (shared machine)")
    ap.add_argument("--no-compile", action="store_true", help="skip the two-process compile rows")
    ap.add_argument("--no-host", action="store_true", help="skip the host LU rows")
    ap.add_argument("--no-dense", action="store_true", help="skip the dense rows")
    ap.add_argument("--no-steps", action="store_true", help="only the two-process compile rows")
    ap.add_argument("--only", help="rows whose name contains this")
    a = ap.parse_args()
    if a.quick:             # one small scene, the JAX factors only, a few steps, no new processes
        a.steps, a.repeat, a.only, a.no_host, a.no_dense, a.no_compile = 10, 1, "vertical cylinder", True, True, True
    rows = [r for r in scenes() if a.only is None or a.only in r[0]]
    print(f"{machine()}; {a.steps} steps, best of {a.repeat}\n")
    table = Table(("scene", "{}"), ("unknowns", "{:d}"), ("solver", "{}"), ("us/step", "{:.0f}"),
                  ("floor us", "{:.0f}"), ("ratio", "{:.2f}"), ("status", "{}"))
    for name, sc in [] if a.no_steps else rows:
        floor = None
        for solver in [s for s in SOLVERS if not (a.no_host and s == "host") and not (a.no_dense and s == "dense")]:
            r = time_scene(name, with_solver(sc, SOLVERS[solver]), a.steps, a.repeat)
            if floor is None:
                floor = floor_us(r.unknowns, a.steps, a.repeat)
            table.add(name, r.unknowns, solver, r.us_per_step, floor, r.us_per_step / floor, "ok" if r.ok else "FAILED")
    if not a.no_steps:
        table.print(a.markdown)
    if a.no_compile:
        return
    print()
    table = Table(("scene (jaxslosh run, 0.5 s)", "{}"), ("compile 1st s", "{:.2f}"), ("compile 2nd s", "{:.2f}"),
                  ("wall 1st s", "{:.1f}"), ("wall 2nd s", "{:.1f}"))
    for name, sc in rows[:2]:
        for solver in ("sparse",) if a.no_host else ("sparse", "sparse-host"):
            (c1, w1), (c2, w2) = compile_phases(with_solver(sc, solver))
            table.add(name + " " + solver, c1, c2, w1, w2)
    table.print(a.markdown)


if __name__ == "__main__":
    main()
