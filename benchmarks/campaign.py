"""A campaign on a local Dask cluster against the same cases one by one in one process.

    PYTHONPATH=. python benchmarks/campaign.py [--cells 20] [--headings 5] [--seeds 2] [--duration 600]
                                               [--workers 2] [--batch 8] [--skip-serial]

Issue 19 item 5: the paper's ship in irregular seas (scenes/paper_ship_waves.toml, its tank reduced
to 20 modes without static correction, the wave forces Froude-Krylov on its box so that every
heading is allowed), `cells` sea states (Hs 0.5-2 m x Tp 5-9 s) x `headings` x `seeds`. Prints, for
the cluster and for the serial loop (one compiled run per case, batch of one, in this process),
wall time, cases per core-hour (cores: the cluster's worker processes; the serial loop 1) and
their ratio. Compilation is included in both (each worker compiles once). No assertion.
"""
import argparse
import os
import sys
import tempfile
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import jaxslosh as js  # noqa: E402
from jaxslosh.campaign.cases import case_values, make_cases, read_scatter  # noqa: E402
from jaxslosh.campaign.worker import run_batch  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def scene_text() -> str:
    text = open(os.path.join(ROOT, "scenes", "paper_ship_waves.toml")).read()
    text = text.replace("[vessel.hydrodynamics]\n", '[vessel.hydrodynamics]\nexcitation = "froude-krylov"\n', 1)
    return text + "\n[tanks.reduction]\nmodes = 20\nstatic_correction = false\n"


def scatter_csv(cells: int) -> str:
    hs = np.linspace(0.5, 2.0, 4)
    tp = np.linspace(5.0, 9.0, max(1, -(-cells // 4)))
    rows = [(h, t) for h in hs for t in tp][:cells]
    return "hs,tp,occurrences\n" + "".join(f"{h:g},{t:g},{int(1000 * np.exp(-h / 2 - (t - 7) ** 2 / 8))}\n"
                                           for h, t in rows)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cells", type=int, default=20)
    p.add_argument("--headings", type=int, default=5)
    p.add_argument("--seeds", type=int, default=2)
    p.add_argument("--duration", type=float, default=600.0)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--batch", type=int, default=8)
    p.add_argument("--skip-serial", action="store_true")
    a = p.parse_args(argv)
    os.environ["PYTHONPATH"] = os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")])
    heads = np.linspace(0.0, np.pi, a.headings) if a.headings > 1 else np.array([np.pi / 2])
    with tempfile.TemporaryDirectory() as d:
        scene_path = os.path.join(d, "ship.toml")
        open(scene_path, "w").write(scene_text())
        csv_path = os.path.join(d, "scatter.csv")
        open(csv_path, "w").write(scatter_csv(a.cells))
        scene = js.load_scene(scene_path)
        n = a.cells * heads.size * a.seeds
        print(f"{n} cases: {a.cells} sea states x {heads.size} headings x {a.seeds} seeds, {a.duration:g} s each "
              f"(dt {scene.simulation.dt:g} s)", file=sys.stderr)
        t0 = time.perf_counter()
        r = js.campaign(scene, csv_path, headings=heads, seeds=a.seeds, duration=a.duration, workers=a.workers,
                        batch=a.batch, output=os.path.join(d, "c.h5"), progress=False)
        wall_c = time.perf_counter() - t0
        print(f"cluster: {r.failed} of {n} cases failed" + "".join(f"\n  case {i}: {st}" for i, st in enumerate(r.status)
                                                              if st != "ok"), file=sys.stderr)
        rows = [("Dask LocalCluster", a.workers, wall_c, n)]
        if not a.skip_serial:
            cases = make_cases(read_scatter(csv_path), heads, a.seeds, scene.waves.seed)
            t0 = time.perf_counter()
            worst = 0.0
            for i in range(cases.n):
                out = run_batch(scene.text, scene.path, a.duration, [case_values(cases, i)], 1)
                if out[0]["status"] != "ok" or r.status[i] != "ok":
                    print(f"one by one: case {i}: {out[0]['status']} (cluster: {r.status[i]})", file=sys.stderr)
                    continue
                a_, b_ = out[0]["stats"]["roll"]["std"], r.statistics["roll"]["std"][i]
                worst = max(worst, abs(a_ - b_) / max(abs(b_), 1e-300))
            rows.append(("one by one, one process", 1, time.perf_counter() - t0, n))
            print(f"largest relative difference of a finished case's roll std, one by one vs the cluster: {worst:.2g}",
                  file=sys.stderr)
    print(f"{'':26} {'cores':>6} {'cases':>6} {'wall s':>9} {'cases/core-hour':>16}")
    rate = []
    for name, cores, wall, cases in rows:
        rate.append(cases / (wall * cores / 3600.0))
        print(f"{name:26} {cores:6d} {cases:6d} {wall:9.1f} {rate[-1]:16.0f}")
    if len(rate) == 2:
        print(f"ratio (cluster / one by one), per core-hour: {rate[0] / rate[1]:.2f}; "
              f"wall-clock speed-up: {rows[1][2] / rows[0][2]:.2f}")


if __name__ == "__main__":
    main()
