"""Steps per second for every tank shape (issue 18 item 3): the paper's ship carrying one tank of
each shape, of about the paper tank's liquid (75 m^3 of water), at full order and on 20 modes.

    PYTHONPATH=. python benchmarks/shapes.py [--steps 1000] [--quick]

Rows: box (the paper's 5 x 5 x 5), the same box given as a gmsh mesh file, a prismatic LNG section
(hopper and top chamfers), a vertical and a horizontal cylinder. Each scene is compiled once, then
`steps` steps are timed on the second call (bench_paper.time_scene). Prints a table; no assertion.
"""
import argparse
import os
import sys
import tempfile

import jax

jax.config.update("jax_enable_x64", True)

import jaxslosh as js  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_paper import paper_variant, time_scene  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def shape_text(base, extra, size, mesh, fill, origin):
    t = base.replace("size = [5.0, 5.0, 4.0]", f"size = {size}").replace("mesh = [5, 5, 5]", f"mesh = {mesh}")
    t = t.replace("fill_depth = 3.0", f"fill_depth = {fill}").replace("origin = [-2.5, -2.5, -1.0]", f"origin = {origin}")
    t = t.replace('walls = "rigid"\n', 'walls = "rigid"\n' + extra + "\n")
    # probes at points every shape holds (the liquid's centre line)
    t = t.replace("point = [4.5, 2.5, 0.0]", "point = [1.0, 0.5, 0.5]").replace("point = [4.5, 2.5, 3.0]", "point = [1.0, 0.5, 0.6]")
    return t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--quick", action="store_true", help="200 steps, no 20-mode rows")
    args = ap.parse_args()
    steps = 200 if args.quick else args.steps
    base = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    tmp = tempfile.mkdtemp()
    import meshio
    from jaxslosh.fem.mesh import box_mesh
    nodes, elements = box_mesh((5.0, 5.0, 3.0), (5, 5, 5))
    msh = os.path.join(tmp, "box.msh")
    meshio.write(msh, meshio.Mesh(nodes, [("hexahedron", elements)]), file_format="gmsh22")
    # the shapes' sizes give about 75 m^3 of water, as the paper's tank holds
    rows = [
        ("box 5x5x5 (paper)", base),
        ("box as a .msh file", shape_text(base, f'shape = "mesh"\nfile = "{msh}"', "[5.0, 5.0, 4.0]", "[5, 5, 5]",
                                          "3.0", "[-2.5, -2.5, -1.0]").replace("fill_depth = 3.0\n", "")
         .replace("mesh = [5, 5, 5]\n", "")),
        ("prismatic (LNG section) 4x12x8", shape_text(
            base, 'shape = "prismatic"\nchamfers = [[1.5, 1.0], [1.5, 1.0]]',
            "[4.0, 6.0, 4.0]", "[4, 12, 8]", "3.5", "[-2.0, -3.0, -1.0]")),
        ("vertical cylinder 8x8x5", shape_text(base, 'shape = "cylinder"\naxis = "z"', "[5.6, 5.6, 4.0]", "[8, 8, 5]",
                                               "3.0", "[-2.8, -2.8, -1.0]")),
        ("horizontal cylinder 6x12x6", shape_text(base, 'shape = "cylinder"\naxis = "x"', "[6.0, 4.0, 4.0]",
                                                  "[6, 12, 6]", "2.0", "[-3.0, -2.0, -1.0]")),
    ]
    print(f"{'scene':34s} {'unknowns':>8s} {'compile s':>9s} {'us/step':>9s} {'steps/s':>9s}  order", flush=True)
    for name, text in rows:
        for modes in ([None] if args.quick else [None, 20]):
            t = paper_variant(text, modes=modes) if modes else text
            r = time_scene(js.load_scene(t), steps)
            print(f"{name:34s} {r['unknowns']:8d} {r['compile']:9.1f} {r['us']:9.1f} {r['sps']:9.0f}  "
                  f"{'20 modes' if modes else 'full'}{'' if r['ok'] else '  FAILED'}", flush=True)


if __name__ == "__main__":
    main()
