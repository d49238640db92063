"""The multimodal tank's step cost against the finite-element tank reduced to 20 modes, and against
the full finite-element tank, on the paper example (scenes/paper_ship_tank.toml); and its probe B
against the finite elements'. Prints a table.

    python -m benchmarks.speed.multimodal [--duration T] [--repeats K] [--quick] [--markdown]

Each scene is compiled once; then the runs are timed K times, the variants alternated (the machine
may be shared: a ratio measured in one invocation holds better than the times), best of K. Two
figures per variant: the whole `js.simulate` call (build, solver set-up, the compiled loop, the
result) per step, and the step alone (benchmarks/harness.py's time_scenes: `js.Stepper.advance`,
no frames kept) per step; both in CPU time of this process (`time.process_time`), so that other
processes' load does not count."""
from __future__ import annotations

import numpy as np

import jaxslosh as js
from benchmarks.harness import Table, best_of, parser, scene, time_scenes

MULTIMODAL = {"tanks[0].mesh": None, "tanks[0].walls": None, "tanks[0].model": "multimodal", "tanks[0].modes": 6}
VARIANTS = {
    "fem (5x5x5)": {},
    "fem, 20 modes": {"tanks[0].reduction.modes": 20},
    "multimodal, 6 modes": MULTIMODAL,
    "multimodal, 6 modes, third-order": {**MULTIMODAL, "tanks[0].expansion": "third-order"},
}
REFERENCE = "fem, 20 modes"


def main():
    ap = parser(__doc__)
    ap.add_argument("--duration", type=float, default=None, help="simulated s (5; --quick: 0.1)")
    ap.add_argument("--repeats", type=int, default=None, help="timed rounds (3; --quick: 1)")
    args = ap.parse_args()
    duration = args.duration or (0.1 if args.quick else 5.0)
    repeats = args.repeats or (1 if args.quick else 3)
    base = js.scene_with(scene("paper_ship_tank"), {"simulation.duration": duration})
    names = (REFERENCE, "multimodal, 6 modes") if args.quick else VARIANTS      # --quick: two of them
    scenes = {name: js.scene_with(base, VARIANTS[name]) if VARIANTS[name] else base for name in names}
    compile_s, zB, status, whole = {}, {}, {}, {}
    for name, sc in scenes.items():
        compile_s[name], _, r = best_of(lambda: js.simulate(sc, throw=False), 1)
        zB[name], status[name] = np.asarray(r.probes["B"].displacement)[:, 2], r.status
    n = int(round(duration / base.simulation.dt))
    for _ in range(repeats):
        for name, sc in scenes.items():          # alternated: each repeat sees the same load
            whole[name] = min(whole.get(name, np.inf), best_of(lambda: js.simulate(sc), 1)[1] / n)
    loop = {r.name: r.cpu_s / r.steps for r in time_scenes(list(scenes.items()), n, repeats)}
    table = Table(("tank", "{}"), ("first run s", "{:.1f}"), ("run ms/step", "{:.3f}"), ("step ms", "{:.4f}"),
                  ("run / " + REFERENCE, "{:.2f}"), ("step / " + REFERENCE, "{:.2f}"), ("status", "{}"))
    for name in scenes:
        table.add(name, compile_s[name], 1e3 * whole[name], 1e3 * loop[name], whole[name] / whole[REFERENCE],
                  loop[name] / loop[REFERENCE], status[name])
    table.print(args.markdown)
    ref = zB.get("fem (5x5x5)", zB[REFERENCE])
    for name, z in zB.items():
        d = z - ref
        against = "fem" if "fem (5x5x5)" in zB else REFERENCE
        print(f"probe B, {name} vs {against}: rms difference / rms {np.sqrt(np.mean(d ** 2) / np.mean(ref ** 2)):.3f}")


if __name__ == "__main__":
    main()
