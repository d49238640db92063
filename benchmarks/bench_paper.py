"""Time the paper example (and the vessel alone): compilation apart from running, steps per second.

    python benchmarks/bench_paper.py [--steps 2000]

Prints a table; no assertion (speed is measured here, never in tests).
"""
import argparse
import os
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)

import jaxslosh as js  # noqa: E402
from jaxslosh.run import _core, advance, prepare, start  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def time_scene(scene, steps):
    setup = prepare(scene, duration=steps * scene.simulation.dt)
    b, solver = _core(setup.built), setup.solver
    t0 = time.perf_counter()
    carry, f0 = start(b, solver)
    jax.block_until_ready(f0)
    t1 = time.perf_counter()
    c2, fr = advance(b, solver, carry, steps, 1)       # first call: compile + run
    jax.block_until_ready(fr)
    t2 = time.perf_counter()
    c3, fr = advance(b, solver, carry, steps, 1)       # second call: run only
    jax.block_until_ready(fr)
    t3 = time.perf_counter()
    run = t3 - t2
    compile_time = (t2 - t1) - run
    its = float(fr.iterations.mean())
    return dict(unknowns=b.system.n, start=t1 - t0, compile=compile_time, run=run, steps=steps,
                sps=steps / run, us=1e6 * run / steps, iters=its, ok=not bool(c3.failed))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=2000)
    a = ap.parse_args()
    cases = [("vessel alone", js.load_scene(os.path.join(ROOT, "scenes", "vessel_only.toml"))),
             ("paper example 5x5x5", js.load_scene(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")))]
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cpu")
    print(f"{'case':24} {'unknowns':>8} {'compile s':>10} {'run s':>8} {'steps/s':>9} {'us/step':>9} {'newton it':>9}")
    for name, scene in cases:
        r = time_scene(scene, a.steps)
        print(f"{name:24} {r['unknowns']:8d} {r['compile']:10.2f} {r['run']:8.3f} {r['sps']:9.0f} {r['us']:9.1f} "
              f"{r['iters']:9.2f}{'' if r['ok'] else '  FAILED'}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
