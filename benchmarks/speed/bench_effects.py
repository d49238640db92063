"""Compile time and step cost per set of effects: what each `[effects]` switch costs, in one run.

    python -m benchmarks.speed.bench_effects [--steps 500] [--repeat 5] [--quick]

Issue 8 ("a scene simulates only the effects it calls for"): the vessel alone, the paper example
with every effect and with Coriolis, centrifugal, gravity turning (each, then all three) or the
liquid switched off, the paper ship in waves with and without the radiation and the wave forces,
and the paper ship with its flexible mast. Each row is the scene's TOML with an `[effects]` table
appended (`js.scene_with`). Columns: the effects simulated (as `jaxslosh check` names them; the
rigid body's inertia is in every row and left out), the unknowns per step, the host-side build
(`js.Stepper`), the compile time (`init` plus the first `advance` call, less the run time of that
call), the cost of a step after compilation (best of `--repeat` calls of `--steps` steps each;
every row is compiled first, then the rows are timed round by round, so that a shared machine's
changing load falls on all of them alike: benchmarks/harness.py's time_scenes) and its ratio to
the paper example with every effect. `--quick`: five rows, 20 steps, best of 2. Prints a Markdown
table (progress on stderr); no assertion (speed is measured here, never in tests). The internal
`assemble` imports name the effects and count the unknowns as `jaxslosh check` does.
"""
import os
import sys
import time


import jaxslosh as js
from jaxslosh.assemble.check import model_effects          # what `jaxslosh check` lists
from jaxslosh.assemble.effects import count_unknowns
from jaxslosh.assemble.system import outline
from benchmarks.harness import Table, machine, parser, scene, time_scenes

REFERENCE = "paper, all effects"

# (row label, scene file, effects switched off, in the quick run)
ROWS = [
    ("vessel only", "vessel_only.toml", (), True),
    ("vessel, buoyancy off", "vessel_only.toml", ("buoyancy",), False),
    (REFERENCE, "paper_ship_tank.toml", (), True),
    ("paper, coriolis off", "paper_ship_tank.toml", ("coriolis",), False),
    ("paper, centrifugal off", "paper_ship_tank.toml", ("centrifugal",), False),
    ("paper, gravity_turning off", "paper_ship_tank.toml", ("gravity_turning",), False),
    ("paper, all three off", "paper_ship_tank.toml", ("coriolis", "centrifugal", "gravity_turning"), True),
    ("paper, liquid off", "paper_ship_tank.toml", ("liquid",), True),
    ("waves, all effects", "paper_ship_waves.toml", (), True),
    ("waves, radiation off", "paper_ship_waves.toml", ("radiation",), False),
    ("waves, waves off", "paper_ship_waves.toml", ("waves",), False),
    ("waves, both off", "paper_ship_waves.toml", ("waves", "radiation"), False),
    ("mast (flexible structure)", "paper_ship_mast.toml", (), False),
]


def load_variant(filename, off):
    """The scene file with an `[effects]` table switching `off` off (no scene here has one)."""
    sc = scene(filename)
    if off and sc.text and "[effects]" in sc.text:
        raise ValueError(f"{filename} has its own [effects] table: cannot add one")
    return js.scene_with(sc, {f"effects.{k}": False for k in off}) if off else sc


def effects_column(scene):
    """The effects `check` lists for the scene's model (its terms' own lines), but the hull's inertia
    and the liquid element's rotation penalty, which every row with liquid has."""
    names = [name for name, _, _ in model_effects(outline(scene))
             if name not in ("rigid-body inertia", "rotation penalty")]
    return ", ".join(names) or "-"


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, help="steps per timed call (default 500, 20 with --quick)")
    ap.add_argument("--repeat", type=int, help="timed calls per row; the best is shown (default 5, 2 with --quick)")
    a = ap.parse_args()
    steps = a.steps or (20 if a.quick else 500)
    repeat = a.repeat or (2 if a.quick else 5)
    if steps < 1 or repeat < 1:
        ap.error("--steps and --repeat must be at least 1")
    rows = [r for r in ROWS if r[3] or not a.quick]
    print(f"{machine()}, float64; {steps} steps per call, best of {repeat}")
    t_all = time.perf_counter()
    scenes = [(label, load_variant(filename, off)) for label, filename, off, _ in rows]
    records = time_scenes(scenes, steps, repeat, progress=lambda text: print("  " + text, file=sys.stderr))
    ref_us = next((r.us_per_step for r in records if r.name == REFERENCE), None)
    print()
    table = Table(("scene", "{}"), ("effects simulated", "{}"), ("unknowns", "{:d}"), ("build s", "{:.2f}"),
                  ("compile s", "{:.2f}"), ("us/step", "{}"), ("ratio", "{}"))
    for (label, filename, _, _), (_, sc), r in zip(rows, scenes, records):
        table.add(f"{label} (`{filename}`)", effects_column(sc), count_unknowns(sc), r.build_s, r.compile_s,
                  f"{r.us_per_step:.1f}" + ("" if r.ok else " FAILED"),
                  f"{r.us_per_step / ref_us:.3f}" if ref_us else "-")
    table.print(a.markdown)
    print()
    load = f"; load average {os.getloadavg()[1]:.1f} over the last 5 min" if hasattr(os, "getloadavg") else ""
    print(f"total {time.perf_counter() - t_all:.0f} s{load}; compile s = init + first advance less its run time; "
          f"ratio = us/step over the row {REFERENCE!r}")


if __name__ == "__main__":
    main()
