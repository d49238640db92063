"""What a run of a scene costs before its first step, in a fresh process: the first call (empty
caches) and a second process (the caches the first filled), tracing and XLA apart.

    python benchmarks/compile_time.py [SCENE ...] [--repeat 2] [--equations] [--api]

Each measurement is one fresh Python process that does what `jaxslosh run` does up to the end of
its first chunk: import, build the model (`build`; a second process reads the model the first kept),
compile `start` and the chunk (cache/compiled.compile_run: JAX's persistent compilation cache and the
exported programs, cache/programs.py, in a temporary folder; `start` compiles while the chunk traces) and
run `start` (`compile`), then the first chunk. `1st step` is the process's time to its first
step (import + build + compile). JAX's compilation events are summed by kind (jax.monitoring):
tracing (jaxpr_trace_duration), lowering (jaxpr_to_mlir_module_duration) and XLA
(backend_compile_duration; in a second process, reading XLA's cache). Programs that compile at the
same time (start and the chunk) are both counted in full: the XLA column can exceed the wall time
it overlaps. Prints a table; no assertion.
`--equations` adds the traced programs' sizes; `--api` a table of `js.simulate`'s first call (build,
compile and 50 steps) and second call (build and 50 steps) in a fresh process. Default scenes: the paper example and the paper ship
with its mast.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

CHILD = r"""
import collections, json, os, sys, time
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
from jaxslosh.run.loop import core
from jaxslosh.run.simulate import prepare
from jaxslosh.cache.programs import cached
from jaxslosh.cache.compiled import compile_run
from jaxslosh.scene import load_scene
t_import = time.perf_counter()
scene = load_scene(sys.argv[1])
setup = cached("model", scene, lambda: prepare(scene))      # as run_to_file: a second process reads the model
b, solver = core(setup.built), setup.solver
t_build = time.perf_counter()
se = setup.save_every
chunk = scene.simulation.chunk or max(1, min(setup.n_steps // se, max(1, 500 // se)))
carry, f0, adv = compile_run(b, solver, chunk, se)
jax.block_until_ready(f0)
t_first = time.perf_counter()
carry, fr = adv(b, solver, carry, chunk, se)
jax.block_until_ready(fr)
t_chunk = time.perf_counter()
eqns = {}
if sys.argv[3] == "1":     # the traced programs' sizes (equations, counted into sub-programs): what XLA compiles
    import equinox as eqx
    from jax.extend import core as jcore
    from jaxslosh.run.loop import traced_advance, traced_init

    def count(jaxpr):
        n = 0
        for e in jaxpr.eqns:
            n += 1
            for p in e.params.values():
                for sub in (p if isinstance(p, (list, tuple)) else [p]):
                    n += count(sub.jaxpr) if isinstance(sub, jcore.ClosedJaxpr) else \
                        count(sub) if isinstance(sub, jcore.Jaxpr) else 0
        return n
    eqns["start_eqns"] = count(eqx.filter_make_jaxpr(traced_init)(b, solver)[0].jaxpr)
    eqns["chunk_eqns"] = count(eqx.filter_make_jaxpr(lambda b_, s_, c_: traced_advance(b_, s_, c_, chunk, se))(
        b, solver, carry)[0].jaxpr)
executables.settle()        # as `jaxslosh run` does at its end: the executables compiled are kept
print(json.dumps({**eqns, "import": t_import - T0, "build": t_build - t_import, "compile": t_first - t_build, "first_step": t_first - T0,
                  "first_chunk": t_chunk - T0, "steps": chunk * se,
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
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="*", default=[os.path.join(ROOT, "scenes", "paper_ship_tank.toml"),
                                                 os.path.join(ROOT, "scenes", "paper_ship_mast.toml")])
    ap.add_argument("--repeat", type=int, default=1, help="cold/warm pairs per scene (a shared machine varies)")
    ap.add_argument("--equations", action="store_true",
                    help="also count the traced programs' equations (start, chunk): a measure of what tracing "
                         "and XLA work on that does not depend on the machine's load")
    ap.add_argument("--api", action="store_true",
                    help="also time js.simulate's first and second call in a fresh process (the Python API)")
    a = ap.parse_args()
    print(f"{'scene':24} {'cache':6} {'import':>7} {'build':>7} {'compile':>8} {'1st step':>9} {'1st chunk':>10} {'trace':>7} "
          f"{'lower':>7} {'XLA':>7}   (seconds, one fresh process each)")
    for scene in a.scenes:
        for _ in range(a.repeat):
            with tempfile.TemporaryDirectory() as cache:
                for label in ("cold", "warm"):
                    r = measure(scene, cache, a.equations and label == "warm")
                    print(f"{os.path.basename(scene)[:24]:24} {label:6} {r['import']:7.2f} {r['build']:7.2f} "
                          f"{r['compile']:8.2f} {r['first_step']:9.2f} {r['first_chunk']:10.2f} {r['trace']:7.2f} {r['lower']:7.2f} "
                          f"{r['xla']:7.2f}" + (f"   equations: start {r['start_eqns']}, chunk {r['chunk_eqns']}"
                                                 if "start_eqns" in r else ""))
                    sys.stdout.flush()
    if a.api:
        print(f"\n{'scene':24} {'import':>7} {'1st call':>9} {'2nd call':>9} {'trace':>7} {'lower':>7} {'XLA':>7}"
              f"   (js.simulate, 50 steps, build included; seconds, one fresh process each)")
        for scene in a.scenes:
            for _ in range(a.repeat):
                r = measure_api(scene)
                print(f"{os.path.basename(scene)[:24]:24} {r['import']:7.2f} {r['first']:9.2f} {r['second']:9.2f} "
                      f"{r['trace']:7.2f} {r['lower']:7.2f} {r['xla']:7.2f}")
                sys.stdout.flush()


if __name__ == "__main__":
    main()
