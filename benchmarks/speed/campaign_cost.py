"""What a campaign case costs against the stepping of a plain run of the same scene, in one process.

    python -m benchmarks.speed.campaign_cost [--duration 600] [--batch 8] [--repeat 2]
        [--parallel [--cases 80]] [--quick]

The scene is benchmarks/speed/campaign.py's (scenes/paper_ship_waves.toml: the paper ship, its tank on 20
modes, Froude-Krylov forces on its box, a yaw damping), its cases that benchmark's scatter x 5
headings x 2 seeds. In one process, compilation excluded from both (each is called once first):

* the plain run: the first case's steps by `js.Stepper.advance` (one compiled scan, no frames
  kept), stepping alone (the initial state and the result's assembly left out);
* a campaign batch: `campaign.worker.run_batch` of `--batch` cases as a Dask worker runs it (the
  cases' scenes, their seas drawn on the host, the vmapped loop, the result, the statistics),
  each phase timed; each repeat runs the campaign's next `--batch` cases in its order (the first
  batch is the warm-up), as a worker meets them.

Printed: each phase per case, the per-case cost / plain-run stepping ratio (wall and this process's
CPU time: on a busy machine the wall clock counts other jobs' time, the CPU time much less of it),
the batch's first call (its compilation: each worker pays it once per sea structure, or reads it
from the persistent cache), and the three-hour sea states per core-hour at the measured CPU time per
case (the record scaled to 216,000 steps; what a case's host work adds does not grow with the
record, so this is a lower bound), with the plain run's step as the bound it approaches.

`--parallel`: campaigns of about `--cases` and twice as many cases on a LocalCluster of 1, then 2
workers (one thread each, a shared persistent compilation cache filled by a first run); the parallel
efficiency of whole campaigns (1-worker wall / (2 x 2-worker wall)) and of the throughput past the
campaign's start-up (the extra cases over the extra wall time, 2 workers against twice 1): meaningful
only on an idle machine with 2 free cores.
The batch's phases are timed one by one through the campaign worker's own pieces
(jaxslosh.campaign.worker, campaign.cases, campaign.stats, and run/batch.py's `_setup0`,
`_batch_fn`, `_batch_result`): internals, as no public API splits a batch into its phases.
`--quick`: 2 cases of 22 s per batch, one repeat. No assertion.
"""
import os
import tempfile
import time

import jax
import numpy as np

import jaxslosh as js
from jaxslosh.campaign import worker
from jaxslosh.campaign.cases import case_scene, case_values, make_cases, read_scatter, sea_arrays
from jaxslosh.campaign.stats import case_statistics, channels
from jaxslosh.run.batch import _batch_fn, _batch_result, _setup0      # a batch's phases, one by one
from benchmarks.harness import parser
from benchmarks.speed.campaign import campaign_scene, scatter_csv

SEA_STATE_S = 3 * 3600.0


class Clock:
    """Wall and process CPU seconds of each named phase."""

    def __init__(self):
        self.wall, self.cpu = {}, {}

    def __call__(self, name, f):
        t0, c0 = time.perf_counter(), time.process_time()
        out = jax.block_until_ready(f())
        self.wall[name] = self.wall.get(name, 0.0) + time.perf_counter() - t0
        self.cpu[name] = self.cpu.get(name, 0.0) + time.process_time() - c0
        return out


def batch(scene, values, duration, B, clock):
    """run_batch's phases (campaign/worker.py), each timed."""
    template = clock("template", lambda: worker.template_scene(scene.text, scene.path, duration))
    scenes = clock("case scenes", lambda: [case_scene(template, v, duration) for v in values])
    seas = clock("seas (host)", lambda: [sea_arrays(s) for s in scenes])
    seas = seas + [seas[-1]] * (B - len(seas))
    arrays = [np.stack([s[k] for s in seas]) for k in range(4)]
    ss = worker.structure_scene(template, scenes[0])
    setup0 = clock("model (kept)", lambda: _setup0(ss))
    fn = _batch_fn(ss, (), None, excited=True)
    carry, fr = clock("loop (vmapped)", lambda: fn(*[jax.numpy.asarray(a, dtype=float) for a in arrays]))
    result, statuses = clock("result", lambda: _batch_result(ss, setup0, carry, fr, B))
    t = np.asarray(result.time)
    clock("statistics", lambda: [case_statistics(t[i], channels(result, i), s.waves.ramp)
                                 for i, s in enumerate(scenes)])
    return statuses


def parallel(scene_path, csv_path, heads, a):
    from jaxslosh.campaign.run import campaign
    cache = tempfile.mkdtemp(prefix="jaxslosh-campaign-cache-")
    per = max(1, a.cases // (len(heads) * 2))
    kw = dict(headings=heads, seeds=2, duration=a.duration, batch=a.batch, progress=False, cache_dir=cache)
    with open(csv_path) as f:
        rows = f.read().splitlines()
    subs = {}
    for m in (1, 2):
        subs[m] = csv_path + f".sub{m}.csv"
        with open(subs[m], "w") as f:
            f.write("\n".join(rows[:1 + m * per]) + "\n")
    campaign(scene_path, subs[1], workers=1, **kw)     # fills the cache: every run then loads the program
    walls, n = {}, {}
    for w in (1, 2):
        for m in (1, 2):
            t0 = time.perf_counter()
            r = campaign(scene_path, subs[m], workers=w, **kw)
            walls[w, m] = time.perf_counter() - t0
            n[m] = r.cases.n
            print(f"  {w} worker(s): {r.cases.n} cases, {walls[w, m]:.1f} s wall, {r.failed} failed, "
                  f"load average {os.getloadavg()[0]:.1f}")
    # a campaign's wall = its start-up (the cluster, the workers' imports, the program's load) plus
    # its cases; the start-up does not grow with the campaign, so the throughput that scales is the
    # marginal one: the extra cases over the extra wall time
    dn = n[2] - n[1]
    rate = {w: dn / (walls[w, 2] - walls[w, 1]) for w in (1, 2)}
    for w in (1, 2):
        print(f"  {w} worker(s): start-up {walls[w, 1] - n[1] / rate[w]:.1f} s, "
              f"then {rate[w]:.2f} cases/s")
    print(f"  parallel efficiency, whole campaigns of {n[1]} cases (1-worker wall / (2 x 2-worker wall)): "
          f"{walls[1, 1] / (2 * walls[2, 1]):.2f}; of {n[2]} cases: {walls[1, 2] / (2 * walls[2, 2]):.2f}")
    print(f"  parallel efficiency of the throughput past start-up (2-worker rate / (2 x 1-worker rate)): "
          f"{rate[2] / (2 * rate[1]):.2f} (goal 0.90; meaningful on an idle machine only)")


def main(argv=None):
    p = parser(__doc__)
    p.add_argument("--duration", type=float, default=600.0)
    p.add_argument("--batch", type=int, default=8)
    p.add_argument("--repeat", type=int, default=2)
    p.add_argument("--parallel", action="store_true")
    p.add_argument("--cases", type=int, default=80)
    a = p.parse_args(argv)
    if a.quick:
        a.duration, a.batch, a.repeat = 22.0, 2, 1       # just past the waves' 20 s ramp
    d = tempfile.mkdtemp()
    scene_path, csv_path = os.path.join(d, "ship.toml"), os.path.join(d, "scatter.csv")
    with open(scene_path, "w") as f:
        f.write(campaign_scene().text)
    with open(csv_path, "w") as f:
        f.write(scatter_csv(20))
    scene = js.load_scene(scene_path)
    heads = np.linspace(0.0, np.pi, 5)
    cases = make_cases(read_scatter(csv_path), heads, 2, scene.waves.seed)
    # batch k holds cases k B .. (k + 1) B - 1, as a campaign's batches do (cell-major: a batch's
    # cases share a few sea states); the first is the warm-up, each repeat runs the next
    batches = [[case_values(cases, i % cases.n) for i in range(k * a.batch, (k + 1) * a.batch)]
               for k in range(a.repeat + 1)]
    values = batches[0]
    steps = int(round(a.duration / scene.simulation.dt))
    print(f"{os.cpu_count()} cores, load average {' '.join(f'{x:.1f}' for x in os.getloadavg())}; "
          f"{a.batch} cases of {a.duration:g} s ({steps} steps) per batch")

    s0 = case_scene(scene, values[0], a.duration)
    t0 = time.perf_counter()
    stepper = js.Stepper(s0)
    start = stepper.init()
    jax.block_until_ready(stepper.advance(start, steps))
    print(f"plain run: build, compile and a first run {time.perf_counter() - t0:.1f} s")
    t0 = time.perf_counter()
    batch(scene, values, a.duration, a.batch, Clock())
    print(f"campaign batch: first call (the worker's compilation and one batch) {time.perf_counter() - t0:.1f} s")

    best = None
    for rep in range(a.repeat):
        plain = Clock()
        plain("stepping", lambda: stepper.advance(start, steps))
        clock = Clock()
        statuses = batch(scene, batches[rep + 1], a.duration, a.batch, clock)
        pw, pc = plain.wall["stepping"], plain.cpu["stepping"]
        bw, bcpu = sum(clock.wall.values()) / a.batch, sum(clock.cpu.values()) / a.batch
        print(f"repeat {rep + 1}: plain run stepping {pw:.3f} s wall, {pc:.3f} s CPU "
              f"({1e6 * pc / steps:.1f} us CPU per step); load average {os.getloadavg()[0]:.1f}")
        print(f"  {'per case':22} {'wall s':>8} {'CPU s':>8} {'/ plain (CPU)':>14}")
        for k in clock.wall:
            print(f"  {k:22} {clock.wall[k] / a.batch:8.4f} {clock.cpu[k] / a.batch:8.4f} "
                  f"{clock.cpu[k] / a.batch / pc:14.3f}")
        print(f"  {'total':22} {bw:8.4f} {bcpu:8.4f} {bcpu / pc:14.3f}   (wall ratio {bw / pw:.3f}); "
              f"{sum(s == 'ok' for s in statuses)} of {len(statuses)} ok")
        if best is None or bcpu / pc < best[0]:
            best = (bcpu / pc, bcpu, pc)
    ratio, bcpu, pc = best
    scale = SEA_STATE_S / a.duration
    print(f"per-case cost / plain-run stepping (CPU, best of {a.repeat}): {ratio:.2f} (goal at most 1.5)")
    print(f"three-hour sea states per core-hour: {3600 / (bcpu * scale):.0f} at the campaign's CPU time per case "
          f"({bcpu * scale:.1f} core-s per sea state); the plain run's step alone: {3600 / (pc * scale):.0f} "
          f"({1e6 * pc / steps:.1f} us per step; 1,000 needs 16.7 us)")
    if a.parallel:
        print("parallel efficiency, a campaign on a LocalCluster:")
        parallel(scene_path, csv_path, heads, a)


if __name__ == "__main__":
    main()
