"""A campaign on a local Dask cluster against the same cases one by one in one process.

    python -m benchmarks.speed.campaign [--cells 20] [--headings 5] [--seeds 2] [--duration 600]
        [--workers 2] [--batch 8[,1,...]] [--serial-cases N | --skip-serial] [-o CAMPAIGN.h5 [--resume]]
        [--nonlinear] [--hs 1.0,1.5] [--tp 5,6] [--yaw-damping 0] [--components 50] [--moored] [--quick]

Issue 19 item 5: the paper's ship in irregular seas (scenes/paper_ship_waves.toml, its tank reduced
to 20 modes without static correction, the wave forces Froude-Krylov on its box so that every
heading is allowed), `cells` sea states x `headings` (0 to pi) x `seeds`, 600 s each at dt 0.05 s.

The sea states and the one change to the scene, so that no case fails:

* Hs 0.2, 0.4, 0.6, 0.8 m x Tp 5, 6, 7, 8, 9 s (20 cells; `--cells` takes the first n). The box's
  pitch is resonant at 1.1 rad/s (5.7 s) with 1.6 % of critical radiation damping and nothing
  viscous (its pitch RAO there is 3.0 rad/m, js.rao), so pitch grows to 0.38 rad in Hs 0.5 m and 0.71 rad in
  Hs 1 m; with the ship free in yaw, in following and oblique seas from Hs 1 m that large pitch
  turns it round (yaw to 180 deg) and the step fails (23 of the 40 cases in Hs 0.5-2 m of the
  first version of this benchmark).
* A linear yaw damping B66 = 2e6 N m s in [vessel.hydrodynamics] viscous_damping (the yaw's time
  constant (I_zz + A66) / B66 about 10 s): a stand-in for what holds a ship's heading (a soft
  mooring, an autopilot), which the scene format has only as damping: the hull's radiation yaw
  damping is below 1e5 N m s under 1.1 rad/s, and nothing restores yaw. Measured on 30 of the
  cases per Hs (Tp 5-9 s, headings 0, pi/4, pi/2, seeds 1-2, single runs): without it none fails
  in Hs 0.5 m and 4 in Hs 1 m; with it none in Hs 0.8 or 1 m (largest yaw 1.35 rad there) and 1 in
  Hs 1.25 m. Hs 0.8 m keeps a margin below that: there the largest roll, pitch and yaw of those 30
  cases are 0.27, 0.59 and 0.66 rad, motions past the linear hydrostatics' range, but every step
  converges.

`--nonlinear` gives the box its deck (depth 5 m) and `[vessel.hydrostatics] model = "nonlinear"`:
restoring and Froude-Krylov forces from the pressure on the instantaneous wetted surface (the
still water's and the incident waves', Wheeler-stretched), so that the large pitch of the higher
sea states stays within the model; a case that passes the hull's angle of vanishing stability is
counted as capsized. `--hs`/`--tp` set the scatter's rows and columns, `--yaw-damping 0` frees
the yaw, `--components` thins the sea (the wave pressure on the hull costs in proportion to the
components times the panels).

`--moored` holds the ship on three catenary lines instead of the yaw damper (which it sets to 0):
the water 50 m deep, anchors 240 m out at 180, 300 and 60 degrees, fairleads 5 m from the COG
towards them and 2 m below it, 258 m of chain of 300 N/m submerged, EA 5e8 N. Their stiffness
(`jaxslosh mooring`) with the box's added mass at 0.1 rad/s gives natural periods of about 100 s
in surge, 110 s in sway and 70 s in yaw (printed). The campaign then has the lines' fairlead
tensions as channels `mooring.line1` to `mooring.line3`.

`--command`: the campaign as users run it, `python -m jaxslosh campaign SCENE --scatter ... --workers W
--batch B --duration D` in a subprocess (its own compilation cache folder, filled by a first run of
the same campaign that is not counted), with 1 worker, then 2 workers, each `--repeat` times (the
best kept). Printed per row: the whole command's wall time (Python's start, the imports, the scene,
the cases, writing) and CPU time (the command and the processes it waited for), per case, the
phases of the command's own summary line, the three-hour sea states per core-hour (3600 s /
(the time per case x 10800 s / D) per core: one worker has one core, two workers two) and the
2-worker efficiency (1-worker wall / (2 x 2-worker wall)); then the vmapped loop's CPU time per
case-step (`campaign.worker.run_batch` of the first B cases in this process, its program read
back from the same cache) and the command's wall time beyond it. The issue's campaign:
`--command --cells 16 --headings 2 --seeds 1 --batch 4` (32 cases of 600 s).

The scene's [campaign] table holds the operability limits (roll 0.1 rad, pitch 0.1 rad, probe B
0.5 m), so the campaign runs with them and writes its operability.

Rows: the Dask LocalCluster (`workers` processes of one thread each) for each `--batch`, writing
the campaign file, and the same cases one by one in one process (a batch of one each, one
compilation) pinned to one core (its XLA threads cannot use a second one), all in one sitting,
compilation included in every row. Cases per core-hour: cases / (wall x cores). Then the
campaign file is checked (every case "ok", statistics finite), the serial loop's statistics are
compared with the cluster's, and the throughput of a 300-cell scatter of 3-hour sea states on 100
cores is projected from each row. `--serial-cases N` runs N of the cases (evenly spaced) one by
one instead of all. `--quick`: 2 cases of 22 s (just past the
waves' 20 s ramp), 1 worker, 1 of them one by one. No assertion.
"""
import argparse
import json
import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

import jaxslosh as js
from jaxslosh.campaign.cases import case_values, make_cases, read_scatter
from jaxslosh.cache import programs
from jaxslosh.campaign.worker import configure_jax, run_batch
from jaxslosh.io.campaign import load_campaign
from benchmarks.harness import ROOT, Table, parser, scene as load

#: N m s, the yaw damping that holds the heading (see the module docstring)
YAW_DAMPING = 2.0e6
HS = (0.2, 0.4, 0.6, 0.8)
TP = (5.0, 6.0, 7.0, 8.0, 9.0)
#: the campaign's operability limits (roll, pitch in rad, probe B in m)
LIMITS = {"roll": 0.1, "pitch": 0.1, "probe.B": 0.5}
#: the projection: a scatter of 300 cells, each a 3-hour sea state, on 100 cores
PROJECT_CELLS, PROJECT_HOURS, PROJECT_CORES = 300, 3.0, 100


#: the moored variant (`--moored`): three catenary lines 120 degrees apart in 50 m of water
MOORING_DEPTH = 50.0
def mooring_tables() -> list:
    """The three lines: anchors 240 m out, fairleads 5 m from the COG, both towards 180, 300, 60 deg."""
    out = []
    for i, a in enumerate((180.0, 300.0, 60.0)):
        c, s = math.cos(math.radians(a)), math.sin(math.radians(a))
        out.append({"name": f"line{i + 1}", "fairlead": [5 * c, 5 * s, -2.0], "anchor": [240 * c, 240 * s, -50.0],
                    "length": 258.0, "weight": 300.0, "ea": 5.0e8})
    return out


#: m, the box's depth for the nonlinear hydrostatics (`--nonlinear`): 2.5 m of freeboard
DEPTH = 5.0


def campaign_scene(nonlinear: bool = False, yaw_damping: float = YAW_DAMPING, components: int = 0,
                   moored: bool = False) -> js.Scene:
    """The benchmark's scene; `nonlinear`: the pressure on the box's wetted surface with its deck
    (restoring and Froude-Krylov forces, hull/), `components`: another number of wave components,
    `moored`: on three catenary lines (pass yaw_damping = 0)."""
    base = load("paper_ship_waves")
    roll = base.vessel.hydrodynamics.viscous_damping[3]           # the scene's roll damping, kept
    keys = {"title": "benchmarks/speed/campaign.py: the paper ship, its tank on 20 modes, Froude-Krylov forces, "
                     f'{"yaw damping" if yaw_damping else "moored" if moored else "free yaw"}{", nonlinear hydrostatics" if nonlinear else ""}',
            "vessel.hydrodynamics.excitation": "froude-krylov",
            "vessel.hydrodynamics.viscous_damping": [0.0, 0.0, 0.0, float(roll), 0.0, float(yaw_damping)],
            "tanks[0].reduction.modes": 20, "tanks[0].reduction.static_correction": False,
            "campaign.limits": LIMITS}
    if nonlinear:
        keys.update({"vessel.hull.depth": DEPTH, "vessel.hydrostatics.model": "nonlinear"})
    if components:
        keys["waves.components"] = components
    if moored:
        keys["environment.depth"] = MOORING_DEPTH
        keys["mooring"] = mooring_tables()
    return js.scene_with(base, keys)


def scatter_csv(cells: int, hs=HS, tp=TP) -> str:
    rows = [(h, t) for h in hs for t in tp][:cells]
    return "hs,tp,occurrences\n" + "".join(f"{h:g},{t:g},{int(1000 * np.exp(-h - (t - 7) ** 2 / 8))}\n"
                                           for h, t in rows)


def serial(scene_path, csv_path, heads, seeds, duration, indices, out_json):
    """The cases `indices` one by one in this process (run in a child pinned to one core)."""
    scene = js.load_scene(scene_path)
    cases = make_cases(read_scatter(csv_path), heads, seeds, scene.waves.seed)
    stats, first = {}, None
    t0 = time.perf_counter()
    for i in indices:
        out = run_batch(scene.text, scene.path, duration, [case_values(cases, i)], 1)[0]
        if first is None:
            first = time.perf_counter() - t0
        stats[i] = {"status": out["status"],
                    "std": {ch: st["std"] for ch, st in (out["stats"] or {}).items()},
                    "max": {ch: st["max"] for ch, st in (out["stats"] or {}).items()}}
    wall = time.perf_counter() - t0
    with open(out_json, "w") as f:
        json.dump({"wall": wall, "first": first, "cases": stats}, f)


def run_serial_child(scene_path, csv_path, heads, a, indices, d):
    out_json = os.path.join(d, "serial.json")
    args = [sys.executable, "-m", "benchmarks.speed.campaign", "--serial-child", scene_path, csv_path, out_json,
            "--headings-rad", ",".join(repr(float(h)) for h in heads), "--seeds", str(a.seeds),
            "--duration", repr(a.duration), "--indices", ",".join(map(str, indices))]
    cpu = min(os.sched_getaffinity(0))
    t0 = time.perf_counter()
    subprocess.run(args, check=True, cwd=ROOT, preexec_fn=lambda: os.sched_setaffinity(0, {cpu}))
    wall = time.perf_counter() - t0          # the child's start and imports included
    with open(out_json) as f:
        return wall, json.load(f)


def _load() -> str:
    """The machine's load averages (1, 5, 15 min): other jobs on the same cores slow every row."""
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def periods(scene):
    """The moored ship's surge, sway and yaw natural periods from the lines' stiffness and the box's
    mass and added mass at the tables' lowest frequency (the liquid counted as frozen)."""
    K = np.diag(np.asarray(js.mooring(scene).stiffness))
    hd = scene.vessel.hydrodynamics
    A0 = np.asarray(hd.added_mass)[0]
    A = A0 if A0.ndim == 1 else np.diag(A0)
    liquid = sum(t.fluid.density * t.size[0] * t.size[1] * t.fill_depth for t in scene.tanks)
    m = scene.vessel.mass + liquid
    a, b = scene.tanks[0].size[:2]
    izz = np.asarray(scene.vessel.inertia)[2, 2] + liquid * (a ** 2 + b ** 2) / 12
    T = [2 * np.pi * math.sqrt((m + A[0]) / K[0]), 2 * np.pi * math.sqrt((m + A[1]) / K[1]),
         2 * np.pi * math.sqrt((izz + A[5]) / K[5])]
    print(f"moored: the lines' K11 {K[0]:.0f} N/m, K22 {K[1]:.0f} N/m, K66 {K[5]:.4g} N m/rad; natural periods "
          f"surge {T[0]:.0f} s, sway {T[1]:.0f} s, yaw {T[2]:.0f} s; no yaw damper", file=sys.stderr)


def check_file(path, n):
    c = load_campaign(path)
    st = np.array(c.status)
    ok = st == "ok"
    finite = all(np.all(np.isfinite(c.statistics[ch][s][ok])) for ch in c.statistics for s in ("std", "max", "tz"))
    print(f"campaign file {path}: {len(st)} of {n} cases, {ok.sum()} ok, {(st == 'pending').sum()} pending, "
          f"{(~ok & (st != 'pending')).sum()} failed; statistics of the ok cases finite: {finite}; "
          f"operability {float(c.attrs.get('operability', np.nan)):.1f} % (limits {c.attrs.get('limits', '{}')})",
          file=sys.stderr)
    return c


#: s, the sea state the rates are counted in
SEA_STATE = 10800.0


def run_command(base, workers, out, env, cwd):
    """One `jaxslosh campaign` (the argument list `base`) with `workers`: (wall s, CPU s of it and the
    processes it waited for, {phase: s} from its summary line)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(base + ["--workers", str(workers), "-o", out], capture_output=True, text=True, cwd=cwd,
                       env=env)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise SystemExit(f"jaxslosh campaign exited {p.returncode}: {p.stderr[-3000:]}")
    line = [x for x in p.stdout.splitlines() if x.startswith("done:")][-1]
    m = re.search(r"([\d.]+) s wall \((.*)\) ->", line)
    phases = {"campaign": float(m.group(1))} if m else {}
    for item in (m.group(2).split(", ") if m else []):
        name, value, _ = item.rsplit(" ", 2)
        phases[name] = float(value)
    return wall, r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime, phases


def loop_cpu(scene_path, csv_path, heads, a, batch, cache):
    """CPU s per case-step of the vmapped loop (run_batch of the campaign's first `batch` cases in
    this process, the program and model read from the commands' cache), best of two."""
    configure_jax(cache)
    programs.use(os.path.join(cache, "programs"))
    scene = js.load_scene(scene_path)
    cases = make_cases(read_scatter(csv_path), heads, a.seeds, scene.waves.seed)
    values = [case_values(cases, i) for i in range(min(batch, cases.n))]
    run_batch(scene.text, scene.path, a.duration, values, batch)           # the program loaded
    best = math.inf
    for _ in range(2):
        c0 = time.process_time()
        run_batch(scene.text, scene.path, a.duration, values, batch)
        best = min(best, time.process_time() - c0)
    return best / (batch * round(a.duration / scene.simulation.dt))


def command(a, scene_path, csv_path, heads, n, d):
    """--command: the whole `jaxslosh campaign` with 1 and 2 workers (see the module docstring)."""
    b = int(a.batch.split(",")[0])
    cache = os.path.join(d, "cache")
    env = dict(os.environ, JAXSLOSH_CACHE_DIR=cache, JAXSLOSH_PROGRESS="0")
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    base = [sys.executable, "-m", "jaxslosh", "campaign", scene_path, "--scatter", csv_path, "--headings",
            ",".join(repr(float(h)) for h in heads), "--seeds", str(a.seeds), "--duration", repr(a.duration),
            "--batch", str(b), "--no-progress"]
    wall, cpu, _ = run_command(base, 1, os.path.join(d, "warm.h5"), env, d)
    print(f"first run (compiles, fills the cache; not counted): {wall:.1f} s wall, {cpu:.1f} s CPU; {_load()}",
          file=sys.stderr)
    rows = {}
    for w in (1, 2):
        for k in range(a.repeat):
            r = run_command(base, w, os.path.join(d, f"w{w}_{k}.h5"), env, d)
            print(f"{w} worker(s), run {k + 1}: {r[0]:.1f} s wall, {r[1]:.1f} s CPU, {r[2]}; {_load()}", file=sys.stderr)
            if w not in rows or r[0] < rows[w][0]:
                rows[w] = r
    per_step = loop_cpu(scene_path, csv_path, heads, a, b, cache)
    steps = round(a.duration / js.load_scene(scene_path).simulation.dt)
    scale = SEA_STATE / a.duration
    table = Table(("jaxslosh campaign", "{}"), ("wall s", "{:.1f}"), ("CPU s", "{:.1f}"), ("wall s/case", "{:.3f}"),
                  ("sea states/core-hour (wall)", "{:.0f}"), ("(CPU)", "{:.0f}"), ("phases of its summary, s", "{}"))
    for w, (wall, cpu, ph) in rows.items():
        shown = ", ".join(f"{k} {v:.1f}" for k, v in ph.items())
        table.add(f"{w} worker{'s' if w > 1 else ''}, {n} cases of {a.duration:g} s, --batch {b}", wall, cpu, wall / n,
                  3600.0 / (wall * w / n * scale), 3600.0 / (cpu / n * scale), shown)
    table.print(a.markdown)
    w1, w2 = rows[1][0], rows[2][0]
    print(f"2-worker efficiency (1-worker wall / (2 x 2-worker wall)): {w1 / (2 * w2):.2f}")
    print(f"the vmapped loop alone (run_batch of {b} cases in one process): {1e6 * per_step:.1f} us CPU per "
          f"case-step, {3600.0 / (per_step * steps * scale):.0f} sea states per core-hour; the 1-worker command's "
          f"wall beyond it: {w1 - per_step * steps * n:.1f} s of {w1:.1f} s; {_load()}")


def main(argv=None):
    p = parser(__doc__)
    p.add_argument("--cells", type=int, default=20)
    p.add_argument("--headings", type=int, default=5)
    p.add_argument("--seeds", type=int, default=2)
    p.add_argument("--duration", type=float, default=600.0)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--batch", default="8", help="cases per batch; several (8,1) run the cluster once for each")
    p.add_argument("--serial-cases", type=int, help="run this many of the cases one by one (default all)")
    p.add_argument("--skip-serial", action="store_true")
    p.add_argument("-o", "--output", help="keep the campaign file here (with several --batch: NAME_b8.h5, ...)")
    p.add_argument("--resume", action="store_true",
                   help="keep the ok cases of an existing -o file and run the others (its wall row then "
                        "counts only those)")
    p.add_argument("--nonlinear", action="store_true",
                   help='[vessel.hydrostatics] model = "nonlinear" on the box with a depth of 5 m')
    p.add_argument("--hs", help="comma-separated Hs (m) of the scatter's rows (default 0.2,0.4,0.6,0.8)")
    p.add_argument("--tp", help="comma-separated Tp (s) of the scatter's columns (default 5,6,7,8,9)")
    p.add_argument("--yaw-damping", type=float, default=YAW_DAMPING, help="N m s (0: the ship free in yaw)")
    p.add_argument("--components", type=int, default=0, help="wave components (default the scene's 200)")
    p.add_argument("--moored", action="store_true", help="three catenary lines instead of the yaw damper")
    p.add_argument("--command", action="store_true",
                   help="time `python -m jaxslosh campaign` with 1 and 2 workers (see the docstring)")
    p.add_argument("--repeat", type=int, default=1, help="--command: runs of each row, the best kept")
    p.add_argument("--serial-child", nargs=3, metavar=("SCENE", "CSV", "OUT"), help=argparse.SUPPRESS)
    p.add_argument("--headings-rad", help=argparse.SUPPRESS)
    p.add_argument("--indices", help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.serial_child:
        heads = [float(h) for h in a.headings_rad.split(",")]
        serial(*a.serial_child[:2], heads, a.seeds, a.duration, [int(i) for i in a.indices.split(",")],
               a.serial_child[2])
        return
    if a.quick:
        a.cells, a.headings, a.seeds, a.duration, a.serial_cases, a.workers = 1, 2, 1, 22.0, 1, 1
        a.batch = "1" if a.command else a.batch
    os.environ["PYTHONPATH"] = os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")])
    heads = np.linspace(0.0, np.pi, a.headings) if a.headings > 1 else np.array([np.pi / 2])
    batches = [int(b) for b in a.batch.split(",")]
    print(f"{time.strftime('%Y-%m-%d %H:%M %Z')}, {os.cpu_count()} cores, {_load()}", file=sys.stderr)
    with tempfile.TemporaryDirectory() as d:
        scene_path = os.path.join(d, "ship.toml")
        with open(scene_path, "w") as f:
            f.write(campaign_scene(a.nonlinear, 0.0 if a.moored else a.yaw_damping, a.components, a.moored).text)
        csv_path = os.path.join(d, "scatter.csv")
        hs = HS if not a.hs else tuple(float(x) for x in a.hs.split(","))
        tp = TP if not a.tp else tuple(float(x) for x in a.tp.split(","))
        cells = min(a.cells, len(hs) * len(tp))
        with open(csv_path, "w") as f:
            f.write(scatter_csv(cells, hs, tp))
        scene = js.load_scene(scene_path)
        if a.moored:
            periods(scene)
        n = cells * heads.size * a.seeds
        print(f"{n} cases: {cells} sea states x {heads.size} headings x {a.seeds} seeds, {a.duration:g} s each "
              f"(dt {scene.simulation.dt:g} s, {a.duration / scene.simulation.dt:.0f} steps)", file=sys.stderr)
        if a.command:
            return command(a, scene_path, csv_path, heads, n, d)
        rows, results, compile_s = [], {}, None
        for b in batches:
            out = (os.path.join(d, f"c_b{b}.h5") if not a.output else a.output if len(batches) == 1
                   else f"{os.path.splitext(a.output)[0]}_b{b}.h5")
            t0 = time.perf_counter()
            r = js.campaign(scene, csv_path, headings=heads, seeds=a.seeds, duration=a.duration, workers=a.workers,
                            batch=b, output=out, progress=False,
                            resume=a.resume and bool(a.output))
            wall = time.perf_counter() - t0
            results[b] = r
            capsized = sum(st.startswith("capsized") for st in r.status)
            print(f"cluster, batch {b}: {wall:.1f} s, {r.failed} of {n} cases not ok ({capsized} capsized, "
                  f"{r.failed - capsized} failed); {_load()}" +
                  "".join(f"\n  case {i}: {st}" for i, st in enumerate(r.status) if st != "ok"), file=sys.stderr)
            check_file(out, n)
            rows.append((f"Dask LocalCluster, {a.workers} workers, --batch {b}", a.workers, wall, n, b))
        if not a.skip_serial:
            k = n if a.serial_cases is None else max(1, min(n, a.serial_cases))
            indices = sorted({int(i) for i in np.linspace(0, n - 1, k).round()})
            wall, s = run_serial_child(scene_path, csv_path, heads, a, indices, d)
            r = results[batches[0]]
            worst, bad = 0.0, 0
            for i, o in s["cases"].items():
                i = int(i)
                if o["status"] != "ok" or r.status[i] != "ok":
                    print(f"one by one: case {i}: {o['status']} (cluster: {r.status[i]})", file=sys.stderr)
                    bad += 1
                    continue
                for ch, x in o["std"].items():
                    y = r.statistics[ch]["std"][i]
                    worst = max(worst, abs(x - y) / max(abs(y), 1e-300))
            sub = "all cases" if len(indices) == n else f"{len(indices)} of the {n} cases, evenly spaced"
            rows.append((f"one by one, one process, 1 core ({sub})", 1, wall, len(indices), 1))
            compile_s = s["first"] - (wall - s["first"]) / max(1, len(indices) - 1)
            print(f"one by one: {wall:.1f} s, first case (compilation and run) {s['first']:.1f} s; {_load()}; {bad} "
                  f"failed; largest relative "
                  f"difference of a channel's std against the cluster (--batch {batches[0]}): {worst:.2g}",
                  file=sys.stderr)
    table = Table(("row", "{}"), ("cores", "{:d}"), ("cases", "{:d}"), ("wall s", "{:.1f}"),
                  ("cases/core-hour", "{:.0f}"))
    rates = []
    for name, cores, wall, cases, _ in rows:
        rates.append(cases / (wall * cores / 3600.0))
        table.add(name, cores, cases, wall, rates[-1])
    table.print(a.markdown)
    if len(rows) > len(batches):
        for b, rate in zip(batches, rates):
            print(f"ratio cluster (--batch {b}) / one by one, per core-hour: {rate / rates[-1]:.2f}; wall-clock "
                  f"speed-up per case: {rows[-1][2] / rows[-1][3] / (rows[batches.index(b)][2] / n):.2f}")
    sim = PROJECT_HOURS * 3600.0
    print(f"projection, {PROJECT_CELLS} cells x {PROJECT_HOURS:g} h sea states ({sim / scene.simulation.dt:.0f} "
          f"steps each) on {PROJECT_CORES} cores at each row's rate (its {a.duration:g} s cases, compilation "
          f"amortised as measured); batches of a row's size go out whole, so rounds = ceil(ceil(cells / batch) / "
          f"cores) and wall = rounds x batch x the core time of a case:")
    for (name, *_, b), rate in zip(rows, rates):
        case_s = 3600.0 / rate * (sim / a.duration)          # core-seconds per 3-hour case
        core_hours = PROJECT_CELLS * case_s / 3600.0
        rounds = math.ceil(math.ceil(PROJECT_CELLS / b) / PROJECT_CORES)
        print(f"  {name:60} {core_hours:6.1f} core-hours, {rounds} round(s) of batches of {b}: "
              f"{rounds * b * case_s / 60:5.1f} min wall")
    if compile_s is not None:
        print(f"  plus each worker's compilation at the start, about {compile_s:.0f} s (the one-by-one row's first "
              f"case less a case's time)")


if __name__ == "__main__":
    main()
