"""Shaped tanks in pure JAX (issue 35 item 1): their step against the floor of pre-factored dense
solves, the JAX factors against the host's sparse LU, and the compile phase of a first and a second
`jaxslosh run` in new processes.

    PYTHONPATH=. python benchmarks/shaped_tanks.py [--steps 400] [--repeat 2] [--only NAME]
        [--no-compile | --no-steps] [--no-host] [--no-dense]

Rows: the two shaped scenes of scenes/ (lng_carrier: two prismatic tanks; type_c_tank: a horizontal
cylinder), and the shapes of benchmarks/shapes.py at full order (prismatic 4x12x8, vertical cylinder
8x8x5, horizontal cylinder 6x12x6), each forced onto the sparse path (`simulation.linear_solver`):

* `jax`: "sparse", the liquid block's solves by the factors of jaxslosh/solve/factored.py;
* `host`: "sparse-host", SciPy's SuperLU called from the step (the path before issue 35);
* `dense`: "dense", the whole liquid's dense matrices and inverses (what "auto" gives below 1,500
  liquid unknowns: the three shapes of benchmarks/shapes.py);
* `floor`: three solves per step with a pre-factored dense matrix of the scene's unknowns (the
  issue's floor; a solve is a product with the pre-computed inverse), in one compiled loop of as
  many steps; the ratio is the step's time over it.

Compile: `python -m jaxslosh run SCENE --duration 0.5` twice, each in a new process, with a fresh
cache folder; the summary line's compile phase of each (the second should compile nothing).
In-process times are the best of `repeat` after compilation. Prints tables; no assertion.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxslosh as js  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_paper import time_scene  # noqa: E402
from shapes import shape_text  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


#: the rows' names for the values of `simulation.linear_solver`
SOLVERS = {"jax": "sparse", "host": "sparse-host", "dense": "dense"}


def with_solver(text, solver):
    return text.replace("[simulation]", f'[simulation]\nlinear_solver = "{solver}"', 1)


def scenes():
    base = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    return [
        ("lng_carrier", open(os.path.join(ROOT, "scenes", "lng_carrier.toml")).read()),
        ("type_c_tank", open(os.path.join(ROOT, "scenes", "type_c_tank.toml")).read()),
        ("prismatic 4x12x8", shape_text(base, 'shape = "prismatic"\nchamfers = [[1.5, 1.0], [1.5, 1.0]]',
                                        "[4.0, 6.0, 4.0]", "[4, 12, 8]", "3.5", "[-2.0, -3.0, -1.0]")),
        ("vertical cylinder 8x8x5", shape_text(base, 'shape = "cylinder"\naxis = "z"', "[5.6, 5.6, 4.0]", "[8, 8, 5]",
                                               "3.0", "[-2.8, -2.8, -1.0]")),
        ("horizontal cylinder 6x12x6", shape_text(base, 'shape = "cylinder"\naxis = "x"', "[6.0, 4.0, 4.0]",
                                                  "[6, 12, 6]", "2.0", "[-3.0, -2.0, -1.0]")),
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
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        loop(Ainv, x).block_until_ready()
        best = min(best, time.perf_counter() - t)
    return 1e6 * best / steps


def compile_phases(text):
    """The summary line's compile phase (s) of two `jaxslosh run`s in new processes, one cache."""
    tmp = tempfile.mkdtemp()
    scene = os.path.join(tmp, "scene.toml")
    with open(scene, "w") as f:
        f.write(text)
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
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--repeat", type=int, default=2, help="timings per case; the best is shown (shared machine)")
    ap.add_argument("--no-compile", action="store_true", help="skip the two-process compile rows")
    ap.add_argument("--no-host", action="store_true", help="skip the host LU rows")
    ap.add_argument("--no-dense", action="store_true", help="skip the dense rows")
    ap.add_argument("--no-steps", action="store_true", help="only the two-process compile rows")
    ap.add_argument("--only", help="rows whose name contains this")
    a = ap.parse_args()
    rows = [r for r in scenes() if a.only is None or a.only in r[0]]
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cpu; {a.steps} steps, "
          f"best of {a.repeat}")
    print(f"{'scene':28} {'unknowns':>8} {'solver':>6} {'us/step':>9} {'floor us':>9} {'ratio':>6} {'newton it':>9}")
    for name, text in [] if a.no_steps else rows:
        floor = None
        for solver in [s for s in SOLVERS if not (a.no_host and s == "host") and not (a.no_dense and s == "dense")]:
            scene = js.load_scene(with_solver(text, SOLVERS[solver]))
            best = None
            for _ in range(a.repeat):
                r = time_scene(scene, a.steps)
                best = r if best is None or r["us"] < best["us"] else best
            if floor is None:
                floor = floor_us(best["unknowns"], a.steps, a.repeat)
            print(f"{name:28} {best['unknowns']:8d} {solver:>6} {best['us']:9.0f} {floor:9.0f} "
                  f"{best['us'] / floor:6.2f} {best['iters']:9.2f}{'' if best['ok'] else '  FAILED'}", flush=True)
    if a.no_compile:
        return
    print()
    print(f"{'scene (jaxslosh run, 0.5 s)':28} {'compile 1st s':>13} {'compile 2nd s':>13} {'wall 1st s':>10} "
          f"{'wall 2nd s':>10}")
    for name, text in rows[:2]:
        for solver in ("sparse",) if a.no_host else ("sparse", "sparse-host"):
            (c1, w1), (c2, w2) = compile_phases(with_solver(text, solver))
            print(f"{name + ' ' + solver:28} {c1:13.2f} {c2:13.2f} {w1:10.1f} {w2:10.1f}", flush=True)


if __name__ == "__main__":
    main()
