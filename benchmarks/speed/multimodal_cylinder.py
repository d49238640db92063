"""The three-dimensional multimodal tank on an upright cylinder against a box of the same size and modes:
its build, compile and step, per mode. Prints a table.

    python -m benchmarks.speed.multimodal_cylinder [--modes 6] [--steps K] [--expansion exact,third-order] [--quick] [--markdown]

A free vessel (set rolling, pitching and drifting) carries one 1.2 m tank filled to 0.6 m, its liquid on
the multimodal model across the whole base: a box (`flow = "3d"`) or an upright cylinder (`shape =
"cylinder"`, diameter 1.2 m) on the same number of modes (a base's lowest, completed to whole
degenerate pairs: the count is the liquid's). Build: `js.Stepper(scene)`; compile: the first
`advance` call less a timed run; step: the best of the timed runs per step; all in CPU time of this
process (`time.process_time`: other processes' load does not count, XLA's compiler threads do).
"""
from __future__ import annotations

import time

import jax

import jaxslosh as js
from benchmarks.harness import Table, machine, parser

SCENE = """
[environment]
gravity = 9.81
[simulation]
duration = 1.0
dt = 0.01
scheme = "newmark"
[vessel]
mass = 2.0e4
inertia = [2.0e4, 4.0e4, 4.0e4]
[vessel.hydrostatics]
waterplane_area = 20.0
displaced_volume = 21.5
gm_t = 1.0
gm_l = 3.0
[vessel.initial]
angular_velocity = [0.03, 0.05, 0.02]
velocity = [0.1, 0.05, 0.0]
[[tanks]]
name = "tank"
origin = [-0.6, -0.6, 0.0]
size = [1.2, 1.2, 1.2]
fill_depth = 0.6
model = "multimodal"
{shape}
expansion = "{expansion}"
modes = {modes}
"""
SHAPES = {"box": 'flow = "3d"', "cylinder": 'shape = "cylinder"\naxis = "z"'}


def measure(text: str, steps: int, repeats: int):
    """(modes, build s, compile s, step s), CPU time of this process."""
    c = time.process_time()
    stepper = js.Stepper(js.load_scene(text))
    build = time.process_time() - c
    c = time.process_time()
    state = jax.block_until_ready(stepper.init())
    jax.block_until_ready(stepper.advance(state, steps))
    first = time.process_time() - c
    runs = []
    for _ in range(repeats):
        c = time.process_time()
        end = jax.block_until_ready(stepper.advance(state, steps))
        runs.append(time.process_time() - c)
    assert stepper.status(end) == "ok", stepper.status(end)
    return stepper.built.system.liquid.nf, build, max(first - min(runs), 0.0), min(runs) / steps


def main():
    ap = parser(__doc__)
    ap.add_argument("--modes", type=int, default=6, help="the tanks' `modes` key (6)")
    ap.add_argument("--steps", type=int, default=None, help="steps per timed run (50; --quick: 5)")
    ap.add_argument("--repeats", type=int, default=2, help="timed runs, the best kept (2)")
    ap.add_argument("--expansion", default="exact,third-order", help="the expansions compared (exact,third-order)")
    args = ap.parse_args()
    steps = args.steps or (5 if args.quick else 50)
    expansions = args.expansion.split(",")
    table = Table(("tank", "{}"), ("expansion", "{}"), ("modes", "{:d}"), ("build s", "{:.1f}"),
                  ("compile s", "{:.1f}"), ("step ms", "{:.2f}"), ("step ms per mode", "{:.3f}"),
                  ("step / box's", "{:.2f}"), ("per mode / box's", "{:.2f}"),
                  title=f"CPU time of this process; {machine()}")
    for expansion in expansions:
        box = None
        for shape, line in SHAPES.items():
            n, build, comp, step = measure(SCENE.format(shape=line, expansion=expansion, modes=args.modes),
                                           steps, args.repeats)
            box = box or (n, step)
            table.add(shape, expansion, n, build, comp, 1e3 * step, 1e3 * step / n, step / box[1],
                      (step / n) / (box[1] / box[0]))
            print(f"{shape}, {expansion}: done", flush=True)
    table.print(args.markdown)


if __name__ == "__main__":
    main()
