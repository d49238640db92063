"""Why a step takes the Newton iterations it takes: the residual after every evaluation, and what
other preconditioners would leave.

    python -m benchmarks.speed.newton_trace [--case paper|campaign|SHAPE] [--start 100] [--steps 300]
        [--variants 5] [--quick]

Issue 47 items 1 and 2. `--case`: the paper example (`paper`, its face-normal tank at full order),
a campaign case (`campaign`: `benchmarks.speed.campaign`'s ship, its tank on 20 modes, Hs 0.8 m,
Tp 6 s, heading pi/4, the single run's adaptive solver), or one of `benchmarks.speed.shapes_floor`'s
shapes by name ("prismatic 4x12x8"). From the state after `--start` steps:

* **the trace**: `--steps` steps of the integrator with a host callback on every Newton pass
  (`StructuredNewton.step`): per evaluation of R, the scaled residual over the tolerance the step
  asks (max(tol, the round-off floor)), its median and 10 and 90 % quantiles; how the steps ended
  (converged, stopped early, stalled); and the early stop's estimate (solve/newton.py `EARLY`)
  against the residual the next evaluation showed: the extra steps a larger EARLY would have stopped
  and the largest residual they would have left.
* **the variants** (`--variants N`: at N states 5 steps apart): the residual after each update of
  the same iterations with other preconditioners, all built from the exact Jacobian (`jax.jacfwd`
  of R at the predictor: fine up to a few thousand unknowns): the carried one (the code's); the
  exact liquid block (A_zz of the Jacobian instead of the constant C: its Coriolis terms); and that
  with the carried rigid columns of the liquid rows (A_zy), of the rigid rows (A_yy), the liquid
  columns of the rigid rows (A_yz), or all three, formed at the step. The carried factors
  (S^-1, A_yz, W_z) give back the carried A_yy and A_zy (A_zy = C W_z, A_yy = S + A_yz W_z).
"""
import sys

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import jaxslosh as js
from jaxslosh.solve import newton                       # the iterations' pass, traced by a callback
from jaxslosh.solve.integrator import _split_newton, step as integrator_step, step_equations
from benchmarks.harness import parser, scene
from benchmarks.speed.campaign import campaign_scene
from benchmarks.speed.shapes import shape_scene
from benchmarks.speed.shapes_floor import SHAPES

PASSES = []      # (it, err, tol, early, est) of every pass, filled by the callback


def traced_step(original):
    def step(self, R, s):
        s2 = original(self, R, s)
        jax.debug.callback(lambda *a: PASSES.append(tuple(float(x) for x in a)), s2.it, s2.err, self.tol,
                           s2.early, s2.est)
        return s2
    return step


def trace(stepper, carry, steps):
    """The passes of `steps` steps, one list of (it, err, tol, early, est) per step."""
    def run(system, solver, s):
        return jax.lax.scan(lambda s, _: (integrator_step(system, solver, s)[0], None), s, None, length=steps)[0]
    original = newton.StructuredNewton.step
    newton.StructuredNewton.step = traced_step(original)
    PASSES.clear()
    try:
        jax.block_until_ready(eqx.filter_jit(run)(stepper.built.system, stepper.solver, carry.s))
    finally:
        newton.StructuredNewton.step = original
    out = []
    for p in PASSES:
        if p[0] == 0:
            out.append([])
        out[-1].append(p)
    return out


def report_trace(steps):
    evals = np.array([len(s) for s in steps])
    print(f"{len(steps)} steps: {evals.mean() - 1:.2f} evaluations of R after the first per step; "
          f"tolerance asked (scaled) median {np.median([s[0][2] for s in steps]):.3g}")
    for k in range(evals.max()):
        e = np.array([s[k][1] / s[k][2] for s in steps if len(s) > k])
        print(f"  evaluation {k}: {len(e):5d} steps, residual / tolerance median {np.median(e):9.3g}, "
              f"10 % {np.quantile(e, 0.1):9.3g}, 90 % {np.quantile(e, 0.9):9.3g}")
    early = sum(s[-1][3] > 0.5 for s in steps)
    conv = sum(s[-1][3] < 0.5 and s[-1][1] <= s[-1][2] for s in steps)
    print(f"  ended: converged {conv}, stopped early {early}, otherwise {len(steps) - conv - early}")
    pairs = []
    for s in steps:
        e, tol = [p[1] for p in s], s[0][2]
        for k in range(2, len(e) - 1):
            pairs.append((e[k] * max(e[k] / e[k - 1], e[k - 1] / e[k - 2]) / tol, e[k + 1] / tol))
    pairs = np.array(pairs).reshape(-1, 2)
    for E in (0.1, 0.2, 0.5):
        sel = pairs[pairs[:, 0] <= E]
        worst = sel[:, 1].max() if len(sel) else 0.0
        print(f"  EARLY = {E}: {len(sel)} more early stops, the residual they leave up to {worst:.3g} of the "
              f"tolerance ({int((sel[:, 1] > 1).sum())} above it)")


def carried_blocks(pre, C):
    S_inv, Ayz, Wz = pre
    return jnp.linalg.inv(S_inv) + Ayz @ Wz, C @ Wz, Ayz      # A_yy, A_zy, A_yz


@eqx.filter_jit
def variants(system, solver, s, passes=4):
    """Scaled residuals (over the tolerance) after each update, per preconditioner variant."""
    L, ns = system.layout(), solver.ns
    f = solver.scheme.c_d(solver.h)
    gsc, alg_sc = system.alg_scales(f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
    scale = L.to_x(system.unknown_scales(), alg_sc)
    _, unpack, pred, parts = step_equations(system, solver, s)
    R, _ = _split_newton(system, parts, lambda x: system.constraint_residual(x, lambda d: unpack(d)[0], gsc),
                         L.n_rigid)
    tol = jnp.maximum(solver.tol, jnp.maximum(solver.noise * jnp.max(jnp.abs(s.c.d), initial=0.0),
                                              system.liquid.roundoff(s.c.d)))
    x0 = L.to_x(pred, s.alg)
    J = jax.jacfwd(R)(x0)
    C = jnp.linalg.inv(solver.Cinv_step)
    Ayy, Azy, Ayz = carried_blocks(s.pre[0], C)

    def structured(Czz, Ayy=Ayy, Azy=Azy, Ayz=Ayz):
        Cinv = jnp.linalg.inv(Czz)
        Wz = Cinv @ Azy
        S_inv = jnp.linalg.inv(Ayy - Ayz @ Wz)

        def apply(r):
            wz = Cinv @ r[ns:]
            xy = S_inv @ (r[:ns] - Ayz @ wz)
            return jnp.concatenate([xy, wz - Wz @ xy])
        return apply

    def run(apply):
        x, e = x0, []
        for _ in range(passes):
            r = R(x)
            e.append(jnp.max(jnp.abs(r / scale)) / tol)
            x = x - apply(r)
        return jnp.stack(e)

    Jzz, Jyy, Jzy, Jyz = J[ns:, ns:], J[:ns, :ns], J[ns:, :ns], J[:ns, ns:]
    return {"carried (the code)": run(lambda r: newton._precond_apply(s.pre[0], solver.Cinv_step, r, ns)),
            "exact A_zz, the rest carried": run(structured(Jzz)),
            "exact A_zz, A_zy at the step": run(structured(Jzz, Azy=Jzy)),
            "exact A_zz, A_yy at the step": run(structured(Jzz, Ayy=Jyy)),
            "exact A_zz, A_yz at the step": run(structured(Jzz, Ayz=Jyz)),
            "exact A_zz, A_yy A_zy A_yz at the step": run(structured(Jzz, Jyy, Jzy, Jyz)),
            "the constant C, the rest at the step": run(structured(C, Jyy, Jzy, Jyz)),
            "|C^-1 (A_zz - C)|": jnp.max(jnp.abs(solver.Cinv_step @ (Jzz - C)))[None]}


def case_scene(case):
    if case == "paper":
        return scene("paper_ship_tank")
    if case == "campaign":
        return js.scene_with(campaign_scene(), {"waves.hs": 0.8, "waves.tp": 6.0, "waves.heading": 0.785})
    return shape_scene(scene("paper_ship_tank"), *SHAPES[case])


def main():
    ap = parser(__doc__)
    ap.add_argument("--case", default="paper", help="paper, campaign or a shape of shapes_floor")
    ap.add_argument("--start", type=int, default=100, help="steps before the trace (the campaign: 1200)")
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--variants", type=int, default=5, help="states at which the preconditioners are compared")
    a = ap.parse_args()
    if a.quick:
        a.start, a.steps, a.variants = 5, 10, 1
    stepper = js.Stepper(case_scene(a.case))
    carry = stepper.advance(stepper.init(), a.start)
    print(f"{a.case}: {stepper.built.system.n} unknowns, from step {a.start}")
    report_trace(trace(stepper, carry, a.steps))
    rows = {}
    for _ in range(a.variants):
        for k, v in variants(stepper.built.system, stepper.solver, carry.s).items():
            rows.setdefault(k, []).append(np.asarray(v))
        carry = stepper.advance(carry, 5)
    if rows:
        print(f"\nresidual / tolerance after each update, median of {a.variants} states (the first: the predictor's)")
    for k, v in rows.items():
        print(f"  {k:40}" + "".join(f"{q:10.3g}" for q in np.median(np.array(v), axis=0)))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
