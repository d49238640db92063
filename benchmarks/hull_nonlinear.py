"""The step of the nonlinear hydrostatics (`vessel.hydrostatics.model = "nonlinear"`) against the linear
GM springs: the paper example's vessel (with and without its tank), as a 12-triangle box, as a
closed mesh of about 2,000 panels, and the parametric-roll scene (waves on the wetted hull).

    python benchmarks/hull_nonlinear.py [--steps 1000] [--repeat 2] [--panels 2028]

Issue 32 item 7: the nonlinear step on a hull of about 2,000 panels should cost at most 1.5 times
the linear step of the paper example. Prints a table; no assertion (speed is measured here, never
in tests).
"""
import argparse
import os
import sys
import tempfile

import jax

jax.config.update("jax_enable_x64", True)

import jaxslosh as js  # noqa: E402
from bench_paper import time_scene  # noqa: E402
from jaxslosh.hull.box import box_hull  # noqa: E402
from jaxslosh.hull.surface import write_hull_mesh  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# the paper's ship as a box: 16 x 10 m waterplane, 400 m^3 (draft 2.5 m), GM_T 1.67 m with the liquid
# frozen: KG = KB + BM - GM = 1.25 + 10^2 / (12 * 2.5) - 1.67 m above the keel
L, B, T, D = 16.0, 10.0, 2.5, 5.0
KG = T / 2 + B ** 2 / (12 * T) - 1.67
HYDRO = """[vessel.hydrostatics]
waterplane_area = 160.0
displaced_volume = 400.0
gm_t = 1.67
gm_l = 14.2
"""


def nonlinear(text, hull):
    return text.replace(HYDRO, hull + '\n[vessel.hydrostatics]\nmodel = "nonlinear"\n')


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3, help="rounds over the cases; the best of each is shown")
    ap.add_argument("--panels", type=int, default=2028, help="triangles of the mesh hull (12 n^2 for the box)")
    a = ap.parse_args()
    n = max(1, round((a.panels / 12) ** 0.5))
    paper = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    alone = open(os.path.join(ROOT, "scenes", "vessel_only.toml")).read().replace(
        "waterplane_area = 200.0", "waterplane_area = 160.0").replace("mass = 4.1e5", "mass = 4.1e5")
    box = f"[vessel.hull]\nlength = {L}\nbeam = {B}\ndraft = {T}\nkg = {KG!r}\ndepth = {D}\n"
    tmp = tempfile.mkdtemp()
    mesh = os.path.join(tmp, "hull.obj")
    tris = box_hull(L, B, KG, D, n)            # in the file's coordinates: waterline at z = 0
    write_hull_mesh(mesh, tris + [0.0, 0.0, KG - T])
    meshed = f'[vessel.hull]\ntype = "mesh"\nfile = "{mesh}"\ncog = [0.0, 0.0, {KG - T!r}]\n'
    cases = [("vessel alone, linear", js.load_scene(alone)),
             ("vessel alone, box 12", js.load_scene(nonlinear(alone, box))),
             (f"vessel alone, mesh {len(tris)}", js.load_scene(nonlinear(alone, meshed))),
             ("paper example, linear", js.load_scene(paper)),
             ("paper example, box 12", js.load_scene(nonlinear(paper, box))),
             (f"paper example, mesh {len(tris)}", js.load_scene(nonlinear(paper, meshed))),
             ("parametric roll (waves)", js.load_scene(os.path.join(ROOT, "scenes", "parametric_roll.toml")))]
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cpu; best of {a.repeat}; "
          f"{a.steps} steps")
    print(f"{'case':28} {'compile s':>10} {'us/step':>9} {'newton it':>9} {'/ paper linear':>15}")
    # rounds over all the cases, the best of each kept: on a shared machine the load moves between
    # rounds, and the ratios of cases timed minutes apart in one pass move with it
    runs = {name: [] for name, _ in cases}
    for _ in range(a.repeat):
        for name, scene in cases:
            runs[name].append(time_scene(scene, a.steps))
    ref = min(r["us"] for r in runs["paper example, linear"])
    for name, _ in cases:
        r = dict(min(runs[name], key=lambda x: x["run"]))
        r["compile"] = runs[name][0]["compile"]
        print(f"{name:28} {r['compile']:10.2f} {r['us']:9.1f} {r['iters']:9.2f} {r['us'] / ref:15.2f}"
              f"{'' if r['ok'] else '  FAILED'}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
