"""Time `jaxslosh export --paraview` on the paper example's 2,000 steps (2,001 frames).

    python -m benchmarks.speed.export_paraview [--result RESULT.h5] [--repeat 3] [--mesh 5,5,5] [--quick]

Issue 20 item 4: every frame of a long run written for ParaView (target: the paper example's 2,000
frames in under 10 s). Runs the paper example (or reads RESULT.h5), then exports it `--repeat`
times into a temporary folder: prints frames, the best and worst wall time (reading the result
file included), the files' size and MB/s. `--quick`: 0.2 s of the example, one export. No
assertion (speed is measured here, never in tests). The export is jaxslosh/io/paraview.py's
`export_paraview`, the function `jaxslosh export --paraview` calls (no Python API names it).
"""
import os
import sys
import tempfile
import time

import jaxslosh as js
from jaxslosh.io.paraview import export_paraview
from benchmarks.harness import Table, parser, scene


def main(argv=None):
    p = parser(__doc__)
    p.add_argument("--result", help="an existing result file (default: run the paper example, 2,000 steps)")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--mesh", default="5,5,5", help="the paper tank's liquid mesh when running it")
    a = p.parse_args(argv)
    if a.quick:
        a.repeat = 1
    with tempfile.TemporaryDirectory() as d:
        path = a.result
        if path is None:
            keys = {"tanks[0].mesh": [int(x) for x in a.mesh.split(",")]}
            if a.quick:
                keys["simulation.duration"] = 0.2
            path = os.path.join(d, "paper.h5")
            t0 = time.perf_counter()
            js.save_result(js.simulate(js.scene_with(scene("paper_ship_tank"), keys)), path)
            print(f"paper example (mesh {a.mesh}) run and saved in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
        times = []
        for i in range(a.repeat):
            t0 = time.perf_counter()
            r = js.load_result(path)
            files = export_paraview(r, os.path.join(d, f"out{i}.xdmf"))
            times.append(time.perf_counter() - t0)
        size = sum(os.path.getsize(f) for f in files)
        nodes = sum(t.nodes.shape[0] for t in r.tanks.values())
        table = Table(("frames", "{:d}"), ("liquid nodes", "{:d}"), ("best s", "{:.2f}"), ("worst s", "{:.2f}"),
                      ("files MB", "{:.1f}"), ("MB/s", "{:.1f}"), ("target", "{}"))
        table.add(len(r.time), nodes, min(times), max(times), size / 1e6, size / 1e6 / min(times),
                  f"under 10 s: {'met' if max(times) < 10 else 'missed'}")
        table.print(a.markdown)


if __name__ == "__main__":
    main()
