"""The shaped tanks at full order against their floor, each element and linear solver beside the
default, and the shapes on 20 modes against the box (issue 47 item 1).

    python -m benchmarks.speed.shapes_floor [--steps 200] [--repeat 3] [--solvers ...] [--no-modes]
        [--breakdown] [--quick] [--markdown]        (--solvers "": the 20-mode table alone)

The paper ship carrying one tank of each shape (benchmarks/speed/shapes.py: prismatic 4x12x8,
vertical cylinder 8x8x5, horizontal cylinder 6x12x6, about the paper tank's 75 m^3 of water) at full
order, each with the default element ("rt" on these shapes) and the scene's default solver, and
with the other `--solvers` (`rt-dense`: `linear_solver = "dense"`; `stabilized`, `stabilized-dense`,
`stabilized-sparse`, `stabilized-host`: the nodal element with "auto", "dense", "sparse" and
"sparse-host"). Every row's floor is three pre-factored dense solves of its own unknowns per step
(benchmarks/speed/floor.py: products with a pre-formed inverse in a `lax.scan`), timed in the same
process. The scenes are compiled first, then timed round by round (benchmarks/harness.py
time_scenes: best of `--repeat`); us/step is this process's CPU time per step (a loaded machine
disturbs it far less than the wall clock, which is printed beside it). Then, unless `--no-modes`,
the box and the three shapes on 20 modes, each against the box.

`--breakdown`: for the default element of each shape, the Newton iterations and preconditioner
formations per step and the step's pieces each timed alone at a state of the running scene
(floor.py's `pieces`: the residual, the preconditioner applied and formed), as floor.py prints
them for the paper example. Prints tables; no assertion.
"""
import time

import jax

import jaxslosh as js
from benchmarks.harness import Table, machine, parser, scene, time_scenes
from benchmarks.speed.bench_paper import paper_variant
from benchmarks.speed.floor import counts, floors, pieces
from benchmarks.speed.shapes import shape_scene

#: the three shapes of issue 47, as benchmarks/speed/shapes.py gives them
SHAPES = {
    "prismatic 4x12x8": ({"shape": "prismatic", "chamfers": [[1.5, 1.0], [1.5, 1.0]]},
                         [4.0, 6.0, 4.0], [4, 12, 8], 3.5, [-2.0, -3.0, -1.0]),
    "vertical cylinder 8x8x5": ({"shape": "cylinder", "axis": "z"}, [5.6, 5.6, 4.0], [8, 8, 5], 3.0,
                                [-2.8, -2.8, -1.0]),
    "horizontal cylinder 6x12x6": ({"shape": "cylinder", "axis": "x"}, [6.0, 4.0, 4.0], [6, 12, 6], 2.0,
                                   [-3.0, -2.0, -1.0]),
}
#: solver rows: (element, linear_solver) keys, None leaving the scene's default
SOLVERS = {"default": (None, None), "rt-dense": ("rt", "dense"), "stabilized": ("stabilized", None),
           "stabilized-dense": ("stabilized", "dense"), "stabilized-sparse": ("stabilized", "sparse"),
           "stabilized-host": ("stabilized", "sparse-host")}


def variant(sc: js.Scene, solver: str) -> js.Scene:
    element, linear = SOLVERS[solver]
    keys = {}
    if element is not None:
        keys["tanks[0].fluid.element"] = element
    if linear is not None:
        keys["simulation.linear_solver"] = linear
    return js.scene_with(sc, keys) if keys else sc


def floor_us(n: int, steps: int, repeat: int) -> float:
    """CPU us per step of three products with a pre-formed n x n inverse (floor.py's floor)."""
    f = floors(n, steps)[0]
    jax.block_until_ready(f())
    best = float("inf")
    for _ in range(repeat):
        t = time.process_time()
        jax.block_until_ready(f())
        best = min(best, time.process_time() - t)
    return 1e6 * best / steps


def breakdown(name: str, sc: js.Scene, n: int, rounds: int) -> list:
    """(unknowns, its, formations, R us, P applied us, P formed us, step us) of the scene's step,
    floor.py's way."""
    stepper = js.Stepper(sc)
    b, solver = stepper.built, stepper.solver
    carry = stepper.init()
    mid = stepper.advance(carry, 100)
    its, formed = counts(stepper, carry, 200)
    residual, apply, form, _ = pieces(b, solver, mid.s, n)
    timed = {"R": lambda: residual(b, solver, mid.s), "P": lambda: apply(b, solver, mid.s),
             "form": lambda: form(b, solver, mid.s), "step": lambda: stepper.advance(mid, n)}
    for f in timed.values():
        jax.block_until_ready(f())
    best = {k: float("inf") for k in timed}
    for _ in range(rounds):
        for k, f in timed.items():
            t = time.process_time()
            jax.block_until_ready(f())
            best[k] = min(best[k], 1e6 * (time.process_time() - t) / n)
    return [stepper.unknowns, its, formed, best["R"], best["P"], best["form"], best["step"]]


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--solvers", default="default,rt-dense,stabilized,stabilized-dense,stabilized-host")
    ap.add_argument("--shapes", default=",".join(SHAPES), help="a comma-separated subset of the shapes' names")
    ap.add_argument("--no-modes", action="store_true", help="leave out the 20-mode table")
    ap.add_argument("--breakdown", action="store_true", help="the default element's step, piece by piece")
    a = ap.parse_args()
    if a.quick:            # the prismatic tank, its default element, a few steps, no modes
        a.steps, a.repeat, a.solvers, a.shapes, a.no_modes = 5, 1, "default", "prismatic 4x12x8", True
    base = scene("paper_ship_tank")
    shapes = {k: shape_scene(base, *SHAPES[k]) for k in a.shapes.split(",")}
    # `--solvers ""`: the 20-mode table alone
    cases = [(f"{k} | {s}", variant(sc, s)) for k, sc in shapes.items() for s in a.solvers.split(",") if s]
    print(f"{machine()}; {a.steps} steps per run, best of {a.repeat} rounds; CPU time of this process\n", flush=True)
    records = time_scenes(cases, a.steps, a.repeat, progress=lambda t: print("  " + t, flush=True))
    fl = {n: floor_us(n, a.steps, a.repeat) for n in sorted({r.unknowns for r in records})}
    table = Table(("tank, full order", "{}"), ("element, solver", "{}"), ("unknowns", "{:,}"),
                  ("compile s", "{:.1f}"), ("us/step CPU", "{:,.0f}"), ("us/step wall", "{:,.0f}"),
                  ("floor us", "{:,.0f}"), ("x floor", "{:.2f}"))
    for (name, _), r in zip(cases, records):
        shape, solver = name.split(" | ")
        table.add(shape, solver + ("" if r.ok else " FAILED"), r.unknowns, r.compile_s, r.cpu_us_per_step,
                  r.us_per_step, fl[r.unknowns], r.cpu_us_per_step / fl[r.unknowns])
    if cases:
        table.print(a.markdown)
    if a.breakdown:
        rows = Table(("tank, default element", "{}"), ("Newton its/step", "{:.2f}"), ("formed/step", "{:.3f}"),
                     ("R us", "{:.0f}"), ("P applied us", "{:.0f}"), ("P formed us", "{:,.0f}"),
                     ("(its+1) R + its P + formed", "{:,.0f}"), ("step us", "{:,.0f}"), ("x floor", "{:.2f}"),
                     title="\nThe default element's step, piece by piece (CPU us)")
        for k, sc in shapes.items():
            n, its, formed, R, P, form, step = breakdown(k, sc, a.steps, a.repeat)
            rows.add(k, its, formed, R, P, form, (its + 1) * R + its * P + formed * form, step,
                     step / fl.get(n, floor_us(n, a.steps, a.repeat)))
        rows.print(a.markdown)
    if a.no_modes:
        return
    modal = [("box 5x5x5 (paper)", paper_variant(base, modes=20))] + \
        [(k, paper_variant(sc, modes=20)) for k, sc in shapes.items()]
    recs = time_scenes(modal, a.steps, a.repeat, progress=lambda t: print("  " + t, flush=True))
    box = recs[0].cpu_us_per_step
    table = Table(("tank, 20 modes", "{}"), ("unknowns", "{:d}"), ("compile s", "{:.1f}"), ("us/step CPU", "{:.1f}"),
                  ("us/step wall", "{:.1f}"), ("x box", "{:.2f}"), title="")
    for (name, _), r in zip(modal, recs):
        table.add(name + ("" if r.ok else " FAILED"), r.unknowns, r.compile_s, r.cpu_us_per_step, r.us_per_step,
                  r.cpu_us_per_step / box)
    table.print(a.markdown)


if __name__ == "__main__":
    main()
