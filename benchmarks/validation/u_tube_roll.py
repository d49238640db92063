"""The U-tube's exchange in a forced roll near its frequency (issue 30's run check), "rt" on modes
and at full order, against the independent linear modal theory of tests/u_tube_response.py (the
2-D potential-flow modes of the same section, same damping). Prints one row per mesh and run: the
steady exchange's amplitude error (%) at 0.9, 1.0 and 1.1 of the U-tube frequency.

    python -m benchmarks.validation.u_tube_roll [--meshes 40x10,80x20] [--modes 4,0] [--quick]   (modes 0: full order)

The exchange is the two reservoirs' levels' difference relative to the tank (the probes' inertial
difference plus the tank's tilt across them), fitted to the forcing frequency over the last five
periods of a 160 s run (20 s ramp, 5 % damping on every sloshing mode, 0.005 rad of roll). The
scene, the section's mesh and the theory are the test's (tests/analysis/test_rt_runs.py,
tests/section_meshes.py, tests/u_tube_response.py; run from the repository root). `--quick`: the
coarse mesh on 4 modes, 25 s at the U-tube frequency (the error then is the transient's, not the
theory's).
"""
import os
import tempfile

import meshio
import numpy as np

import jaxslosh as js
from benchmarks.harness import Table, parser
from tests import sloshing_reference as ref
from tests.analysis.test_rt_runs import U_TUBE
from tests.section_meshes import u_tube_hex
from tests.u_tube_response import roll_exchange

AMPLITUDE, ZETA = 0.005, 0.05


def exchange(sc, W):
    r = js.simulate(sc)
    t = np.asarray(r.time)
    roll = np.asarray(r.vessel.roll_pitch_yaw)[:, 0]
    dz = np.asarray(r.probes["L"].displacement)[:, 2] - np.asarray(r.probes["R"].displacement)[:, 2]
    keep = t > t[-1] - 10 * np.pi / W
    A = np.column_stack([np.sin(W * t[keep]), np.cos(W * t[keep])])
    return np.hypot(*np.linalg.lstsq(A, (dz + 7.0 * np.sin(roll))[keep], rcond=None)[0]) / AMPLITUDE


def main():
    ap = parser(__doc__)
    ap.add_argument("--meshes", default="40x10,80x20")
    ap.add_argument("--modes", default="4,0")
    a = ap.parse_args()
    if a.quick:
        a.meshes, a.modes = "40x10", "4"
    section = ref.u_tube(8.0, 1.0, 0.3, 2.0)
    w_u = ref.rectilinear_sloshing_omegas(section, 1.0, n=1, h_target=0.05)[0]
    Ws = w_u * np.array([0.9, 1.0, 1.1])
    expected, _ = roll_exchange(section, 1.0, (-4.0, -0.5), 0.5, 7.5, Ws, ZETA)
    print(f"U-tube frequency {w_u:.5f} rad/s; theory (exchange per radian): "
          + ", ".join(f"{abs(e):.2f}" for e in expected))
    table = Table(("mesh", "{}"), ("run", "{}"), ("0.9", "{:+.2f} %"), ("1.0", "{:+.2f} %"), ("1.1", "{:+.2f} %"))
    with tempfile.TemporaryDirectory() as tmp:
        for mesh in a.meshes.split(","):
            ny, nz = (int(v) for v in mesh.split("x"))
            nodes, elements = u_tube_hex(8.0, 1.0, 0.3, 1.0, ny, nz, 0.2)
            path = os.path.join(tmp, f"u{ny}.vtu")
            meshio.write(path, meshio.Mesh(nodes, [("hexahedron", elements)]))
            for modes in (int(m) for m in a.modes.split(",")):
                errs = []
                run = "full order" if modes == 0 else f"{modes} modes"
                for W, e in zip(Ws, expected):
                    if a.quick and W != Ws[1]:
                        errs.append(float("nan"))
                        continue
                    keys = {"tanks.u.reduction": None} if modes == 0 else {"tanks.u.reduction.modes": modes}
                    if a.quick:
                        keys["simulation.duration"] = 25.0
                    try:
                        sc = js.scene_with(js.load_scene(U_TUBE.format(frequency=W, file=path)), keys)
                        errs.append(100 * (exchange(sc, W) / abs(e) - 1))
                    except js.SceneError as err:         # a full order above rt's dense limit
                        table.add(f"2x{ny}x{nz}", run, str(err), "", "")
                        break
                else:
                    table.add(f"2x{ny}x{nz}", run, *errs)
    table.print(a.markdown)


if __name__ == "__main__":
    main()
