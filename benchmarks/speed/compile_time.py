"""What a run of a scene costs before its first step, in a fresh process: the first call (empty
caches) and a second process (the caches the first filled), tracing and XLA apart.

    python -m benchmarks.speed.compile_time [SCENE ...] [--repeat 2] [--equations] [--api] [--quick] [--markdown]

Each measurement is one fresh Python process that runs `jaxslosh run`'s own path
(jaxslosh/run/tofile.run_to_file, an internal: its report's phases are what is measured) on the
scene cut to its first chunk: import, build the model (`build`; a second process reads the model
the first kept), compile `start` and the chunk (JAX's persistent compilation cache and the exported
programs, cache/programs.py, in a temporary folder; `start` compiles while the chunk traces) and
run `start` (`compile`), then the first chunk. `1st step` is the process's time to its first
step (import + build + compile). JAX's compilation events are summed by kind (jax.monitoring):
tracing (jaxpr_trace_duration), lowering (jaxpr_to_mlir_module_duration) and XLA
(backend_compile_duration; in a second process, reading XLA's cache). Programs that compile at the
same time (start and the chunk) are both counted in full: the XLA column can exceed the wall time
it overlaps. Prints a table; no assertion.
`--equations` adds the traced programs' sizes (`js.Stepper`'s `init` and `advance` over the chunk's
steps, which keeps no frames); `--api` a table of `js.simulate`'s first call (build,
compile and 50 steps) and second call (build and 50 steps) in a fresh process. Default scenes: the paper example and the paper ship
with its mast.
"""
import json
import os
import subprocess
import sys
import tempfile

from benchmarks.harness import ROOT, Table, parser

CHILD = r"""
import collections, json, os, sys, tempfile, time
T0 = time.perf_counter()
os.environ["JAXSLOSH_CACHE_DIR"] = sys.argv[2]
import jax
from jaxslosh import entry
from jaxslosh.cache import executables
# as `jaxslosh run` (jaxslosh/entry.py): the executables its last run used start loading, then the package is imported
executables.preload(executables.cache_folder()[1], entry.command_hint(["run", sys.argv[1]]))
from jaxslosh.cli.common import setup_jax
setup_jax()                 # as `jaxslosh run`: float64, XLA's cache and the exported programs in the folder
events = collections.defaultdict(float)
jax.monitoring.register_event_duration_secs_listener(
    lambda name, d, **kw: events.__setitem__(name.split("/")[-1], events[name.split("/")[-1]] + d))
import jaxslosh as js
from jaxslosh.run.tofile import run_to_file
t_import = time.perf_counter()
scene = js.load_scene(sys.argv[1])
sim = scene.simulation
se = sim.save_every or 1
n_steps = int(round(sim.duration / sim.dt))
chunk = sim.chunk or max(1, min(n_steps // se, max(1, 500 // se)))
scene = js.scene_with(scene, {"simulation.duration": chunk * se * sim.dt})     # the first chunk only
with tempfile.TemporaryDirectory() as out:
    rep = run_to_file(scene, os.path.join(out, "r.h5"), progress=False)
ph = rep.times
eqns = {}
if sys.argv[3] == "1":     # the traced programs' sizes (equations, counted into sub-programs): what XLA compiles
    import equinox as eqx
    from jax.extend import core as jcore

    def count(jaxpr):
        n = 0
        for e in jaxpr.eqns:
            n += 1
            for p in e.params.values():
                for sub in (p if isinstance(p, (list, tuple)) else [p]):
                    n += count(sub.jaxpr) if isinstance(sub, jcore.ClosedJaxpr) else \
                        count(sub) if isinstance(sub, jcore.Jaxpr) else 0
        return n
    stepper = js.Stepper(scene)
    carry = stepper.init()
    eqns["start_eqns"] = count(eqx.filter_make_jaxpr(lambda st: st.init())(stepper)[0].jaxpr)
    eqns["chunk_eqns"] = count(eqx.filter_make_jaxpr(lambda st, c: st.advance(c, chunk * se))(stepper, carry)[0].jaxpr)
executables.settle()        # as `jaxslosh run` does at its end: the executables compiled are kept
t_build, t_first = t_import + ph["build"], t_import + ph["build"] + ph["compile"]
print(json.dumps({**eqns, "import": t_import - T0, "build": ph["build"], "compile": ph["compile"],
                  "first_step": t_first - T0, "first_chunk": t_first + ph.get("stepping", 0.0) - T0, "steps": chunk * se,
                  "trace": events["jaxpr_trace_duration"], "lower": events["jaxpr_to_mlir_module_duration"],
                  "xla": events["backend_compile_duration"]}))
"""


API_CHILD = r"""
import collections, json, sys, time
T0 = time.perf_counter()
import jax
jax.config.update("jax_enable_x64", True)
events = collections.defaultdict(float)
jax.monitoring.register_event_duration_secs_listener(
    lambda name, d, **kw: events.__setitem__(name.split("/")[-1], events[name.split("/")[-1]] + d))
import jaxslosh as js
scene = js.load_scene(sys.argv[1])
t_import = time.perf_counter()
sim = scene.simulation
duration = 50 * sim.dt * max(1, sim.save_every or 1)     # 50 steps: the call is its build and compile
r = js.simulate(scene, duration=duration, throw=False)
t_first = time.perf_counter()
r = js.simulate(scene, duration=duration, throw=False)
t_second = time.perf_counter()
print(json.dumps({"import": t_import - T0, "first": t_first - t_import, "second": t_second - t_first,
                  "trace": events["jaxpr_trace_duration"], "lower": events["jaxpr_to_mlir_module_duration"],
                  "xla": events["backend_compile_duration"], "status": r.status}))
"""


def measure_api(scene):
    """js.simulate's first and second call in a fresh process (50 steps; no cache folder: the Python
    API keeps its compiled programs in the process only)."""
    p = subprocess.run([sys.executable, "-c", API_CHILD, scene], capture_output=True, text=True, cwd=ROOT)
    if p.returncode:
        raise SystemExit(p.stderr)
    return json.loads(p.stdout.strip().splitlines()[-1])


def measure(scene, cache, equations=False):
    p = subprocess.run([sys.executable, "-c", CHILD, scene, cache, "1" if equations else "0"], capture_output=True, text=True, cwd=ROOT)
    if p.returncode:
        raise SystemExit(p.stderr)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main():
    ap = parser(__doc__)
    ap.add_argument("scenes", nargs="*", default=[os.path.join(ROOT, "scenes", "paper_ship_tank.toml"),
                                                 os.path.join(ROOT, "scenes", "paper_ship_mast.toml")])
    ap.add_argument("--repeat", type=int, default=1, help="cold/warm pairs per scene (a shared machine varies)")
    ap.add_argument("--equations", action="store_true",
                    help="also count the traced programs' equations (start, chunk): a measure of what tracing "
                         "and XLA work on that does not depend on the machine's load")
    ap.add_argument("--api", action="store_true",
                    help="also time js.simulate's first and second call in a fresh process (the Python API)")
    a = ap.parse_args()
    if a.quick:             # the vessel alone, one cold/warm pair
        a.scenes, a.repeat = [os.path.join(ROOT, "scenes", "vessel_only.toml")], 1
    table = Table(("scene", "{}"), ("cache", "{}"), ("import", "{:.2f}"), ("build", "{:.2f}"), ("compile", "{:.2f}"),
                  ("1st step", "{:.2f}"), ("1st chunk", "{:.2f}"), ("trace", "{:.2f}"), ("lower", "{:.2f}"),
                  ("XLA", "{:.2f}"), ("equations (start, chunk)", "{}"),
                  title="seconds, one fresh process each")
    for scene in a.scenes:
        for _ in range(a.repeat):
            with tempfile.TemporaryDirectory() as cache:
                for label in ("cold", "warm"):
                    r = measure(scene, cache, a.equations and label == "warm")
                    table.add(os.path.basename(scene)[:24], label, r["import"], r["build"], r["compile"],
                              r["first_step"], r["first_chunk"], r["trace"], r["lower"], r["xla"],
                              f"{r['start_eqns']}, {r['chunk_eqns']}" if "start_eqns" in r else "")
    table.print(a.markdown)
    if a.api:
        print()
        table = Table(("scene", "{}"), ("import", "{:.2f}"), ("1st call", "{:.2f}"), ("2nd call", "{:.2f}"),
                      ("trace", "{:.2f}"), ("lower", "{:.2f}"), ("XLA", "{:.2f}"),
                      title="js.simulate, 50 steps, build included; seconds, one fresh process each")
        for scene in a.scenes:
            for _ in range(a.repeat):
                r = measure_api(scene)
                table.add(os.path.basename(scene)[:24], r["import"], r["first"], r["second"], r["trace"],
                          r["lower"], r["xla"])
        table.print(a.markdown)


if __name__ == "__main__":
    main()
