"""What a step costs, and how that compares with simpler ways of doing the same work, in one run.

    python -m benchmarks.speed.bench_speed [--steps 200] [--batch 64] [--tables newton,gradient,batch,memory]
        [--quick] [--markdown]

Prints four tables (no assertion; tests never time anything):
  1. the structured quasi-Newton step against a naive Newton (global jax.jacfwd of the residual and a
     dense solve in every iteration) on the same scene, same step, same tolerance;
  2. the cost of jax.grad of a trajectory loss against the forward run;
  3. a vmapped batch of runs against the same runs one after another (compilation timed apart);
  4. the peak memory of one 2,000-step gradient of the paper example.
The structured step is timed by benchmarks/harness.py's time_scene; the naive Newton is built from
the step's equations (`jaxslosh.solve.integrator.step_equations`, an internal: the comparison needs
the very residual the structured step solves) on the `js.Stepper`'s system and solver.
"""
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import jaxslosh as js
from jaxslosh.solve.integrator import StepInfo, step_equations      # the naive Newton's residual
from benchmarks.harness import ROOT, Table, best_of, machine, parser, scene as load, time_scene


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
    """(wall s, result) of one call (the first: compile and run)."""
    w, _, out = best_of(lambda: f(*args), 1)
    return w, out


def newton_table(scenes, steps, markdown):
    print(f"\n1. structured quasi-Newton against a naive Newton, {steps} steps")
    table = Table(("case", "{}"), ("unknowns", "{:d}"), ("structured us/step", "{:.1f}"), ("naive us/step", "{:.1f}"),
                  ("ratio", "{:.1f}"))
    for name, scene in scenes:
        r = time_scene(name, scene, steps, repeat=1)
        stepper = js.Stepper(scene)
        s0 = stepper.init().s
        timed(naive_run, stepper.built.system, stepper.solver, s0, steps)
        t_n, _ = timed(naive_run, stepper.built.system, stepper.solver, s0, steps)
        table.add(name, r.unknowns, r.us_per_step, 1e6 * t_n / steps, t_n / r.run_s)
    table.print(markdown)


def gradient_table(scenes, steps, markdown):
    print(f"\n2. gradient of a trajectory loss against the forward run, {steps} steps")
    table = Table(("case", "{}"), ("forward s", "{:.3f}"), ("grad s", "{:.3f}"), ("ratio", "{:.2f}"))
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
        table.add(name, t_f, t_g, t_g / t_f)
    table.print(markdown)


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


def batch_table(scenes, steps, batch, markdown):
    print(f"\n3. a vmapped batch of {batch} runs against the same runs one after another, {steps} steps")
    table = Table(("case", "{}"), ("compile s", "{:.2f}"), ("batch s", "{:.2f}"), ("singles s", "{:.2f}"),
                  ("runs/s batch", "{:.1f}"), ("runs/s single", "{:.1f}"), ("ratio", "{:.2f}"))
    for name, scene in scenes:
        T = steps * scene.simulation.dt
        gm = np.linspace(1.2, 2.0, batch)
        t_c, _ = timed(lambda: js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm}, duration=T)[0].time)
        t_b = min(timed(lambda: js.simulate_batch(scene, {"vessel.hydrostatics.gm_t": gm}, duration=T)[0].time)[0]
                  for _ in range(2))
        js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm[0]}, duration=T)   # compile
        t_s = best_of(lambda: [js.simulate(scene, params={"vessel.hydrostatics.gm_t": g}, duration=T).time
                               for g in gm], 2)[0]
        table.add(name, t_c - t_b, t_b, t_s, batch / t_b, batch / t_s, t_s / t_b)
    table.print(markdown)


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--memory-steps", type=int, default=2000)
    ap.add_argument("--tables", default="newton,gradient,batch,memory", help="comma-separated subset to run")
    a = ap.parse_args()
    if a.quick:             # the vessel alone, a few steps, a batch of 2, no memory table
        a.steps, a.batch, a.tables = 5, 2, "newton,gradient,batch"
    tables = set(a.tables.split(","))
    scenes = [("vessel alone", load("vessel_only")), ("paper example 5x5x5", load("paper_ship_tank"))]
    if a.quick:
        scenes = scenes[:1]
    print(machine())
    if "newton" in tables:
        newton_table(scenes, a.steps, a.markdown)
    if "gradient" in tables:
        gradient_table(scenes, a.steps, a.markdown)
    if "batch" in tables:
        batch_table(scenes, a.steps, a.batch, a.markdown)
    if "memory" in tables:
        memory_table(a.memory_steps)


if __name__ == "__main__":
    main()
