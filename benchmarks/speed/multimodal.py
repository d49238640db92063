"""The multimodal tank's step cost against the finite-element tank reduced to 20 modes, and against
the full finite-element tank, on the paper example (scenes/paper_ship_tank.toml); and its probe B
against the finite elements'. Prints a table.

    python benchmarks/multimodal.py [--duration T] [--repeats K]

Each scene is compiled once; then the runs are timed K times, the variants alternated (the machine
may be shared: a ratio measured in one invocation holds better than the times), best of K. Two
figures per variant: the whole `js.simulate` call (build, solver set-up, the compiled loop, the
result) per step, and the compiled loop alone (steps and saved frames) per step; both in CPU time
of this process (`time.process_time`), so that other processes' load does not count."""
from __future__ import annotations

import argparse
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import jaxslosh as js  # noqa: E402
from jaxslosh.cache.compiled import compile_run  # noqa: E402
from jaxslosh.run.loop import core  # noqa: E402
from jaxslosh.run.simulate import prepare  # noqa: E402

VARIANTS = {
    "fem (5x5x5)": lambda t: t,
    "fem, 20 modes": lambda t: t.replace('walls = "rigid"', 'walls = "rigid"\n[tanks.reduction]\nmodes = 20'),
    "multimodal, 6 modes": lambda t: t.replace('mesh = [5, 5, 5]\nwalls = "rigid"', 'model = "multimodal"\nmodes = 6'),
    "multimodal, 6 modes, third-order": lambda t: t.replace('mesh = [5, 5, 5]\nwalls = "rigid"',
                                                            'model = "multimodal"\nmodes = 6\nexpansion = "third-order"'),
}
REFERENCE = "fem, 20 modes"


def _loop(scene):
    """The compiled time loop of a scene (as js.simulate compiles it) and a function that runs it."""
    setup = prepare(scene)
    b, solver = core(setup.built), setup.solver
    n_frames = setup.n_steps // setup.save_every
    carry, _, run = compile_run(b, solver, n_frames, setup.save_every)
    return setup.n_steps, lambda: jax.block_until_ready(run(b, solver, carry, n_frames, setup.save_every))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=5.0)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    text = open("scenes/paper_ship_tank.toml").read().replace("duration = 20.0", f"duration = {args.duration}")
    scenes = {name: js.load_scene(edit(text)) for name, edit in VARIANTS.items()}
    compile_s, loops, zB, status = {}, {}, {}, {}
    for name, scene in scenes.items():
        t0 = time.perf_counter()
        r = js.simulate(scene, throw=False)
        compile_s[name] = time.perf_counter() - t0
        zB[name], status[name] = np.asarray(r.probes["B"].displacement)[:, 2], r.status
        loops[name] = _loop(scene)
    whole, loop = {}, {}
    for _ in range(args.repeats):
        for name, scene in scenes.items():          # alternated: each repeat sees the same load
            n, run = loops[name]
            t0 = time.process_time()
            js.simulate(scene)
            whole[name] = min(whole.get(name, np.inf), (time.process_time() - t0) / n)
            t0 = time.process_time()
            run()
            loop[name] = min(loop.get(name, np.inf), (time.process_time() - t0) / n)
    print(f"{'tank':<22} {'first run s':>11} {'run ms/step':>12} {'loop ms/step':>13} "
          f"{'run / ' + REFERENCE:>20} {'loop / ' + REFERENCE:>21}  status")
    for name in scenes:
        print(f"{name:<22} {compile_s[name]:>11.1f} {1e3 * whole[name]:>12.3f} {1e3 * loop[name]:>13.4f} "
              f"{whole[name] / whole[REFERENCE]:>20.2f} {loop[name] / loop[REFERENCE]:>21.2f}  {status[name]}")
    ref = zB["fem (5x5x5)"]
    for name, z in zB.items():
        d = z - ref
        print(f"probe B, {name} vs fem: rms difference / rms {np.sqrt(np.mean(d ** 2) / np.mean(ref ** 2)):.3f}")


if __name__ == "__main__":
    main()
