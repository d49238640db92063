"""The quasi-static elastic catenary of one mooring line (docs/guide/moorings.md).

Given the fairlead's horizontal and vertical distance from the anchor (XF, ZF), the unstretched
length L, the submerged weight per unstretched metre w (negative: buoyant), the axial stiffness EA,
the seabed friction coefficient CB and the anchor's height hA above the seabed, the line's
profile equations give (XF, ZF) as closed-form functions of the fairlead tension's horizontal and
vertical components (H, V) (Jonkman's form, as FAST, MAP++ and MoorPy use it). One function
`profile` covers every branch, chosen from (H, V) alone so that the branches meet continuously:

* suspended (no seabed contact; buoyant lines, taut lines, raised anchors whose sag stays above
  the seabed);
* touchdown (anchor on the seabed, L_B = L - V/w on the seabed, with Coulomb friction CB w per
  metre: the tension falls linearly along the seabed portion and may reach zero before the anchor);
* U-shaped (raised anchor, the line dips to the seabed between anchor and fairlead).

`solve` finds (H, V) by Newton from the inextensible estimate of Peyrot & Goulois (the start
MAP++ and MoorPy use) or, for a line stretched beyond its length, the straight elastic bar; the
iterations run in a `lax.while_loop` and the gradients come from the implicit function theorem
(`jax.lax.custom_root`), not from the iterations.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

#: Newton stops when both profile residuals are below this fraction of the line's length
TOL = 1e-13
MAX_ITER = 200
#: Newton iterations from a warm start before the cold solve takes over (one or two suffice for the
#: previous step's solution)
WARM_ITER = 8
#: chord steps from a warm start with its Jacobian (from a step's motion, two or three reach round-off)
CHORD_STEPS = 3
#: the step's residual takes the chord steps' solution where every line's scaled residual before
#: the last step is below this (the last gains some four digits more; else NaN: the step fails and
#: says so); the full solve at the step's end reaches TOL
CHORD_TOL = 1e-9


class Catenary(NamedTuple):
    """One line's solution (N, m): the tension's components at the fairlead (H towards the anchor,
    V > 0 when the line pulls the fairlead down) and at the anchor (horizontal towards the
    fairlead, vertical > 0 lifting the anchor), the unstretched length on the seabed and the 2x2
    stiffness [[dH/dXF, dH/dZF], [dV/dXF, dV/dZF]]."""
    fairlead_horizontal: jax.Array
    fairlead_vertical: jax.Array
    anchor_horizontal: jax.Array
    anchor_vertical: jax.Array
    seabed_length: jax.Array
    stiffness: jax.Array



def _asinh_chord(a, b):
    """(asinh a - asinh b) / (a - b), smooth through a = b (a weightless or taut line): the
    Taylor series about the midpoint where the difference would cancel."""
    d = a - b
    m = 0.5 * (a + b)
    small = jnp.abs(d) < 1e-2
    d_safe = jnp.where(small, 1.0, d)
    direct = (jnp.arcsinh(jnp.where(small, m + 0.5, a)) - jnp.arcsinh(jnp.where(small, m - 0.5, b))) / d_safe
    s = 1.0 + m * m
    series = (s ** -0.5 + (2 * m * m - 1) * s ** -2.5 * d * d / 24.0
              + (24 * m ** 4 - 72 * m * m + 9) * s ** -4.5 * d ** 4 / 1920.0)
    return jnp.where(small, series, direct)


def _suspended(H, V, L, w, EA):
    # products by reciprocals, not quotients: XLA fuses no divide that two expressions share into
    # both, so each shared quotient was a kernel of its own (eight kernels an evaluation, three now;
    # the step evaluates the profile in every residual: docs/benchmarks.md, mooring lines)
    hi, ei = 1.0 / H, 1.0 / EA
    a = V * hi
    b = (V - w * L) * hi
    xf = L * _asinh_chord(a, b) + H * L * ei
    zf = L * (a + b) / (jnp.sqrt(1 + a * a) + jnp.sqrt(1 + b * b)) + (V * L - 0.5 * w * L * L) * ei
    return xf, zf


def _rise_slope(H, h, w, EA):
    """The slope sinh at the top of a catenary that rises h from its lowest point (zero slope) with
    horizontal tension H: H/w (cosh - 1) + H^2 sinh^2 / (2 EA w) = h is a quadratic in y = cosh - 1,
    solved in its cancellation-free form."""
    ae = H * H / (2 * EA * w)
    B = H / w + 2 * ae
    y = 2 * h / (B + jnp.sqrt(B * B + 4 * ae * h))
    # sqrt's slope is infinite at 0 (an anchor on the seabed): kept out of the gradient there
    pos = y > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, y * (y + 2), 1.0)), 0.0)


def _contact(H, V, L, w, EA, CB, hA):
    """The line on the seabed: (XF, ZF, L_B, the anchor's horizontal and vertical force), w > 0."""
    # the part between a raised anchor and the seabed
    u = _rise_slope(H, hA, w, EA)
    wi, hi, ei = 1.0 / w, 1.0 / H, 1.0 / EA       # products by reciprocals (see _suspended)
    s1 = H * u * wi
    s2 = V * wi
    LB = L - s1 - s2
    # friction acts only where the seabed portion ends at the anchor (a raised anchor's U-shaped
    # line slides towards its middle from both sides: taken frictionless)
    cbw = jnp.where(hA > 0, 0.0, CB) * w
    cbw_safe = jnp.where(cbw > 0, cbw, 1.0)
    slack_part = jnp.maximum(cbw * LB - H, 0.0)
    friction = (-cbw * LB * LB + jnp.where(cbw > 0, slack_part ** 2 / cbw_safe, 0.0)) * (0.5 * ei)
    a = V * hi
    xf = (LB + H * wi * jnp.arcsinh(u) + H * wi * jnp.arcsinh(a) + H * L * ei + friction)
    zf = H * wi * (jnp.sqrt(1 + a * a) - 1) + V * V * (0.5 * ei * wi) - hA
    return xf, zf, LB, jnp.maximum(H - cbw * LB, 0.0), -w * s1


def profile(H, V, L, w, EA, CB=0.0, hA=0.0):
    """(XF, ZF, seabed length, anchor horizontal, anchor vertical) of the line whose fairlead
    tension is (H, V), H > 0, on whichever branch (H, V) lies."""
    wc = jnp.where(w > 0, w, 1.0)
    xc, zc, LB, HA, VA = _contact(H, V, L, wc, EA, CB, hA)
    contact = (w > 0) & (LB > 0)
    xs, zs = _suspended(H, V, L, w, EA)
    LB = jnp.where(contact, LB, 0.0)
    # the anchor's vertical force: minus the weight of the line between a raised anchor and the
    # seabed (0 on the touchdown branch), V - wL when suspended: equal where the branches meet
    return (jnp.where(contact, xc, xs), jnp.where(contact, zc, zs), LB,
            jnp.where(contact, HA, H), jnp.where(contact, VA, V - w * L))


def _start(XF, ZF, L, w, EA):
    """Peyrot & Goulois's inextensible estimate (a buoyant line as the mirror image of a hanging
    one); for a line longer stretched than its length, the straight elastic bar carrying half its
    weight at each end."""
    sign = jnp.where(w < 0, -1.0, 1.0)
    ws = jnp.maximum(jnp.abs(w), 1e-12 * EA / L)
    zs = ZF * sign
    dist = jnp.sqrt(XF * XF + ZF * ZF)
    xsafe = jnp.where(XF > 0, XF, 1.0)
    ratio = jnp.maximum((L * L - zs * zs) / (xsafe * xsafe) - 1.0, 1e-6)
    lam = jnp.where(XF <= 0, 1e6, jnp.where(dist >= L, 0.2, jnp.sqrt(3 * ratio)))
    H0 = jnp.maximum(jnp.abs(0.5 * ws * XF / lam), 1e-6 * ws * L)
    V0 = sign * 0.5 * ws * (zs / jnp.tanh(lam) + L)
    T = EA * (dist / L - 1.0)
    dsafe = jnp.where(dist > 0, dist, 1.0)
    taut = dist > L
    H0 = jnp.where(taut, jnp.maximum(H0, T * XF / dsafe), H0)
    V0 = jnp.where(taut, T * ZF / dsafe + 0.5 * w * L, V0)
    return jnp.stack([H0, V0])


def _newton(residual, x0, scale):
    # the residual and its Jacobian from one forward-mode pass, and the error of the step's result
    # from the line search's own trial residuals: each appears once in the loop's body (every copy
    # is compiled again wherever the solve is traced)
    jac = jax.jacfwd(lambda x: (lambda r: (r, r))(residual(x)), has_aux=True)

    def step(state):
        x, _, it = state
        J, r = jac(x)
        det = J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]
        dx = -jnp.array([J[1, 1] * r[0] - J[0, 1] * r[1], J[0, 0] * r[1] - J[1, 0] * r[0]]) / det
        # a backtracking line search, all trial steps at once (no Python or traced loop over
        # them): the longest step of 1, 1/2, ..., 1/2^11 that lowers the residual (Armijo),
        # else the one that lowers it most; H stays positive (a step that would cross zero goes
        # a tenth of the way there instead)
        norm0 = jnp.sum(r * r)
        alpha = 0.5 ** jnp.arange(12.0)
        H = jnp.maximum(x[0] + alpha * dx[0], 0.1 * x[0])
        trial = jnp.stack([H, x[1] + alpha * dx[1]], axis=1)
        rs = jax.vmap(residual)(trial)
        norms = jnp.sum(rs * rs, axis=1)
        norms = jnp.where(jnp.isfinite(norms), norms, jnp.inf)
        ok = norms <= (1 - 1e-4 * alpha) * norm0
        pick = jnp.where(jnp.any(ok), jnp.argmax(ok), jnp.argmin(norms))
        return trial[pick], jnp.max(jnp.abs(rs[pick])) / scale, it + 1

    def cond(state):
        _, err, it = state
        return (err > TOL) & (it < MAX_ITER)

    x, err, _ = jax.lax.while_loop(cond, step, (x0, jnp.asarray(jnp.inf, x0.dtype), 0))
    # a line that did not converge gives NaN, which the caller's own Newton reports with its step
    return jnp.where(err <= 1e3 * TOL, x, jnp.nan)


def _contact_solve(XF, ZF, L, w, EA, CB, hA):
    """The solution on the seabed branch, found as a one-dimensional problem: there the vertical
    span fixes V for each H (the fairlead's part rises ZF + hA from the seabed), and XF grows
    with H. Newton on log H inside a bracket that bisection keeps (a flat or steep profile
    cannot throw it out)."""
    def parts(logH):
        H = jnp.exp(logH)
        V = H * _rise_slope(H, ZF + hA, w, EA)
        return _contact(H, V, L, w, EA, CB, hA)[0] - XF, V

    f = lambda h: parts(h)[0]  # noqa: E731
    scale = jnp.log(jnp.abs(w) * L)

    def step(state):
        # the value and slope from one jvp, and the error tested at the iterate the step starts
        # from (one more step past convergence): the profile appears once in the loop's body
        h, lo, hi, _, it = state
        r, dr = jax.jvp(f, (h,), (jnp.ones_like(h),))
        lo = jnp.where(r < 0, h, lo)
        hi = jnp.where(r > 0, h, hi)
        new = h - r / dr
        inside = jnp.isfinite(new) & (new > lo) & (new < hi)
        new = jnp.where(inside, new, 0.5 * (lo + hi))
        # a converged iterate stays (a step rounded to nothing would fall outside the bracket)
        return jnp.where(jnp.abs(r) / L <= TOL, h, new), lo, hi, jnp.abs(r) / L, it + 1

    cond = lambda state: (state[3] > TOL) & (state[4] < MAX_ITER)  # noqa: E731
    lo, hi = scale - 40.0, jnp.log(EA) + 10.0
    h0 = jnp.clip(jnp.log(_start(XF, ZF, L, w, EA)[0]), lo + 1.0, hi - 1.0)
    h, *_ = jax.lax.while_loop(cond, step, (h0, lo, hi, jnp.asarray(jnp.inf, h0.dtype), 0))
    H = jnp.exp(h)
    return jnp.stack([H, parts(h)[1]])


def _slack(XF, ZF, L, w, EA, CB, hA):
    """(whether the line is slack, the tiny H that stands for zero there): a line anchored so
    close that even with no horizontal tension its seabed portion would reach past the anchor
    lies piled on the seabed: H = 0, and V carries the part hanging from the fairlead."""
    wc = jnp.where(w > 0, w, 1.0)
    H0 = jnp.abs(wc) * L * jnp.exp(-40.0)
    V0 = H0 * _rise_slope(H0, ZF + hA, wc, EA)
    return (w > 0) & (_contact(H0, V0, L, wc, EA, CB, hA)[0] >= XF), H0


def _solve_iterations(residual, XF, ZF, L, w, EA, CB, hA):
    """(H, V) by the seabed branch's one-dimensional solve where it lands on that branch, else by
    Newton on the whole profile from the inextensible or taut estimate."""
    wc = jnp.where(w > 0, w, 1.0)
    slack, H0 = _slack(XF, ZF, L, w, EA, CB, hA)
    xc = _contact_solve(XF, ZF, L, wc, EA, CB, hA)
    on_seabed = (w > 0) & (profile(xc[0], xc[1], L, w, EA, CB, hA)[2] > 0) & jnp.all(jnp.isfinite(xc))
    xs = _newton(residual, _start(XF, ZF, L, w, EA), 1.0)
    x_slack = jnp.stack([H0, H0 * _rise_slope(H0, ZF + hA, wc, EA)])
    return jnp.where(slack, x_slack, jnp.where(on_seabed, xc, xs))


def solve(XF, ZF, L, w, EA, CB=0.0, hA=0.0):
    """The fairlead tension (H, V) of the line with spans (XF, ZF); differentiable in every
    argument through the implicit function theorem."""
    XF, ZF, L, w, EA, CB, hA = (jnp.asarray(v, dtype=float) for v in (XF, ZF, L, w, EA, CB, hA))
    slack, H0 = jax.lax.stop_gradient(_slack(XF, ZF, L, w, EA, CB, hA))

    residual = _line_residual(L, w, EA, CB, hA, XF, ZF, slack, H0)

    def tangent_solve(g, y):
        return jnp.linalg.solve(jax.jacfwd(g)(y), y)

    spans = jax.lax.stop_gradient((XF, ZF, L, w, EA, CB, hA))
    x0 = jnp.zeros(2)
    return jax.lax.custom_root(residual, x0, lambda f, _: _solve_iterations(f, *spans), tangent_solve)


def _line_residual(L, w, EA, CB, hA, XF, ZF, slack, H0):
    """One line's residual in its fairlead tension x = (H, V): the profile's spans minus the given."""
    def residual(x):
        xf, zf = profile(x[0], x[1], L, w, EA, CB, hA)[:2]
        # a slack line has no horizontal tension (H0 stands for zero): XF no longer matters
        first = jnp.where(slack, (x[0] - H0) / jnp.abs(w), xf - XF)
        return jnp.stack([first, zf - ZF]) / L
    return residual


def _lines_iterations(XF, ZF, L, w, EA, CB, hA):
    """(n, 2) solutions of n lines: the seabed branch's one-dimensional solve for all, and the
    whole-profile Newton (its line search tries twelve steps an iteration: four fifths of a
    solve's cost) only when some line is off the seabed: moored lines at rest and in their
    working range touch it, and the step solves them in every residual evaluation."""
    wc = jnp.where(w > 0, w, 1.0)
    slack, H0 = jax.vmap(_slack)(XF, ZF, L, w, EA, CB, hA)
    xc = jax.vmap(_contact_solve)(XF, ZF, L, wc, EA, CB, hA)
    on_seabed = ((w > 0) & (jax.vmap(profile)(xc[:, 0], xc[:, 1], L, w, EA, CB, hA)[2] > 0)
                 & jnp.all(jnp.isfinite(xc), axis=1))

    def newton(_):
        def one(XF, ZF, L, w, EA, CB, hA, slack, H0):
            return _newton(_line_residual(L, w, EA, CB, hA, XF, ZF, slack, H0), _start(XF, ZF, L, w, EA), 1.0)
        return jax.vmap(one)(XF, ZF, L, w, EA, CB, hA, slack, H0)

    xs = jax.lax.cond(jnp.any(~(slack | on_seabed)), newton, lambda _: jnp.zeros_like(xc), None)
    x_slack = jnp.stack([H0, H0 * jax.vmap(_rise_slope)(H0, ZF + hA, wc, EA)], axis=1)
    return jnp.where(slack[:, None], x_slack, jnp.where(on_seabed[:, None], xc, xs))


def _lines_residual(XF, ZF, L, w, EA, CB, hA, slack, H0):
    """x (n, 2) -> the n lines' residuals (n, 2) (_line_residual of each)."""
    def residual(x):
        return jax.vmap(lambda *a: _line_residual(*a[:9])(a[9]))(L, w, EA, CB, hA, XF, ZF, slack, H0, x)
    return residual


def _blocks(residual, x):
    """The lines' 2 x 2 Jacobians (n, 2, 2) of a residual whose lines are independent: two products
    (every line's H, then every line's V, moved at once), not 2n."""
    cols = jax.vmap(lambda e: jax.jvp(residual, (x,), (jnp.broadcast_to(e, x.shape),))[1])(jnp.eye(2, dtype=x.dtype))
    return jnp.moveaxis(cols, 0, -1)


def _solve2(J, r):
    """J^-1 r for (n, 2, 2) blocks, in closed form (a batched LAPACK call costs more than the line)."""
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    return jnp.stack([J[:, 1, 1] * r[:, 0] - J[:, 0, 1] * r[:, 1], J[:, 0, 0] * r[:, 1] - J[:, 1, 0] * r[:, 0]],
                     axis=1) / det[:, None]


def _err(r):
    """Each line's largest scaled residual (inf where it is not finite)."""
    return jnp.where(jnp.isfinite(r[:, 0]) & jnp.isfinite(r[:, 1]), jnp.maximum(jnp.abs(r[:, 0]), jnp.abs(r[:, 1])),
                     jnp.inf)


def _chord(residual, guess, inverse, r0=None):
    """(x, the residual before the last step) after CHORD_STEPS chord steps from `guess` with
    `inverse` (n, 2, 2), the inverse of the residual's Jacobian at the guess: one evaluation of the
    profile each, none after the last (within a step's motion each step gains some four digits; the
    evaluations are a small part of what the lines add to a step: docs/benchmarks.md, the moored
    step's pieces), a line held once below TOL.
    Written out, no loop: a `lax.while_loop` inside the residual runs apart from the step's fused
    kernels. `r0`: the residual at the guess where the caller has it (`_start_residual`)."""
    x, r = guess, residual(guess) if r0 is None else r0
    for k in range(CHORD_STEPS):       # a fixed count, unrolled: not a loop over time steps
        x = jnp.where((_err(r) <= TOL)[:, None], x, _descend(x, _times(inverse, r)))
        if k < CHORD_STEPS - 1:
            r = residual(x)
    return x, r


def _start_residual(XF, ZF, L, w, slack, H0, guess, at):
    """The lines' residual at `guess` from `at` (n, 2), the profile's spans (XF, ZF) there, kept
    from where the guess was solved: no evaluation of the profile (`_line_residual`'s terms)."""
    first = jnp.where(slack, (guess[:, 0] - H0) / jnp.abs(w), at[:, 0] - XF)
    return jnp.stack([first, at[:, 1] - ZF], axis=1) / L[:, None]


def _lines_chord(XF, ZF, L, w, EA, CB, hA, slack, H0, guess, inverse, at=None):
    """The chord steps of `_chord` alone, no fallback: what the step's residual solves (it is
    evaluated in every Newton iteration and traced again in every linearisation of the step, where
    a fallback's loops and cold solve would be compiled again each time). A line whose residual
    before the last step is still above CHORD_TOL (a step that moved it far, a branch change) gives
    NaN, which fails the step with its number (or redoes it in sub-steps, `[simulation] substeps`);
    the step's end refreshes the guess (`lines_settle`, once a step). `at`: the profile's spans at
    the guess (then the residual there is not evaluated: one evaluation of the profile fewer in
    every evaluation of the step's residual)."""
    r0 = None if at is None else _start_residual(XF, ZF, L, w, slack, H0, guess, at)
    x, r = _chord(_lines_residual(XF, ZF, L, w, EA, CB, hA, slack, H0), guess, inverse, r0)
    return jnp.where((_err(r) <= CHORD_TOL)[:, None], x, jnp.nan)


def _lines_warm(XF, ZF, L, w, EA, CB, hA, slack, H0, guess, inverse=None):
    """`_lines_iterations` from a nearby solution `guess` (n, 2) (the previous step's): the chord
    steps of `_chord` where the Jacobian's `inverse` there is given; then, and without `inverse`,
    Newton where some line is still above TOL, each line held once below it (a loop that does not
    run when the chord steps converged); where some line has not converged in WARM_ITER
    iterations (a guess from far away, a branch change), the cold solve of every line."""
    residual = _lines_residual(XF, ZF, L, w, EA, CB, hA, slack, H0)
    x = guess if inverse is None else _chord(residual, guess, inverse)[0]
    r = residual(x)

    def newton(state):
        x, r, it = state
        x = jnp.where((_err(r) <= TOL)[:, None], x, _descend(x, _solve2(_blocks(residual, x), r)))
        return x, residual(x), it + 1

    def polish(state):
        x, r, _ = jax.lax.while_loop(lambda s: jnp.any(_err(s[1]) > TOL) & (s[2] < WARM_ITER), newton, state[:3])
        # the cold solve in a loop that runs at most once: under vmap a lax.cond would run it always
        x, _ = jax.lax.while_loop(lambda s: s[1], lambda s: (_lines_iterations(XF, ZF, L, w, EA, CB, hA), False),
                                  (x, jnp.any(_err(r) > TOL)))
        return x, residual(x), 0, False

    return jax.lax.while_loop(lambda s: s[3], polish, (x, r, 0, jnp.any(_err(r) > TOL)))[0]


def _times(inverse, r):
    """(n, 2) the products of (n, 2, 2) blocks and (n, 2) vectors, written out: a batched dot is an
    XLA kernel of its own (and so is a reduction over the pair, `_err`), where these products fuse
    with the profile's arithmetic around them."""
    return inverse[:, :, 0] * r[:, :1] + inverse[:, :, 1] * r[:, 1:]


def _descend(x, dx):
    """x - dx with H kept positive (a step that would cross zero goes nine tenths of the way there)."""
    return jnp.stack([jnp.maximum(x[:, 0] - dx[:, 0], 0.1 * x[:, 0]), x[:, 1] - dx[:, 1]], axis=1)


def _inv2(J):
    """(n, 2, 2) the inverses of (n, 2, 2) blocks, in closed form."""
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    return jnp.stack([jnp.stack([J[:, 1, 1], -J[:, 0, 1]], -1), jnp.stack([-J[:, 1, 0], J[:, 0, 0]], -1)],
                     1) / det[:, None, None]


def _prepared(XF, ZF, L, w, EA, CB, hA):
    """The lines' residual (`_lines_residual`) and (slack, H0) (`_slack`), values as float arrays."""
    XF, ZF, L, w, EA, CB, hA = (jnp.asarray(v, dtype=float) for v in (XF, ZF, L, w, EA, CB, hA))
    slack, H0 = jax.vmap(_slack)(XF, ZF, L, w, EA, CB, hA)
    return _lines_residual(XF, ZF, L, w, EA, CB, hA, slack, H0), slack, H0


def lines_inverse(XF, ZF, L, w, EA, CB, hA, x):
    """(n, 2, 2) the inverse of the lines' residual Jacobian at their solution x (n, 2): what
    `solve_lines` keeps for chord steps from there."""
    return _inv2(_blocks(_prepared(XF, ZF, L, w, EA, CB, hA)[0], x))


def lines_settle(XF, ZF, L, w, EA, CB, hA, guess, inverse, at=None):
    """((n, 2) solutions, (n, 2, 2) the inverses of the Jacobians there, (n, 2) the profile's spans
    there) from the last step's `guess`, `inverse` and `at` (`_lines_chord`'s): what a step's end
    keeps for the next (once a step, no loop). One chord step from the guess, which needs no
    evaluation of the profile (its residual there comes from `at`), then one evaluation of the
    profile with its Jacobian (a jvp in two directions) and a Newton step from there: the chord step
    leaves the step's motion times the chord's rate (some four digits below the motion's), the
    Newton step squares that, to round-off wherever the step's own chord steps converged (where
    they did not, the step has failed, NaN, and its states are not kept). The Jacobian is the one
    before the Newton step (within round-off of the solution's), and the spans at the solution are
    the fairlead's own (XF, ZF), which the Newton step leaves within round-off (a slack line's
    horizontal span is not read: its residual is its tension's). One evaluation of the profile,
    where the step's chord steps, a Newton step and the spans took four: each is a chain of small
    XLA kernels, and their count, not their arithmetic, was what the step's end cost
    (docs/benchmarks.md, mooring lines)."""
    XF, ZF, L, w = (jnp.asarray(v, dtype=float) for v in (XF, ZF, L, w))
    residual, slack, H0 = _prepared(XF, ZF, L, w, EA, CB, hA)
    r0 = residual(guess) if at is None else _start_residual(XF, ZF, L, w, slack, H0, guess, at)
    x = jnp.where((_err(r0) <= TOL)[:, None], guess, _descend(guess, _times(inverse, r0)))
    r, cols = jax.vmap(lambda e: jax.jvp(residual, (x,), (jnp.broadcast_to(e, x.shape),)),
                       out_axes=(None, 0))(jnp.eye(2, dtype=x.dtype))
    J = jnp.moveaxis(cols, 0, -1)
    x = jnp.where((_err(r) <= TOL)[:, None], x, _descend(x, _solve2(J, r)))
    return x, _inv2(J), jnp.stack([XF, ZF], axis=1)


def lines_spans(L, w, EA, CB, hA, x):
    """(n, 2) the profile's spans (XF, ZF) of the lines at tensions x (n, 2)."""
    return jnp.stack(jax.vmap(profile)(x[:, 0], x[:, 1], L, w, EA, CB, hA)[:2], axis=1)


def solve_lines(XF, ZF, L, w, EA, CB, hA, guess=None, inverse=None, fallback=True, at=None):
    """(n, 2) fairlead tensions (H, V) of n lines ((n,) arrays of spans and values): the same
    solutions as `solve` line by line, the whole-profile Newton run only where a line needs it
    (`_lines_iterations`), or Newton from `guess` (n, 2), a nearby solution such as the previous
    step's (`_lines_warm`, with chord steps where the Jacobian's `inverse` there is given, as
    `lines_inverse` gives it; with `fallback=False` those chord steps alone, `_lines_chord`, from
    the residual at the guess that `at`, the profile's spans there, gives);
    differentiable in every argument through the implicit function
    theorem, one 2 x 2 solve per line, whatever the guess."""
    XF, ZF, L, w, EA, CB, hA = (jnp.asarray(v, dtype=float) for v in (XF, ZF, L, w, EA, CB, hA))
    slack, H0 = jax.lax.stop_gradient(jax.vmap(_slack)(XF, ZF, L, w, EA, CB, hA))
    residual = _lines_residual(XF, ZF, L, w, EA, CB, hA, slack, H0)

    def tangent_solve(g, y):
        # the lines are independent: their 2 x 2 blocks, each solved alone
        return _solve2(_blocks(g, y), y)

    spans = jax.lax.stop_gradient((XF, ZF, L, w, EA, CB, hA))
    if guess is None:
        iterate = lambda f, _: _lines_iterations(*spans)  # noqa: E731
    else:
        inv = None if inverse is None else jax.lax.stop_gradient(inverse)
        if fallback or inv is None:
            iterate = lambda f, x0: _lines_warm(*spans, slack, H0, x0, inv)  # noqa: E731
        else:
            at = None if at is None else jax.lax.stop_gradient(at)
            iterate = lambda f, x0: _lines_chord(*spans, slack, H0, x0, inv, at)  # noqa: E731
    x0 = jnp.zeros((XF.shape[0], 2)) if guess is None else jax.lax.stop_gradient(guess)
    return jax.lax.custom_root(residual, x0, iterate, tangent_solve)


@jax.jit
def catenary(span: tuple, length: float, weight: float, ea: float, seabed_friction: float = 0.0,
             anchor_height: float = 0.0) -> Catenary:
    """One elastic catenary line (docs/guide/moorings.md).

    Args:
        span: (XF, ZF), the fairlead's horizontal and vertical distance from the anchor, m.
        length: unstretched length L, m.
        weight: submerged weight per unstretched metre w, N/m (negative: buoyant).
        ea: axial stiffness EA, N.
        seabed_friction: Coulomb friction coefficient of the part on the seabed.
        anchor_height: the anchor's height above the seabed, m (the seabed still below it).

    Returns:
        A `Catenary` (a NamedTuple of arrays), differentiable in every argument.
    """
    XF, ZF = span
    args = tuple(jnp.asarray(v, dtype=float) for v in (XF, ZF, length, weight, ea, seabed_friction, anchor_height))
    def solved(s):
        x = solve(s[0], s[1], *args[2:])
        return x, x
    # the solution as the derivative's own primal: the solve traced (and compiled) once
    K, (H, V) = jax.jacfwd(solved, has_aux=True)(jnp.stack(args[:2]))
    _, _, LB, HA, VA = profile(H, V, *args[2:])
    return Catenary(H, V, HA, VA, LB, K)
