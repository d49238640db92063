"""The paper example's step against its floor, and where the step's time goes.

    python -m benchmarks.speed.floor [--steps 200] [--rounds 7] [--quick]

The floor (issue 35): three pre-factored dense solves of the example's 474 unknowns per step. Three
forms are timed: "floor", a `lax.scan` of products with a pre-formed 474 x 474 inverse (the fastest
pre-factored dense solve JAX has on the CPU, and the form the step's own solves take); SciPy's
`lu_solve` on LU factors, called from Python (LAPACK's triangular solves, with a call's overhead);
and `jax.scipy.linalg.lu_solve` in a scan (XLA's triangular solves, slow on the CPU). Ratios are
printed against the first and the second. The step is `js.Stepper`'s, in one compiled scan
saving a frame (`observe`) every step as the paper scene does, and saving one frame at the end
(`advance`, then `observe`: what the output path costs). The breakdown times the step's pieces
alone, each in a scan of its own at a state of the running example: the residual R (every Newton
iteration evaluates it once, and once more to see that the last update converged), the
preconditioner's application (one per iteration: the liquid block's inverse and the rigid Schur
complement), and its formation (only when convergence slows); the iterations and formations per
step are counted on a run of 2,000 steps (an untimed run with a host counter).

Everything is measured in one process, after compilation; each piece is timed once per round, the
rounds interleaved, and the best round is kept (a shared machine: the median is printed too). The
times are the process's CPU time (all its threads), not the wall clock: on a machine shared with
other work the wall clock counts the time the process waits for a core, CPU time only what it
computes (caches shared with other work still slow it).

The breakdown needs the step's internals (no public API exposes a piece of the step):
jaxslosh.solve.integrator's `step_equations` (the residual and the predictor) and `step` (the
integrator's step, for the counts), and jaxslosh.solve.newton's preconditioner, on the model and
solver of the public `js.Stepper` (its `built` and `solver`).
"""
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg

import jaxslosh as js
from jaxslosh.solve import newton                                    # the preconditioner's pieces
from jaxslosh.solve.integrator import step as integrator_step, step_equations
from benchmarks.harness import machine, parser, scene


def pieces(b, solver, s, n):
    """The step's pieces, each a jitted scan of n calls (each call depends on the last, so none is
    hoisted out of the loop)."""
    tiny = 1e-300

    @eqx.filter_jit
    def residual(b, solver, s):
        R, _, x0, _ = step_equations(b.system, solver, s)
        return jax.lax.scan(lambda x, _: (x + tiny * R(x), None), x0, None, length=n)[0]

    @eqx.filter_jit
    def apply(b, solver, s):
        _, _, x0, _ = step_equations(b.system, solver, s)
        data = s.pre[0]
        return jax.lax.scan(lambda x, _: (x + tiny * newton._precond_apply(data, solver.Cinv_step, x), None),
                            x0, None, length=n)[0]

    @eqx.filter_jit
    def form(b, solver, s):
        _, _, x0, parts = step_equations(b.system, solver, s)

        def body(x, _):
            data = newton._precond_data_parts(parts, x, solver.Cinv_step, 6)
            return x + tiny * data[2][:, 0].sum(), None
        return jax.lax.scan(body, x0, None, length=n)[0]

    @eqx.filter_jit
    def frame(stepper, c):
        def body(cc, _):
            f = stepper.observe(cc)
            leaves = jax.tree_util.tree_leaves(f)
            bump = sum(jnp.sum(x.astype(float)) for x in leaves)
            return cc._replace(s=cc.s._replace(c=cc.s.c._replace(d=cc.s.c.d + tiny * bump))), None
        return jax.lax.scan(body, c, None, length=n)[0]

    return residual, apply, form, frame


def floors(size, n):
    rng = np.random.default_rng(0)
    A = rng.standard_normal((size, size)) / np.sqrt(size) + np.eye(size)
    Ainv = jnp.asarray(np.linalg.inv(A))
    lu = jax.scipy.linalg.lu_factor(jnp.asarray(A))
    b0 = jnp.ones(size)

    @jax.jit
    def by_inverse(Ainv, b0):
        def body(x, _):
            for _ in range(3):
                x = Ainv @ (b0 + 1e-300 * x)
            return x, None
        return jax.lax.scan(body, b0, None, length=n)[0]

    @jax.jit
    def by_lu(lu, b0):
        def body(x, _):
            for _ in range(3):
                x = jax.scipy.linalg.lu_solve(lu, b0 + 1e-300 * x)
            return x, None
        return jax.lax.scan(body, b0, None, length=n)[0]

    lu_np = scipy.linalg.lu_factor(A)
    b_np = np.ones(size)

    def by_scipy():            # LAPACK's getrs from Python, one call per solve
        x = b_np
        for _ in range(n):
            for _ in range(3):
                x = scipy.linalg.lu_solve(lu_np, b_np + 1e-300 * x)
        return x

    return (lambda: by_inverse(Ainv, b0)), (lambda: by_lu(lu, b0)), by_scipy


@eqx.filter_jit
def framed(stepper, c, n):
    """n steps in one scan, a frame (`observe`) kept after each, as a run saving every step does."""
    def body(cc, _):
        cc = stepper.step(cc)
        return cc, stepper.observe(cc)
    return jax.lax.scan(body, c, None, length=n)


def counts(stepper, carry, steps=2000):
    """Newton iterations and preconditioner formations per step, on `steps` steps of the example
    (the integrator's step in a scan of its own: a fresh trace, which sees the counter on
    `StructuredNewton.precondition`, whichever form of the factors it builds)."""
    formed = [0]
    original = newton.StructuredNewton.precondition

    def counted(self, R, x):
        jax.debug.callback(lambda: formed.__setitem__(0, formed[0] + 1))
        return original(self, R, x)

    def run(system, solver, s):
        def body(s, _):
            s, info = integrator_step(system, solver, s)
            return s, info.iterations
        return jax.lax.scan(body, s, None, length=steps)[1]

    newton.StructuredNewton.precondition = counted
    try:
        its = jax.block_until_ready(eqx.filter_jit(run)(stepper.built.system, stepper.solver, carry.s))
    finally:
        newton.StructuredNewton.precondition = original
    return float(np.mean(its)), formed[0] / steps


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=200, help="steps (or calls) per timing")
    ap.add_argument("--rounds", type=int, default=7, help="interleaved rounds; the best is kept")
    a = ap.parse_args()
    if a.quick:             # a few calls, one round, a short count
        a.steps, a.rounds = 5, 1
    n = a.steps
    stepper = js.Stepper(scene("paper_ship_tank"))
    b, solver = stepper.built, stepper.solver
    carry = stepper.init()
    mid = stepper.advance(carry, 50 if a.quick else 500)     # a state of the running example (t = 5 s)
    its, formed = counts(stepper, carry, 20 if a.quick else 2000)
    residual, apply, form, frame = pieces(b, solver, mid.s, n)
    floor_inv, floor_lu, floor_scipy = floors(b.system.n, n)
    timed = {
        "floor": floor_inv,
        "floor, SciPy lu_solve": floor_scipy,
        "floor, jax lu_solve": floor_lu,
        "step, a frame every step": lambda: framed(stepper, mid, n),
        "step, one frame": lambda: stepper.observe(stepper.advance(mid, n)),
        "residual R": lambda: residual(b, solver, mid.s),
        "preconditioner applied": lambda: apply(b, solver, mid.s),
        "preconditioner formed": lambda: form(b, solver, mid.s),
        "frame": lambda: frame(stepper, mid),
    }
    for f in timed.values():                           # compile
        jax.block_until_ready(f())
    us = {k: [] for k in timed}
    for _ in range(a.rounds):
        for k, f in timed.items():
            t = time.process_time()
            jax.block_until_ready(f())
            us[k].append(1e6 * (time.process_time() - t) / n)
    best = {k: min(v) for k, v in us.items()}
    spread = {k: sorted(v)[len(v) // 2] for k, v in us.items()}
    fl, st = best["floor"], best["step, a frame every step"]
    print(f"{machine()}; paper example, "
          f"{b.system.n} unknowns; {n} steps per timing, best of {a.rounds} interleaved rounds (median after /)")
    print(f"{'':34} {'us/step':>9} {'/ median':>9} {'x floor':>8} {'x SciPy':>8}")
    for k in ("floor", "floor, SciPy lu_solve", "floor, jax lu_solve", "step, a frame every step", "step, one frame"):
        sp = best[k] / best["floor, SciPy lu_solve"]
        print(f"{k:34} {best[k]:9.1f} {spread[k]:9.1f} {best[k] / fl:8.2f} {sp:8.2f}")
    print(f"\nbreakdown of the step ({its:.2f} Newton iterations and {formed:.3f} formations of the "
          f"preconditioner per step):")
    print(f"{'piece':34} {'us each':>9} {'per step':>9} {'us/step':>9} {'share':>7}")
    rows = [("residual R", its + 1.0), ("preconditioner applied", its), ("preconditioner formed", formed),
            ("frame", 1.0)]
    total = 0.0
    for k, times in rows:
        c = best[k] * times
        total += c
        print(f"{k:34} {best[k]:9.1f} {times:9.3f} {c:9.1f} {c / st:7.0%}")
    print(f"{'the rest (loop, update, tests)':34} {'':9} {'':9} {st - total:9.1f} {(st - total) / st:7.0%}")
    bound = (its + 1) * best["residual R"] + its * best["preconditioner applied"]
    print(f"\nlower bound with these iterations, (its + 1) R + its P: {bound:.1f} us/step = {bound / fl:.2f} x floor; "
          f"the goal, 1.3 x floor: {1.3 * fl:.1f} us/step")


if __name__ == "__main__":
    main()
