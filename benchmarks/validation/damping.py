"""The liquid damping's validation figures (docs/validation.md): the logarithmic decrement of a
free decay of the first sloshing mode against 2 pi zeta / sqrt(1 - zeta^2), and the laminar
boundary-layer ratio against the rectangular tank's closed form (liquid/damping.py).

    python -m benchmarks.validation.damping [--quick]

A 1.0 x 0.4 m tank filled to 0.5 m, held still, its liquid started on the first sloshing mode
(5.3 rad/s) by a velocity; 7 s at dt = 0.01 s (118 steps a period). Starting the liquid on a mode
and reading its surface heave need the model's internals (jaxslosh/run/simulate.prepare,
solve/integrator's `initial_state` and `step`, assemble/damping): no public API starts a run from
a given liquid velocity. `--quick`: the first row and the first mesh only."""
from __future__ import annotations

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxslosh as js  # noqa: E402
from jaxslosh.assemble.damping import build_damping  # noqa: E402
from jaxslosh.assemble.liquid import build_liquid_block  # noqa: E402
from jaxslosh.liquid.damping import rectangular_ratio  # noqa: E402
from jaxslosh.run.simulate import prepare  # noqa: E402
from jaxslosh.solve.integrator import initial_state, step  # noqa: E402
from benchmarks.harness import parser  # noqa: E402

HELD = """
title = "held tank"
[environment]
gravity = 9.81
[simulation]
duration = 7.0
dt = 0.01
scheme = "newmark"
alpha = 0.0
[vessel]
mass = 1.0e4
inertia = [1.0e4, 1.0e4, 1.0e4]
[vessel.forced]
dof = "surge"
amplitude = 0.0
frequency = 1.0
[[tanks]]
name = "tank"
origin = [-0.5, -0.2, -0.3]
size = [1.0, 0.4, 0.6]
fill_depth = 0.5
mesh = [8, 2, 4]
"""


def decay_decrement(scene):
    setup = prepare(scene)
    b, solver, system = setup.built, setup.solver, setup.built.system
    M = np.asarray(system.liquid.constant_blocks()[0])
    mode = np.linalg.solve(M, np.asarray(system.tail[0].B[:, 0]))
    mode = mode / np.max(np.abs(np.asarray(system.liquid.nodal_fields(system.liquid.frame_field(jnp.asarray(mode))))))
    K = np.asarray(system.liquid.constant_blocks()[1])
    omega = float(np.sqrt(mode @ K @ mode / (mode @ M @ mode)))
    corner = b.surfaces[0][:1]
    s0, _ = initial_state(system, solver, b.c0, b.v0.at[6:].set(1e-3 * omega * jnp.asarray(mode)))

    @jax.jit
    def run(s0):
        def one(s, _):
            s, _ = step(system, solver, s)
            return s, system.liquid.surface_heave(s.c.d, corner)[0]
        return jax.lax.scan(one, s0, None, length=setup.n_steps)[1]

    z = np.asarray(run(s0)) - float(system.liquid.surface_heave(b.c0.d, corner)[0])
    i = np.flatnonzero((z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:])) + 1
    a, m, c = z[i - 1], z[i], z[i + 1]
    peaks = m - 0.125 * (c - a) ** 2 / (a - 2 * m + c)
    return -np.polyfit(np.arange(len(peaks)), np.log(peaks), 1)[0]


def target(zeta):
    return 2 * np.pi * zeta / np.sqrt(1 - zeta ** 2)


def main():
    quick = parser(__doc__).parse_args().quick
    held = js.load_scene(HELD)
    rows = [("full order, trapezoidal", {"tanks[0].damping.ratio": [0.02]}),
            ("reduced (6 modes), trapezoidal", {"tanks[0].damping.ratio": [0.02], "tanks[0].reduction.modes": 6}),
            ("full order, HHT alpha = 0.01", {"tanks[0].damping.ratio": 0.02, "simulation.scheme": "hht",
                                              "simulation.alpha": 0.01})]
    print("free decay of the first sloshing mode, ratio 0.02: decrement against 2 pi zeta / sqrt(1 - zeta^2)")
    for name, keys in rows[:1] if quick else rows:
        d = decay_decrement(js.scene_with(held, keys))
        print(f"  {name:32s} {d:.5f} vs {target(0.02):.5f} ({100 * (d / target(0.02) - 1):+.2f} %)")
    print("laminar boundary layers, nu = 1e-6 m^2/s, first mode: mesh value against the closed form")
    closed = rectangular_ratio(1.0, 0.4, 0.5, 9.81, 1e-6)
    for mesh in ([8, 2, 4],) if quick else ([8, 2, 4], [12, 4, 6]):
        scene = js.scene_with(held, {"tanks[0].mesh": mesh, "tanks[0].damping.viscosity": 1e-6})
        zeta = float(np.asarray(build_damping(scene, None, build_liquid_block(scene, None, 9.81))[1][0].zeta)[0])
        print(f"  mesh {str(mesh):12s} {zeta:.5e} vs {closed:.5e} ({100 * (zeta / closed - 1):+.2f} %)")
    if quick:
        return
    scene = js.scene_with(held, {"tanks[0].damping.viscosity": 1e-3})
    zeta = float(np.asarray(build_damping(scene, None, build_liquid_block(scene, None, 9.81))[1][0].zeta)[0])
    d = decay_decrement(scene)
    print(f"  free decay with nu = 1e-3 (zeta {zeta:.4f}): decrement {d:.5f} vs {target(zeta):.5f} "
          f"({100 * (d / target(zeta) - 1):+.2f} %)")


if __name__ == "__main__":
    main()
