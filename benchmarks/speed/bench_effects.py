"""Compile time and step cost per set of effects: what each `[effects]` switch costs, in one run.

    python benchmarks/bench_effects.py [--steps 500] [--repeat 5] [--quick]

Issue 8 ("a scene simulates only the effects it calls for"): the vessel alone, the paper example
with every effect and with Coriolis, centrifugal, gravity turning (each, then all three) or the
liquid switched off, the paper ship in waves with and without the radiation and the wave forces,
and the paper ship with its flexible mast. Each row is the scene's TOML with an `[effects]` table
appended. Columns: the effects simulated (as `jaxslosh check` names them; the rigid body's inertia
is in every row and left out), the unknowns per step, the host-side build (`prepare`), the compile
time (`start` plus the first `advance` call, less the run time of that call: each timed apart,
`block_until_ready`), the cost of a step after compilation (best of `--repeat` calls of `--steps`
steps each; every row is compiled first, then the rows are timed round by round, so that a shared
machine's changing load falls on all of them alike) and its ratio to the paper example with every
effect. `--quick`: five rows, 200 steps, best of 2. Prints a Markdown table (progress on stderr);
no assertion (speed is measured here, never in tests).
"""
import argparse
import os
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)

import jaxslosh as js  # noqa: E402
from jaxslosh.assemble.check import model_effects  # noqa: E402
from jaxslosh.assemble.effects import count_unknowns  # noqa: E402
from jaxslosh.assemble.system import outline  # noqa: E402
from jaxslosh.run.loop import core as _core, advance, start  # noqa: E402
from jaxslosh.run.simulate import prepare
from jaxslosh.scene.keys import with_overrides
from jaxslosh.scene.load import tomllib  # noqa: E402  (tomli before Python 3.11)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
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
    path = os.path.join(ROOT, "scenes", filename)
    text = open(path).read()
    if off:
        if "effects" in tomllib.loads(text):
            raise ValueError(f"{filename} has its own [effects] table: cannot append one")
        text += "\n[effects]\n" + "".join(f"{k} = false\n" for k in off)
    return js.load_scene(text)


def effects_column(scene):
    """The effects `check` lists for the scene's model (its terms' own lines), but the hull's inertia
    and the liquid element's rotation penalty, which every row with liquid has."""
    names = [name for name, _, _ in model_effects(outline(scene))
             if name not in ("rigid-body inertia", "rotation penalty")]
    return ", ".join(names) or "-"


class Row:
    """One scene compiled: its build and compile times, then the runs timed round by round."""

    def __init__(self, label, filename, scene, steps):
        self.label, self.filename, self.scene, self.steps = label, filename, scene, steps
        t0 = time.perf_counter()
        setup = prepare(with_overrides(scene, duration=steps * scene.simulation.dt))
        self.b, self.solver = _core(setup.built), setup.solver
        t1 = time.perf_counter()
        self.carry, f0 = start(self.b, self.solver)
        jax.block_until_ready(f0)
        t2 = time.perf_counter()
        first = self._run()                            # first call: compile + run
        self.build, self.start, self.first = t1 - t0, t2 - t1, first
        self.runs = []

    def _run(self):
        s = time.perf_counter()
        c, fr = advance(self.b, self.solver, self.carry, self.steps, 1)
        jax.block_until_ready(fr)
        t = time.perf_counter() - s
        self.iters, self.ok = float(fr.iterations.mean()), not bool(c.failed)
        return t

    def time_run(self):                                # compiled: run only
        self.runs.append(self._run())

    @property
    def us(self):
        return 1e6 * min(self.runs) / self.steps

    @property
    def compile(self):
        return self.start + max(0.0, self.first - min(self.runs))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, help="steps per timed call (default 500, 200 with --quick)")
    ap.add_argument("--repeat", type=int, help="timed calls per row; the best is shown (default 5, 2 with --quick)")
    ap.add_argument("--quick", action="store_true", help="five rows, fewer steps")
    a = ap.parse_args()
    steps = a.steps or (200 if a.quick else 500)
    repeat = a.repeat or (2 if a.quick else 5)
    if steps < 1 or repeat < 1:
        ap.error("--steps and --repeat must be at least 1")
    rows = [r for r in ROWS if r[3] or not a.quick]
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cpu, float64; "
          f"{steps} steps per call, best of {repeat}")
    t_all = time.perf_counter()
    done = []
    for label, filename, off, _ in rows:               # compile every row first
        done.append(Row(label, filename, load_variant(filename, off), steps))
        print(f"  compiled {label}: {done[-1].start + done[-1].first:.2f} s", file=sys.stderr)
    for k in range(repeat):                            # then time them round by round: a shared machine's
        for row in done:                               # load falls on every row alike
            row.time_run()
        print(f"  round {k + 1} of {repeat} timed", file=sys.stderr)
    ref_us = next((row.us for row in done if row.label == REFERENCE), None)
    print()
    print("| scene | effects simulated | unknowns | build s | compile s | us/step | Newton it | ratio |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for row in done:
        ratio = f"{row.us / ref_us:.3f}" if ref_us else "-"
        flag = "" if row.ok else " FAILED"
        print(f"| {row.label} (`{row.filename}`) | {effects_column(row.scene)} | {count_unknowns(row.scene)} | "
              f"{row.build:.2f} | {row.compile:.2f} | {row.us:.1f}{flag} | {row.iters:.2f} | {ratio} |")
    print()
    load = f"; load average {os.getloadavg()[1]:.1f} over the last 5 min" if hasattr(os, "getloadavg") else ""
    print(f"total {time.perf_counter() - t_all:.0f} s{load}; compile s = start + first advance less its run time; "
          f"ratio = us/step over the row {REFERENCE!r}")


if __name__ == "__main__":
    main()
