"""Time `jaxslosh export --paraview` on the paper example's 2,000 steps (2,001 frames).

    python benchmarks/export_paraview.py [--result RESULT.h5] [--repeat 3] [--mesh 5,5,5]

Issue 20 item 4: every frame of a long run written for ParaView (target: the paper example's 2,000
frames in under 10 s). Runs the paper example (or reads RESULT.h5), then exports it `--repeat`
times into a temporary folder: prints frames, the best and worst wall time (reading the result
file included), the files' size and MB/s. No assertion (speed is measured here, never in tests).
"""
import argparse
import os
import sys
import tempfile
import time

import jax

jax.config.update("jax_enable_x64", True)

import jaxslosh as js  # noqa: E402
from jaxslosh.io.paraview import export_paraview  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--result", help="an existing result file (default: run the paper example, 2,000 steps)")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--mesh", default="5,5,5", help="the paper tank's liquid mesh when running it")
    a = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        path = a.result
        if path is None:
            text = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
            text = text.replace("mesh = [5, 5, 5]", f"mesh = [{a.mesh}]")
            path = os.path.join(d, "paper.h5")
            t0 = time.perf_counter()
            js.save_result(js.simulate(js.load_scene(text)), path)
            print(f"paper example (mesh {a.mesh}) run and saved in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
        times = []
        for i in range(a.repeat):
            t0 = time.perf_counter()
            r = js.load_result(path)
            files = export_paraview(r, os.path.join(d, f"out{i}.xdmf"))
            times.append(time.perf_counter() - t0)
        size = sum(os.path.getsize(f) for f in files)
        nodes = sum(t.nodes.shape[0] for t in r.tanks.values())
        print(f"{'frames':>7} {'liquid nodes':>13} {'best s':>8} {'worst s':>8} {'files MB':>9} {'MB/s':>7}  target")
        print(f"{len(r.time):7d} {nodes:13d} {min(times):8.2f} {max(times):8.2f} {size / 1e6:9.1f} "
              f"{size / 1e6 / min(times):7.1f}  under 10 s: {'met' if max(times) < 10 else 'missed'}")


if __name__ == "__main__":
    main()
