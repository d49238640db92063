"""Time the paper example (and the vessel alone): compilation apart from running, steps per second.

    python -m benchmarks.speed.bench_paper [--steps 2000] [--repeat 2] [--quick] [--markdown]

Issue item 3(a): compile time and steps per second for the vessel alone, the paper example
(5 x 5 x 5, full order and 20 sloshing modes), and meshes 10 x 10 x 6 and 20 x 20 x 12 (full order,
sparse, and 20 modes). Prints a table; no assertion (speed is measured here, never in tests). The
step is timed by benchmarks/harness.py (`js.Stepper.advance`: the steps of one compiled scan, no
frames kept).
"""

import jaxslosh as js
from benchmarks.harness import Table, machine, parser, scene, time_scene


def paper_variant(base: js.Scene, mesh=None, modes=None, dt=None, static_correction=True) -> js.Scene:
    """The paper scene with another liquid mesh, a modal reduction or another step."""
    keys = {}
    if mesh is not None:
        keys["tanks[0].mesh"] = list(mesh)
    if modes:
        keys["tanks[0].reduction.modes"] = modes
        keys["tanks[0].reduction.static_correction"] = bool(static_correction)
    if dt is not None:
        keys["simulation.dt"] = dt
    return js.scene_with(base, keys) if keys else base


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=2, help="timings per case; the best is shown (shared machine)")
    a = ap.parse_args()
    steps = 20 if a.quick and a.steps == 2000 else a.steps
    paper = scene("paper_ship_tank")
    cases = [("vessel alone", scene("vessel_only"), steps),
             ("paper example 5x5x5", paper, steps),
             ("paper, 20 modes", paper_variant(paper, modes=20), steps),
             ("paper, 20 modes, no s.c.", paper_variant(paper, modes=20, static_correction=False), steps),
             ("mesh 10x10x6", paper_variant(paper, mesh=(10, 10, 6)), min(steps, 400)),
             ("mesh 20x20x12", paper_variant(paper, mesh=(20, 20, 12)), min(steps, 60)),
             ("mesh 20x20x12, 20 modes", paper_variant(paper, mesh=(20, 20, 12), modes=20), steps)]
    if a.quick:
        cases = cases[:4]
    print(f"{machine()}; best of {a.repeat}\n")
    table = Table(("case", "{}"), ("unknowns", "{:d}"), ("compile s", "{:.2f}"), ("run s", "{:.3f}"),
                  ("steps/s", "{:.0f}"), ("us/step", "{:.1f}"), ("status", "{}"))
    for name, sc, n in cases:
        r = time_scene(name, sc, n, a.repeat)
        table.add(name, r.unknowns, r.compile_s, r.run_s, r.steps_per_s, r.us_per_step, "ok" if r.ok else "FAILED")
    table.print(a.markdown)


if __name__ == "__main__":
    main()
