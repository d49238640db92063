"""Steps per second for every tank shape (issue 18 item 3): the paper's ship carrying one tank of
each shape, of about the paper tank's liquid (75 m^3 of water), at full order and on 20 modes.

    python -m benchmarks.speed.shapes [--steps 1000] [--quick] [--markdown]

Rows: box (the paper's 5 x 5 x 5), the same box given as a gmsh mesh file, a prismatic LNG section
(hopper and top chamfers), a vertical and a horizontal cylinder. Each scene is compiled once, then
`steps` steps are timed after it (benchmarks/harness.py's time_scene). Prints a table; no assertion.
"""
import os
import tempfile

import jaxslosh as js
from benchmarks.harness import Table, machine, parser, scene, time_scene
from benchmarks.speed.bench_paper import paper_variant


def shape_scene(base: js.Scene, extra: dict, size, mesh, fill, origin) -> js.Scene:
    """The paper scene's tank as another shape (`extra`: its shape keys), of the given size, mesh,
    fill depth and origin (None removes the key), its probes at points every shape holds (the
    liquid's centre line)."""
    keys = {"tanks[0].size": size, "tanks[0].mesh": mesh, "tanks[0].fill_depth": fill, "tanks[0].origin": origin,
            "probes.A.point": [1.0, 0.5, 0.5], "probes.B.point": [1.0, 0.5, 0.6]}
    keys.update({f"tanks[0].{k}": v for k, v in extra.items()})
    return js.scene_with(base, keys)


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=1000)
    args = ap.parse_args()
    steps = 20 if args.quick else args.steps          # --quick: 20 steps, no 20-mode rows, two shapes
    base = scene("paper_ship_tank")
    tmp = tempfile.mkdtemp()
    import meshio
    from jaxslosh.fem.mesh import box_mesh
    nodes, elements = box_mesh((5.0, 5.0, 3.0), (5, 5, 5))
    msh = os.path.join(tmp, "box.msh")
    meshio.write(msh, meshio.Mesh(nodes, [("hexahedron", elements)]), file_format="gmsh22")
    # the shapes' sizes give about 75 m^3 of water, as the paper's tank holds
    rows = [
        ("box 5x5x5 (paper)", base),
        ("box as a .msh file", shape_scene(base, {"shape": "mesh", "file": msh}, [5.0, 5.0, 4.0], None,
                                           None, [-2.5, -2.5, -1.0])),
        ("prismatic (LNG section) 4x12x8", shape_scene(
            base, {"shape": "prismatic", "chamfers": [[1.5, 1.0], [1.5, 1.0]]},
            [4.0, 6.0, 4.0], [4, 12, 8], 3.5, [-2.0, -3.0, -1.0])),
        ("vertical cylinder 8x8x5", shape_scene(base, {"shape": "cylinder", "axis": "z"}, [5.6, 5.6, 4.0], [8, 8, 5],
                                                3.0, [-2.8, -2.8, -1.0])),
        ("horizontal cylinder 6x12x6", shape_scene(base, {"shape": "cylinder", "axis": "x"}, [6.0, 4.0, 4.0],
                                                   [6, 12, 6], 2.0, [-3.0, -2.0, -1.0])),
    ]
    if args.quick:
        rows = rows[2:4]
    print(machine() + "\n")
    table = Table(("scene", "{}"), ("unknowns", "{:d}"), ("compile s", "{:.1f}"), ("us/step", "{:.1f}"),
                  ("steps/s", "{:.0f}"), ("order", "{}"))
    for name, sc in rows:
        for modes in ([None] if args.quick else [None, 20]):
            r = time_scene(name, paper_variant(sc, modes=modes) if modes else sc, steps)
            table.add(name, r.unknowns, r.compile_s, r.us_per_step, r.steps_per_s,
                      ("20 modes" if modes else "full") + ("" if r.ok else "  FAILED"))
    table.print(args.markdown)


if __name__ == "__main__":
    main()
