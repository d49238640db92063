"""Time the paper example (and the vessel alone): compilation apart from running, steps per second.

    python benchmarks/bench_paper.py [--steps 2000] [--repeat 2] [--quick]

Issue item 3(a): compile time and steps per second for the vessel alone, the paper example
(5 x 5 x 5, full order and 20 sloshing modes), and meshes 10 x 10 x 6 and 20 x 20 x 12 (full order,
sparse, and 20 modes). Prints a table; no assertion (speed is measured here, never in tests).
"""
import argparse
import os
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)

import jaxslosh as js  # noqa: E402
from jaxslosh.run.loop import core as _core, advance, start  # noqa: E402
from jaxslosh.run.simulate import prepare
from jaxslosh.scene.keys import with_overrides

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def paper_variant(text, mesh=None, modes=None, dt=None, static_correction=True):
    """The paper scene's TOML with another liquid mesh, a modal reduction or another step."""
    if mesh is not None:
        text = text.replace("mesh = [5, 5, 5]", f"mesh = [{mesh[0]}, {mesh[1]}, {mesh[2]}]")
    if modes:
        text = text.replace("[tanks.fluid]", f"[tanks.reduction]\nmodes = {modes}\nstatic_correction = "
                                             f"{'true' if static_correction else 'false'}\n\n[tanks.fluid]")
    if dt is not None:
        text = text.replace("dt = 0.01", f"dt = {dt}")
    return text


def time_scene(scene, steps, save_every=1):
    setup = prepare(with_overrides(scene, duration=steps * scene.simulation.dt))
    b, solver = _core(setup.built), setup.solver
    t0 = time.perf_counter()
    carry, f0 = start(b, solver)
    jax.block_until_ready(f0)
    t1 = time.perf_counter()
    frames = steps // save_every
    steps = frames * save_every
    c2, fr = advance(b, solver, carry, frames, save_every)       # first call: compile + run
    jax.block_until_ready(fr)
    t2 = time.perf_counter()
    c3, fr = advance(b, solver, carry, frames, save_every)       # second call: run only
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
    ap.add_argument("--repeat", type=int, default=2, help="timings per case; the best is shown (shared machine)")
    ap.add_argument("--quick", action="store_true", help="vessel, paper example and the 20-mode runs only")
    ap.add_argument("--save-every", type=int, default=1,
                    help="a result frame (probes, energies) every N steps; 1: every step, as the paper scene saves")
    a = ap.parse_args()
    paper = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    cases = [("vessel alone", js.load_scene(os.path.join(ROOT, "scenes", "vessel_only.toml")), a.steps),
             ("paper example 5x5x5", js.load_scene(paper), a.steps),
             ("paper, 20 modes", js.load_scene(paper_variant(paper, modes=20)), a.steps),
             ("paper, 20 modes, no s.c.", js.load_scene(paper_variant(paper, modes=20, static_correction=False)), a.steps),
             ("mesh 10x10x6", js.load_scene(paper_variant(paper, mesh=(10, 10, 6))), min(a.steps, 400)),
             ("mesh 20x20x12", js.load_scene(paper_variant(paper, mesh=(20, 20, 12))), min(a.steps, 60)),
             ("mesh 20x20x12, 20 modes", js.load_scene(paper_variant(paper, mesh=(20, 20, 12), modes=20)), a.steps)]
    if a.quick:
        cases = cases[:4]
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cpu; best of {a.repeat}; "
          f"a frame saved every {a.save_every} step(s)")
    print(f"{'case':24} {'unknowns':>8} {'compile s':>10} {'run s':>8} {'steps/s':>9} {'us/step':>9} {'newton it':>9}")
    for name, scene, steps in cases:
        runs = [time_scene(scene, steps, a.save_every) for _ in range(a.repeat)]
        r = dict(min(runs, key=lambda x: x["run"]))
        r["compile"] = runs[0]["compile"]      # later repetitions find the loop compiled already
        print(f"{name:24} {r['unknowns']:8d} {r['compile']:10.2f} {r['run']:8.3f} {r['sps']:9.0f} {r['us']:9.1f} "
              f"{r['iters']:9.2f}{'' if r['ok'] else '  FAILED'}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
