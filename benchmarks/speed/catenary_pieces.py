"""The three catenary lines' solve inside the moored step, piece by piece.

    python -m benchmarks.speed.catenary_pieces [--rounds 7] [--quick]

The lines of benchmarks/speed/mooring_cost.py (420 m, 600 N/m, EA 3e8 N, spans 395 m x 99 m, all
three solved at once as the step's term solves them), the fairleads moved 1 mm from the guess:
what each evaluation of the step's residual runs (the chord steps from the last step's solution,
`solve_lines(..., fallback=False)`), its linearisation (one jvp: what the step's preconditioner
and gradients take, through the implicit function theorem), the step's end (`lines_settle`: one
chord step, one evaluation with the Jacobian there and a Newton step, once a step) and one evaluation of the
profile alone; then the lines' whole term in the moored paper example (its rows: the fairleads'
spans, the solve, the force and moment; their linearisation in the six rigid directions; its
step's end). Each in a compiled `fori_loop` of many calls (a call alone would time the dispatch),
process CPU time per call, best of the rounds; then the free paper example's step (js.Stepper) in
the same run, to put them in proportion. A moored step of the paper example evaluates its residual
some 4.3 times (3.3 Newton iterations after the first evaluation, the same as the free step's),
linearises it once (the preconditioner) and settles once. No assertion.
"""
import jax
import jax.numpy as jnp

import jaxslosh as js
from benchmarks.harness import Table, best_of, parser, scene, time_scene
from benchmarks.speed.mooring_cost import LINES
from jaxslosh.mooring import catenary as cat
from jaxslosh.mooring.term import mooring_term
from jaxslosh.physics.kinematics import rotation_matrix
from jaxslosh.physics.terms import Kin

CALLS = 2000


def pieces():
    """{piece: a function of a scalar d that runs it CALLS times, d feeding each call}."""
    n = 3
    L, w, EA, CB, hA = (jnp.full(n, v) for v in (420.0, 600.0, 3e8, 0.0, 0.0))
    XF, ZF = jnp.full(n, 395.0), jnp.full(n, 99.0)
    x0 = cat.solve_lines(XF, ZF, L, w, EA, CB, hA)
    inv = cat.lines_inverse(XF, ZF, L, w, EA, CB, hA, x0)
    at = cat.lines_spans(L, w, EA, CB, hA, x0)

    def solve(xf):
        return cat.solve_lines(xf, ZF, L, w, EA, CB, hA, x0, inv, False, at)

    def settle(xf):
        return sum(jnp.sum(a) for a in cat.lines_settle(xf, ZF, L, w, EA, CB, hA, x0, inv, at))

    each = {"residual's chord solve": lambda d: jnp.sum(solve(XF + 1e-3 + d)),
            "its linearisation (jvp)": lambda d: jnp.sum(jax.jvp(solve, (XF + 1e-3 + d,), (jnp.ones(n),))[1]),
            "step's end (settle)": lambda d: settle(XF + 1e-3 + d),
            "one profile evaluation": lambda d: jnp.sum(cat.lines_spans(L, w, EA, CB, hA, x0 + d))}
    each.update(term_pieces())
    # each call feeds the next through a negligible d: XLA can neither hoist nor merge the calls
    return {k: jax.jit(lambda d, f=f: jax.lax.fori_loop(0, CALLS, lambda i, d: d + 1e-300 * f(d), d))
            for k, f in each.items()}


def term_pieces():
    """The lines' whole term in the moored paper example after 20 steps (its states warm): its
    rows (the fairleads' spans, the solve, the force and moment), their linearisation in the six
    rigid directions (as the preconditioner takes it) and its step's end."""
    st = js.Stepper(js.scene_with(scene("paper_ship_tank"), {"environment.depth": 100.0, "mooring": LINES}))
    s = st.advance(st.init(), 20).s
    system = st.built.system
    term = mooring_term(system)
    z = s.z[system.all_terms().index(term)]

    def rows(x):               # x: the first three of the six rigid directions move X0
        c = s.c._replace(X0=s.c.X0 + x[:3])
        A = rotation_matrix(c.q)
        k = Kin(c, s.v[:3], s.v[3:6], jnp.zeros(0), jnp.zeros(6), jnp.zeros(0), s.t, z, A, A.T @ jnp.array([0, 0, -9.81]))
        return term.rows(k).rigid

    x0 = jnp.full(6, 1e-4)
    return {"the lines' term: its rows": lambda d: jnp.sum(rows(x0 + d)),
            "its rows' linearisation (6 columns)": lambda d: jnp.sum(jax.vmap(jax.linearize(rows, x0 + d)[1])(
                jnp.eye(6))),
            "its step's end (state_settle)": lambda d: jnp.sum(term.state_settle(z, s.c._replace(X0=s.c.X0 + d)))}


def main():
    ap = parser(__doc__)
    ap.add_argument("--rounds", type=int, default=7)
    a = ap.parse_args()
    rounds = 2 if a.quick else a.rounds
    fns = pieces()
    for f in fns.values():
        jax.block_until_ready(f(0.0))
    free = time_scene("free", scene("paper_ship_tank"), steps=50 if a.quick else 200, repeat=rounds)
    table = Table(("piece", "{}"), ("CPU us/call", "{:.2f}"), ("% of the free step", "{:.2f}"))
    step = free.cpu_us_per_step
    for k, f in fns.items():
        cpu = best_of(lambda f=f: f(0.0), rounds)[1] / CALLS * 1e6
        table.add(k, cpu, 100 * cpu / step)
    table.add("the free paper step", step, 100.0)
    table.print(markdown=a.markdown)
    n_res = 4.3
    for first in (0, 4):
        per = [best_of(lambda f=f: f(0.0), rounds)[1] / CALLS * 1e6 for f in list(fns.values())[first:first + 3]]
        total = n_res * per[0] + per[1] + per[2]
        print(f"{'the solves' if first == 0 else 'the whole term'} in a moored step ({n_res} residuals, one "
              f"linearisation, one settle): {total:.1f} us, {100 * total / step:.1f} % of the free step")


if __name__ == "__main__":
    main()
