"""The shipped elastic tank (scenes/paper_ship_elastic_tank.toml) with the face-normal liquid ("rt")
against the stabilized element, in elastic and in rigid walls: peaks of roll, pitch and probes A
(bottom, near a wall) and B (free surface above it), the largest difference between the elements
as a share of the stabilized run's peak, and the walls' own effect (elastic minus rigid) in each
element. Then the energy of the "rt" run with the trapezoidal rule and no damping.

    python -m benchmarks.validation.rt_elastic_tank [--meshes 5x5x5,10x10x6] [--duration 4] [--quick]

Then, with --modes, the coupled modes of the tank held still (`jaxslosh modes`): the first sloshing
modes and the first modes of the walls (strain share above one half) of both elements (the tank's
blocks and modes are jaxslosh's fem/ internals, what `jaxslosh modes` prints). `--quick`: 0.2 s.
"""
import numpy as np

import jaxslosh as js
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.liquid.face.element import build_face_liquid
from jaxslosh.liquid.walls import build_tank_with_walls, tank_modes
from jaxslosh.liquid.face.walls import build_face_tank_with_walls, face_tank_modes
from benchmarks.harness import Table, parser, scene


def tank_scene(mesh, element, elastic=True, duration=4.0, newmark=False) -> js.Scene:
    keys = {"tanks[0].mesh": list(mesh), "simulation.duration": duration, "tanks[0].fluid.element": element}
    if newmark:
        keys.update({"simulation.scheme": "newmark", "simulation.alpha": None})
    if not elastic:
        keys["tanks[0].walls"] = None
    return js.scene_with(scene("paper_ship_elastic_tank"), keys)


def channels(r):
    rpy = np.asarray(r.vessel.roll_pitch_yaw)
    return {"roll": rpy[:, 0], "pitch": rpy[:, 1], "A": np.asarray(r.probes["A"].displacement)[:, 2],
            "B": np.asarray(r.probes["B"].displacement)[:, 2]}


def runs(mesh, duration, markdown=False):
    out = {}
    for element in ("rt", "stabilized"):
        for elastic in (True, False):
            out[element, elastic] = channels(js.simulate(tank_scene(mesh, element, elastic, duration)))
    print(f"\nmesh {'x'.join(map(str, mesh))}, {duration:g} s (HHT alpha 0.01, as shipped):")
    table = Table(("channel", "{}"), ("peak rt", "{:.5g}"), ("peak stabilized", "{:.5g}"),
                  ("rt - stabilized (of peak)", "{:.4f}"), ("walls' effect rt", "{:.4f}"),
                  ("walls' effect stabilized", "{:.4f}"), ("same with rigid walls: rt - stabilized", "{:.4f}"))
    for k in ("roll", "pitch", "A", "B"):
        a, b = out["rt", True][k], out["stabilized", True][k]
        ar, br = out["rt", False][k], out["stabilized", False][k]
        peak = np.abs(b).max()
        table.add(k, np.abs(a).max(), peak, np.abs(a - b).max() / peak, np.abs(a - ar).max() / peak,
                  np.abs(b - br).max() / peak, np.abs(ar - br).max() / np.abs(br).max())
    table.print(markdown)
    r = js.simulate(tank_scene(mesh, "rt", True, duration, newmark=True))
    E = np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)
    print(f"rt, trapezoidal rule, no damping: energy within {np.abs(E / E[0] - 1).max():.2e} of its start")


def modes(mesh, markdown=False):
    s = tank_scene(mesh, "rt")
    t = s.tanks[0]
    tm = t.geometry.mesh(t.fill_depth, t.mesh)
    fm = face_tank_modes(build_face_tank_with_walls(t, build_face_liquid(tm.nodes, tm.elements, tm.depth, 1000.0,
                                                                          1500.0, 9.81)), n=400)
    nodal = tank_modes(build_tank_with_walls(t, build_liquid(t.size, t.fill_depth, t.mesh, 1000.0, 1500.0, 9.81)),
                       n=600)
    print(f"\nmesh {'x'.join(map(str, mesh))}: coupled modes (rad/s)")
    table = Table(("element", "{}"), ("first 5 sloshing modes", "{}"), ("first 6 wall modes", "{}"))
    for name, m, wall in (("rt", fm, np.array([k == "wall" for k in fm.kind])),
                          ("stabilized", nodal, nodal.wall_share > 0.5)):
        slosh = m.omega[[k == "sloshing" for k in m.kind]][:5]
        walls = ", ".join(f"{w:.2f}" for w in m.omega[wall][:6])
        table.add(name, ", ".join(f"{w:.4f}" for w in slosh), walls)
    table.print(markdown)


def main():
    p = parser(__doc__)
    p.add_argument("--meshes", default="5x5x5")
    p.add_argument("--duration", type=float, default=4.0)
    p.add_argument("--modes", action="store_true")
    a = p.parse_args()
    if a.quick:
        a.duration = 0.2
    for m in a.meshes.split(","):
        mesh = tuple(int(x) for x in m.split("x"))
        if a.modes:
            modes(mesh, a.markdown)
        else:
            runs(mesh, a.duration, a.markdown)


if __name__ == "__main__":
    main()
