"""Where the multimodal tank's step goes, against the finite-element tank reduced to 20 modes, on the
paper example (scenes/paper_ship_tank.toml). Prints a table.

    python -m benchmarks.speed.multimodal_profile [--steps K] [--repeats R] [--quick]

Each variant runs K steps of its compiled loop (the Newton evaluations per step are read from the
frames), then each piece is jitted alone at the state reached and timed as a `lax.scan` of many
evaluations (CPU time of this process, best of R; the per-call dispatch does not count): the step's
residual R(x), the Newton preconditioner (the exact Jacobian of the small block and its inverse,
`StructuredNewton.precondition`), the integrator's step, the loop's step, the saved frame (probes,
energies), and for the multimodal tank its integrals (the third-order tank's polynomial M(beta))
and its rows alone. XLA's cost analysis gives
the flops and transcendental functions of each compiled piece. Derived: the share of the step spent
in residual evaluations and the rest (the preconditioner formed again when convergence slows, the
predictor, the update). Last, Newton's scaled residual per evaluation with a fresh exact Jacobian
from three predictors (the worst of three steps): how few evaluations a step could take.

The pieces are the step's own internals (jaxslosh.solve.integrator, solve.newton, physics): timing one
piece of the step needs them, and no public API exposes them; the state, the model and the step
come from the public `js.Stepper` (`built`, `solver`, `step`, `observe`), the Newton evaluations
per step from `js.simulate`'s `solver.iterations`."""
from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxslosh as js
from jaxslosh.physics.kinematics import tv3
from jaxslosh.liquid.multimodal.expansion import ExpandedTank
from jaxslosh.solve.integrator import _split_newton, step_equations
from jaxslosh.solve.integrator import step as int_step
from jaxslosh.solve.newton import StructuredNewton
from benchmarks.harness import parser, scene
from benchmarks.speed.multimodal import MULTIMODAL

VARIANTS = {
    "fem, 20 modes": {"tanks[0].reduction.modes": 20},
    "multimodal, 6 modes": MULTIMODAL,
    "multimodal, 6 modes, third-order": {**MULTIMODAL, "tanks[0].expansion": "third-order"},
}
INTEGRALS = "tank's integrals"


def timed(f, args, n, repeats, cost=True):
    """(seconds per evaluation of f(*args), flops, transcendentals): n evaluations in one jitted scan
    (the first argument nudged by a round-off-free amount so that XLA cannot hoist them)."""
    def many(args):
        def body(c, _):
            a0 = jax.tree_util.tree_map(lambda x: x + c * 1e-30 if jnp.issubdtype(x.dtype, jnp.floating) else x,
                                        args[0])
            out = f(a0, *args[1:])
            leaves = [o for o in jax.tree_util.tree_leaves(out) if jnp.issubdtype(o.dtype, jnp.floating)]
            return c + 1e-300 * sum(jnp.sum(o) for o in leaves), None
        return jax.lax.scan(body, jnp.zeros(()), None, length=n)[0]
    run = jax.jit(many)
    run(args).block_until_ready()
    best = np.inf
    for _ in range(repeats):
        t0 = time.process_time()
        run(args).block_until_ready()
        best = min(best, time.process_time() - t0)
    if not cost:            # --quick: XLA's cost analysis compiles each piece again
        return best / n, 0.0, 0.0
    ca = jax.jit(f).lower(*args).compile().cost_analysis()
    ca = ca[0] if isinstance(ca, list) else ca
    return best / n, ca.get("flops", 0.0), ca.get("transcendentals", 0.0)


def profile(sc, steps, repeats, n=200, quick=False):
    stepper = js.Stepper(sc)
    solver = stepper.solver
    carry = stepper.advance(stepper.init(), steps)
    r = js.simulate(js.scene_with(sc, {"simulation.duration": steps * sc.simulation.dt}))
    evals = float(np.mean(np.asarray(r.solver.iterations))) + 1.0    # the frames count those after the first
    s, sysm = carry.s, stepper.built.system
    L = sysm.layout()

    def equations(s):
        f = solver.scheme.c_d(solver.h)
        gsc, _ = sysm.alg_scales(f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
        _, unpack, pred, Rm_parts = step_equations(sysm, solver, s)
        R, split = _split_newton(sysm, Rm_parts, lambda x: sysm.constraint_residual(x, lambda d: unpack(d)[0], gsc),
                                 L.n_rigid)
        return R, split, L.to_x(pred, s.alg)

    def precondition(s, x):
        R, split, _ = equations(s)
        return StructuredNewton(solver.Cinv_step, jnp.ones_like(x), 1e-10, 25, True, solver.ns, split).precondition(R, x)

    x0 = equations(s)[2]
    rows = {"residual R(x)": timed(lambda s, x: equations(s)[0](x), (s, x0), n, repeats, not quick),
            "preconditioner (Jacobian, inverse)": timed(precondition, (s, x0), n // 10, repeats, not quick),
            "integrator step": timed(lambda s: int_step(sysm, solver, s)[0], (s,), n // 4, repeats, not quick),
            "loop step": timed(lambda c: stepper.step(c), (carry,), n // 4, repeats, not quick),
            "saved frame": timed(lambda c: stepper.observe(c), (carry,), n, repeats, not quick)}
    liq = sysm.liquid
    if liq.nonlinear:
        t, k = liq.tanks[0], sysm.kin(s.c, s.v[:3], s.v[3:6], s.v[6:], s.acc[:6], s.acc[6:])
        Vb = tv3(k.A, k.V0)
        be, bd, bdd = s.c.d[:t.n], s.v[6:6 + t.n], s.acc[6:6 + t.n]
        # the exact tank's integrals; the third-order tank's polynomial M(beta) in their place
        ints = t.mass_matrix if isinstance(t, ExpandedTank) else t.integrals
        rows[INTEGRALS] = timed(lambda be: ints(be), (be,), n, repeats, not quick)
        rows["tank's rows (jvp and grad)"] = timed(lambda be: t.rows(Vb, k.omega, be, bd, Vb, k.a6[3:6], bdd, k.g_b),
                                                   (be,), n, repeats, not quick)
    return evals, rows, {} if quick else predictors(sysm, solver, carry.s, equations)


def predictors(sysm, solver, s0, equations, steps=3):
    """The scaled residual per evaluation of Newton with a fresh exact Jacobian, from today's
    predictor (the accelerations a_n of the last step) and from their linear and quadratic
    extrapolations, a few steps on from s0: how many evaluations a step needs at best."""
    L, h, b = sysm.layout(), solver.h, solver.scheme.beta
    f = solver.scheme.c_d(h)
    gsc, alg_sc = sysm.alg_scales(f, lambda itf: jnp.maximum(1.0 / f, 1e-13 * itf.L_ref / solver.tol))
    scale = L.to_x(sysm.unknown_scales(), alg_sc)
    R = jax.jit(lambda s, x: equations(s)[0](x))
    J = jax.jit(lambda s, x: jax.jacfwd(lambda y: equations(s)[0](y))(x))
    advance1 = jax.jit(lambda s: int_step(sysm, solver, s)[0])
    out = {"a_n": [], "2 a_n - a_(n-1)": [], "3 a_n - 3 a_(n-1) + a_(n-2)": []}
    s2, s1 = s0, advance1(s0)
    s = advance1(s1)
    for _ in range(steps):
        s2, s1, s = s1, s, advance1(s)
        Js = J(s, equations(s)[2])
        base = h * s.v + h * h * (0.5 - b) * s.a
        for name, a in zip(out, (s.a, 2 * s.a - s1.a, 3 * s.a - 3 * s1.a + s2.a)):
            x, errs = L.to_x(base + h * h * b * a, s.alg), []
            for _ in range(3):
                r = R(s, x)
                errs.append(float(jnp.max(jnp.abs(r / scale))))
                x = x - jnp.linalg.solve(Js, r)
            out[name].append(errs)
    return {name: np.max(np.asarray(e), axis=0) for name, e in out.items()}


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=150)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    if args.quick:          # the 20-mode tank alone: a few steps, one timing, no cost analysis nor predictors
        args.steps, args.repeats = 5, 1
    base = js.scene_with(scene("paper_ship_tank"), {"simulation.duration": 3.0})
    out = {}
    variants = {"fem, 20 modes": VARIANTS["fem, 20 modes"]} if args.quick else VARIANTS
    for name, keys in variants.items():          # printed as each variant ends (a long run keeps its first table)
        evals, rows, pred = out[name] = profile(js.scene_with(base, keys), args.steps, args.repeats,
                                                20 if args.quick else 200, args.quick)
        print(f"\n{name}: {evals:.2f} residual evaluations per step (after {args.steps} steps)")
        print(f"  {'piece':<36} {'us':>9} {'flops':>10} {'transc.':>8}")
        for piece, (sec, fl, tr) in rows.items():
            print(f"  {piece:<36} {1e6 * sec:>9.1f} {fl:>10.0f} {tr:>8.0f}")
        step, res = rows["loop step"][0], evals * rows["residual R(x)"][0]
        print(f"  residual evaluations: {1e6 * res:.1f} us per step ({res / step:.0%} of the loop's step); "
              f"the rest (preconditioner refreshes, predictor, update): {1e6 * (step - res):.1f} us")
        print(f"  scaled residual per evaluation, fresh exact Jacobian (tolerance {1e-10:g}), by predictor:")
        for p, e in pred.items():
            print(f"    {p:<28} " + " ".join(f"{v:.1e}" for v in e), flush=True)
    if args.quick:
        return
    fe = out["fem, 20 modes"][1]
    for name in ("multimodal, 6 modes", "multimodal, 6 modes, third-order"):
        mm = out[name][1]
        print(f"\nloop step, {name} / 20 modes: {mm['loop step'][0] / fe['loop step'][0]:.2f}; "
              f"its {INTEGRALS} (third-order: M(beta)) alone / the 20-mode step: "
              f"{mm[INTEGRALS][0] / fe['loop step'][0]:.2f}")


if __name__ == "__main__":
    main()
