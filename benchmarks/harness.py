"""What every benchmark script shares: one timing helper, one table printer, one argument parser.

    from benchmarks.harness import Table, parser, scene, time_scene

    args = parser(__doc__).parse_args()                   # --markdown, --quick
    table = Table(("case", "{}"), ("unknowns", "{:d}"), ("us/step", "{:.1f}"))
    r = time_scene("paper example", scene("paper_ship_tank"), steps=200 if args.quick else 2000)
    table.add(r.name, r.unknowns, r.us_per_step)
    table.print(markdown=args.markdown)                   # aligned text, or the docs' Markdown table

`time_scene` times a scene's step through the public `js.Stepper` (its `advance(state, n)`: n steps in
one compiled scan, keeping no frames), so every script measures the same thing the same way: the
first call's compilation apart from the run, the run's wall and this process's CPU time (other
processes' load does not count in the CPU time), best of `repeat` runs. Speed is measured here and
printed, never asserted (docs/benchmarks.md).
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import re
import sys
import time
from typing import Any, Optional, Sequence

import jax

jax.config.update("jax_enable_x64", True)

import jaxslosh as js  # noqa: E402

#: the repository root (scenes/, docs/): scripts run from it as `python -m benchmarks.speed.NAME`
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def scene(name: str) -> js.Scene:
    """A scene of the repository's scenes/ folder by name (`scene("paper_ship_tank")`)."""
    return js.load_scene(os.path.join(ROOT, "scenes", name if name.endswith(".toml") else name + ".toml"))


@dataclasses.dataclass(frozen=True)
class Record:
    """One timed scene: its step's cost and what it took to get there."""
    name: str
    unknowns: int            # the step's unknowns (rigid, liquid, structures)
    steps: int               # steps per timed run
    build_s: float           # js.Stepper(scene): the model and the solver's constant inverses
    compile_s: float         # init's and the first advance's call less one run: tracing and compiling
    run_s: float             # wall seconds of `steps` steps, best of `repeat`
    cpu_s: float             # this process's CPU seconds of the same runs, best of `repeat`
    ok: bool                 # no step failed

    @property
    def us_per_step(self) -> float:
        """Wall microseconds per step (best run)."""
        return 1e6 * self.run_s / self.steps

    @property
    def cpu_us_per_step(self) -> float:
        """This process's CPU microseconds per step (best run)."""
        return 1e6 * self.cpu_s / self.steps

    @property
    def steps_per_s(self) -> float:
        return self.steps / self.run_s


class _Timed:
    """A scene's stepper, compiled (its first call timed), then its runs timed one call at a time."""

    def __init__(self, name, scene, steps, params=None, dt=None):
        self.name, self.steps = name, int(steps)
        t0 = time.perf_counter()
        self.stepper = js.Stepper(scene, params, dt=dt)
        t1 = time.perf_counter()
        self.state = jax.block_until_ready(self.stepper.init())
        self.end = jax.block_until_ready(self.stepper.advance(self.state, self.steps))    # compiles, then runs
        self.build, self.first = t1 - t0, time.perf_counter() - t1
        self.wall, self.cpu = [], []

    def run(self):
        w, c = time.perf_counter(), time.process_time()
        self.end = jax.block_until_ready(self.stepper.advance(self.state, self.steps))
        self.wall.append(time.perf_counter() - w)
        self.cpu.append(time.process_time() - c)

    def record(self) -> Record:
        run = min(self.wall)
        return Record(name=self.name, unknowns=self.stepper.unknowns, steps=self.steps, build_s=self.build,
                      compile_s=max(self.first - run, 0.0), run_s=run, cpu_s=min(self.cpu),
                      ok=self.stepper.status(self.end) == "ok")


def time_scene(name: str, scene: js.Scene, steps: int, repeat: int = 2, *, params: Optional[dict] = None,
               dt: Optional[float] = None) -> Record:
    """Time `steps` steps of the scene (`params`, `dt` as for `js.Stepper`): build the stepper,
    compile and run once, then run `repeat` more times from the same start; the best wall and the
    best CPU time of those runs. Compile s is the first call's wall time less the best run's."""
    timed = _Timed(name, scene, steps, params, dt)
    for _ in range(max(1, repeat)):
        timed.run()
    return timed.record()


def time_scenes(cases: Sequence[tuple[str, js.Scene]], steps: int, repeat: int = 2, progress=None) -> list[Record]:
    """time_scene of several scenes, compiled all first and then timed round by round (each scene
    once per round), so that a shared machine's changing load falls on every scene alike.
    `progress(text)`, if given, hears of each compilation and round."""
    timed = []
    for name, sc in cases:
        timed.append(_Timed(name, sc, steps))
        if progress:
            progress(f"compiled {name}: {timed[-1].first:.2f} s")
    for k in range(max(1, repeat)):
        for t in timed:
            t.run()
        if progress:
            progress(f"round {k + 1} of {repeat} timed")
    return [t.record() for t in timed]


def best_of(fn, repeat: int = 3) -> tuple[float, float, Any]:
    """(best wall s, best CPU s, last result) of `repeat` calls of fn() (its result waited for): for
    scripts that time something other than a scene's step (a solve, a campaign, an export)."""
    wall, cpu, out = [], [], None
    for _ in range(max(1, repeat)):
        w, c = time.perf_counter(), time.process_time()
        out = jax.block_until_ready(fn())
        wall.append(time.perf_counter() - w)
        cpu.append(time.process_time() - c)
    return min(wall), min(cpu), out


#: a cell that is a number (a sign, digits, separators, an exponent, a unit of %, x or s after it)
_NUMBER = re.compile(r"^[+-]?(\d[\d,]*\.?\d*|\.\d+|nan|inf)(e[+-]?\d+)?( ?(%|x|s))?( FAILED)?$", re.IGNORECASE)


class Table:
    """Rows printed as aligned text (the default) or as a Markdown table (`--markdown`: what the
    docs' pages hold). Columns are (header, format) pairs; a cell that is a string is printed as it is."""

    def __init__(self, *columns: tuple[str, str], title: Optional[str] = None):
        self.headers = [h for h, _ in columns]
        self.formats = [f for _, f in columns]
        self.title = title
        self.rows: list[list[str]] = []

    def add(self, *cells: Any) -> None:
        if len(cells) != len(self.headers):
            raise ValueError(f"{len(cells)} cells for {len(self.headers)} columns ({', '.join(self.headers)})")
        self.rows.append([c if isinstance(c, str) else f.format(c) for c, f in zip(cells, self.formats)])

    def text(self, markdown: bool = False) -> str:
        rows = [self.headers] + self.rows
        widths = [max(len(r[i]) for r in rows) for i in range(len(self.headers))]
        # numbers right-aligned (a column of them), names and words left-aligned
        right = [bool(self.rows) and all(_NUMBER.match(r[i]) for r in self.rows if r[i])
                 for i in range(len(self.headers))]

        def line(r):
            return [c.rjust(w) if right[i] else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))]
        out = [] if self.title is None else [self.title, ""]
        if markdown:
            out.append("| " + " | ".join(line(self.headers)) + " |")
            out.append("|" + "|".join(("-" * (w + 1) + ":") if right[i] else (":" + "-" * (w + 1))
                                      for i, w in enumerate(widths)) + "|")
            out += ["| " + " | ".join(line(r)) + " |" for r in self.rows]
        else:
            out += ["  ".join(line(r)).rstrip() for r in rows]
        return "\n".join(out)

    def print(self, markdown: bool = False, file=None) -> None:
        print(self.text(markdown), file=file or sys.stdout, flush=True)


def parser(doc: Optional[str] = None) -> argparse.ArgumentParser:
    """The scripts' argument parser: the docstring's first paragraph as help, `--markdown` (the
    tables as the docs' Markdown) and `--quick` (a short run that checks the script still works; its
    numbers are not the page's)."""
    ap = argparse.ArgumentParser(description=(doc or "").strip().split("\n\n")[0] or None,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--markdown", action="store_true", help="print the tables as Markdown (docs/benchmarks.md)")
    ap.add_argument("--quick", action="store_true",
                    help="a short run (a few steps, the smallest cases) that checks the script still runs")
    return ap


def machine() -> str:
    """What the numbers were measured on (a line scripts print above their tables)."""
    return f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cpu"
