"""What a step costs, and how that compares with simpler ways of doing the same work, in one run.

    python benchmarks/bench_speed.py [--steps 200] [--batch 64] [--tables newton,gradient,batch,memory]

Prints four tables (no assertion; tests never time anything):
  1. the structured quasi-Newton step against a naive Newton (global jax.jacfwd of the residual and a
     dense solve in every iteration) on the same scene, same step, same tolerance;
  2. the cost of jax.grad of a trajectory loss against the forward run;
  3. a vmapped batch of runs against the same runs one after another (compilation timed apart);
  4. the peak memory of one 2,000-step gradient of the paper example.
"""
import argparse
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxslosh as js  # noqa: E402
from jaxslosh.solve.integrator import StepInfo, step_equations  # noqa: E402
from jaxslosh.run.loop import core as _core, advance, start  # noqa: E402
from jaxslosh.run.simulate import prepare
from jaxslosh.scene.keys import with_overrides

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def naive_step(system, solver, s):
    """The same generalized-alpha step solved the textbook way: full Jacobian, dense solve."""
    scale = system.scales()
    R, unpack, x0, _ = step_equations(system, solver, s)

    def body(carry):
        x, it, _ = carry
        x = x - jnp.linalg.solve(jax.jacfwd(R)(x), R(x))
        return x, it + 1, jnp.max(jnp.abs(R(x) / scale))

    x, it, err = jax.lax.while_loop(lambda c: (c[2] > solver.tol) & (c[1] < solver.max_iter), body,
                                    (x0, 0, jnp.max(jnp.abs(R(x0) / scale))))
    c, v, acc, a = unpack(x)
    return s._replace(c=c, v=v, acc=acc, a=a, t=s.t + solver.h), StepInfo(it, err, err <= solver.tol)


@eqx.filter_jit
def naive_run(system, solver, s, n):
    def one(st, _):
        st, info = naive_step(system, solver, st)
        return st, info.iterations
    return jax.lax.scan(one, s, None, length=n)


def timed(f, *args):
    t0 = time.perf_counter()
    out = f(*args)
    jax.block_until_ready(out)
    return time.perf_counter() - t0, out


def newton_table(scenes, steps):
    print(f"\n1. structured quasi-Newton against a naive Newton, {steps} steps")
    print(f"{'case':26} {'unknowns':>8} {'structured us/step':>19} {'naive us/step':>14} {'ratio':>7}")
    for name, scene in scenes:
        setup = prepare(with_overrides(scene, duration=steps * scene.simulation.dt))
        b, solver = _core(setup.built), setup.solver
        carry, _ = start(b, solver)
        timed(advance, b, solver, carry, steps, 1)
        t_s, _ = timed(advance, b, solver, carry, steps, 1)
        timed(naive_run, b.system, solver, carry.s, steps)
        t_n, _ = timed(naive_run, b.system, solver, carry.s, steps)
        print(f"{name:26} {b.system.n:8d} {1e6 * t_s / steps:19.1f} {1e6 * t_n / steps:14.1f} {t_n / t_s:7.1f}")


def gradient_table(scenes, steps):
    print(f"\n2. gradient of a trajectory loss against the forward run, {steps} steps")
    print(f"{'case':26} {'forward s':>10} {'grad s':>8} {'ratio':>7}")
    for name, scene in scenes:
        T = steps * scene.simulation.dt

        def loss(gm):
            r = js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm}, duration=T)
            return jnp.sum(r.vessel.roll_pitch_yaw[:, 0] ** 2)

        f, g = loss, jax.grad(loss)     # simulate's loop is compiled inside; first calls compile
        gm0 = jnp.asarray(scene.vessel.hydrostatics.gm_t)
        timed(f, gm0)
        timed(g, gm0)
        t_f, _ = timed(f, gm0)
        t_g, _ = timed(g, gm0)
        print(f"{name:26} {t_f:10.3f} {t_g:8.3f} {t_g / t_f:7.2f}")


def memory_table(steps):
    """Peak resident memory of a process that takes one gradient of the paper example."""
    import subprocess
    import sys
    code = f"""
import resource, jax
jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp, jaxslosh as js
scene = js.load_scene({os.path.join(ROOT, 'scenes', 'paper_ship_tank.toml')!r})
def loss(gm):
    r = js.simulate(scene, params={{"vessel.hydrostatics.gm_t": gm}}, duration={steps} * scene.simulation.dt)
    return jnp.sum(r.vessel.roll_pitch_yaw[:, 0] ** 2)
print(float(jax.grad(loss)(1.67)), resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    grad, peak = out.stdout.split()[-2:]
    print(f"\n4. peak memory of a process taking one {steps}-step gradient of the paper example: {float(peak):.0f} MB"
          f" (dloss/dGM_T = {float(grad):.6g})")


def batch_table(scenes, steps, batch):
    print(f"\n3. a vmapped batch of {batch} runs against the same runs one after another, {steps} steps")
    print(f"{'case':26} {'compile s':>9} {'batch s':>8} {'singles s':>10} {'runs/s batch':>13} {'runs/s single':>14} "
          f"{'ratio':>7}")
    for name, scene in scenes:
        T = steps * scene.simulation.dt
        gm = np.linspace(1.2, 2.0, batch)
        t_c, _ = timed(lambda: js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm}, duration=T)[0].time)
        t_b = min(timed(lambda: js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm}, duration=T)[0].time)[0]
                  for _ in range(2))
        js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm[0]}, duration=T)   # compile
        t_s = 1e9
        for _ in range(2):
            t0 = time.perf_counter()
            for g in gm:
                jax.block_until_ready(js.simulate(scene, params={"vessel.hydrostatics.gm_t": g}, duration=T).time)
            t_s = min(t_s, time.perf_counter() - t0)
        print(f"{name:26} {t_c - t_b:9.2f} {t_b:8.2f} {t_s:10.2f} {batch / t_b:13.1f} {batch / t_s:14.1f} "
              f"{t_s / t_b:7.2f}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--memory-steps", type=int, default=2000)
    ap.add_argument("--tables", default="newton,gradient,batch,memory", help="comma-separated subset to run")
    a = ap.parse_args()
    tables = set(a.tables.split(","))
    scenes = [("vessel alone", js.load_scene(os.path.join(ROOT, "scenes", "vessel_only.toml"))),
              ("paper example 5x5x5", js.load_scene(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")))]
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cpu")
    if "newton" in tables:
        newton_table(scenes, a.steps)
    if "gradient" in tables:
        gradient_table(scenes, a.steps)
    if "batch" in tables:
        batch_table(scenes, a.steps, a.batch)
    if "memory" in tables:
        memory_table(a.memory_steps)


if __name__ == "__main__":
    main()
