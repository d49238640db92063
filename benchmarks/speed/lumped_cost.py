"""What lumped mooring lines add to the paper example's step, per line and per segment.

    python -m benchmarks.speed.lumped_cost [--steps 200] [--rounds 5] [--markdown] [--quick]

The paper example (scenes/paper_ship_tank.toml) free and on lumped lines (`model = "lumped"`,
docs/guide/moorings-lumped.md) of the catenary lines of benchmarks/speed/mooring_cost.py (420 m,
600 N/m, EA 3e8 N, anchors 400 m out in 100 m of water, the lumped keys' defaults): one line and
three lines at 120 degrees, each of 10, 20 and 40 segments. Each scene's step is timed through
`js.Stepper.advance` (benchmarks/harness.py `time_scenes`: all compiled first, then the rounds
interleaved, the best kept), process CPU time. The table gives the sub-steps of the 0.01 s step
that the lines take (their stable explicit sub-step, `describe`), the CPU time per step, what the
lines add to the free step, and that added time per line and segment and per line, segment and
sub-step. No assertion.
"""
import numpy as np

from benchmarks.harness import Table, machine, parser, scene, time_scenes
from benchmarks.speed.mooring_cost import LINES
import jaxslosh as js
from jaxslosh.mooring.lumped_term import lumped_terms


def lumped(n_lines: int, segments: int) -> list:
    """The first n_lines of mooring_cost's lines (1: the one at 0 degrees), lumped in `segments`."""
    return [dict(line, model="lumped", segments=segments) for line in LINES[:n_lines]]


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--rounds", type=int, default=5)
    a = ap.parse_args()
    steps, rounds = (20, 1) if a.quick else (a.steps, a.rounds)
    shapes = [(1, 10), (3, 10)] if a.quick else [(n, s) for n in (1, 3) for s in (10, 20, 40)]
    free = scene("paper_ship_tank")
    cases = [("free", free)] + [(f"{n} x {s}", js.scene_with(free, {"environment.depth": 100.0,
                                                                       "mooring": lumped(n, s)}))
                                for n, s in shapes]
    records = time_scenes(cases, steps, repeat=rounds)
    base = records[0].cpu_us_per_step
    table = Table(("lines x segments", "{}"), ("sub-steps", "{}"), ("CPU us/step", "{:.1f}"),
                  ("added us/step", "{:.1f}"), ("added / free", "{:.2f}"),
                  ("us per line-segment", "{:.3f}"), ("ns per line-segment-substep", "{:.1f}"))
    table.add("free paper example", "", base, 0.0, 0.0, "", "")
    for (n, s), r in zip(shapes, records[1:]):
        sub = sorted({t.substeps for t in lumped_terms(js.Stepper(dict(cases)[f"{n} x {s}"]).built.system)})
        k = sub[0] if len(sub) == 1 else int(np.max(sub))
        added = r.cpu_us_per_step - base
        table.add(f"{n} x {s}" + ("" if r.ok else " FAILED"), str(k), r.cpu_us_per_step, added, added / base,
                  added / (n * s), 1e3 * added / (n * s * k))
    print(f"{machine()}; {steps} steps a round, best of {rounds} interleaved rounds (CPU time)")
    table.print(markdown=a.markdown)


if __name__ == "__main__":
    main()
