"""Newton iterations with the structured approximate inverse of the step matrix, and the tangent
solves of the implicit function theorem (`lax.custom_root`).

The first `ns` unknowns (the rigid ones, and the frames and multipliers of the terms that own some)
enter nonlinearly: their rows and columns of the Jacobian are linearised with JAX (ns products each
way) and closed by a Schur complement; the rest (liquid and elastic modal coordinates) is replaced by
a constant block whose inverse `Cinv` is formed once per run (solve/linear.py).
"""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp

from ..fem.linalg import inv


def _precond_data_split(parts_m, Ac, x, Cinv, nr, ns):
    """As _precond_data for A = Am + Ac, when unknowns nr..ns (interface frames and multipliers) enter
    the residual only through the cheap part Ac (the constraints), whose rows nr..ns are all of A's
    there: the first ns columns and rows of A are Ac's plus, in the first nr, Am's. Am is the
    linearisation of the expensive part given in parts, parts_m(x[:nr], x[ns:]) = (its rows nr.., its
    rows ns..) (zero on rows nr..ns), linearised in x[:nr] alone for its columns and transposed in
    x[ns:] alone for its rows, as in _precond_data_parts."""
    n = x.shape[0]
    I = jnp.eye(n, ns, dtype=x.dtype)
    cm, Am_yz = _parts_linearised(parts_m, x[:nr], x[ns:])
    cols = jax.vmap(Ac, in_axes=1, out_axes=1)(I)
    cols = cols.at[:nr, :nr].add(cm[:nr]).at[ns:, :nr].add(cm[nr:])
    if n == ns:                      # no constant block (no liquid, no deformable unknowns)
        return (inv(cols),)
    AcT = jax.linear_transpose(Ac, x)
    Ayz = jax.vmap(lambda e: AcT(e)[0])(I.T)[:, ns:].at[:nr].add(Am_yz)
    Wz = Cinv @ cols[ns:]
    return inv(cols[:ns] - Ayz @ Wz), Ayz, Wz


def _parts_linearised(parts, y, z):
    """For a residual given in parts, parts(y, z) = (R_y, R_z): its columns over y, [A_yy; A_zy]
    ((ny + nz, ny), by linearising in y alone), and its rows R_y over z, A_yz ((ny, nz), by a
    transpose in z alone: the terms that R_y shares with z, the liquid's, not the whole residual;
    see physics/system.residual_parts). None for A_yz when z is empty."""
    I = jnp.eye(y.shape[0], dtype=y.dtype)
    _, jvp_y = jax.linearize(lambda y_: jnp.concatenate(parts(y_, z)), y)
    cols = jax.vmap(jvp_y, in_axes=1, out_axes=1)(I)
    if z.shape[0] == 0:
        return cols, None
    _, vjp_z = jax.vjp(lambda z_: parts(y, z_)[0], z)
    return cols, jax.vmap(lambda e: vjp_z(e)[0])(I)


def _precond_data_parts(parts, x, Cinv, ns):
    """As _precond_data for the residual given in parts, parts(x[:ns], x[ns:]) (_parts_linearised)."""
    cols, Ayz = _parts_linearised(parts, x[:ns], x[ns:])
    if Ayz is None:
        return (inv(cols),)
    Wz = Cinv @ cols[ns:]
    return inv(cols[:ns] - Ayz @ Wz), Ayz, Wz


def _precond_data(A, like, Cinv, ns=6):
    """The factors of P^-1 for a linear map A with the Newton matrix's structure: the first ns rows
    and columns exact (ns products with A, ns with its transpose: the rigid unknowns, and the
    interface frames and multipliers when there are flexible structures), the rest (liquid and
    elastic modal coordinates) replaced by the constant C (inverse Cinv); a Schur complement on the
    ns unknowns. Exact without liquid and structures."""
    n = like.shape[0]
    E6 = jnp.eye(n, ns, dtype=like.dtype)
    cols = jax.vmap(A, in_axes=1, out_axes=1)(E6)                   # [A_yy; A_zy]
    if n == ns:
        return (inv(cols),)
    AT = jax.linear_transpose(A, like)
    Ayz = jax.vmap(lambda e: AT(e)[0])(E6.T)[:, ns:]                 # (ns, nz)
    Wz = Cinv @ cols[ns:]
    return inv(cols[:ns] - Ayz @ Wz), Ayz, Wz


def _precond_apply(data, Cinv, r, ns=6):
    if len(data) == 1:
        return data[0] @ r
    S_inv, Ayz, Wz = data
    wz = Cinv @ r[ns:]
    xy = S_inv @ (r[:ns] - Ayz @ wz)
    return jnp.concatenate([xy, wz - Wz @ xy])


def _preconditioner(A, like, Cinv, ns=6):
    data = _precond_data(A, like, Cinv, ns)
    return lambda r: _precond_apply(data, Cinv, r, ns)

#: a carried preconditioner is formed again when an iteration reduces the residual by less than this
#: factor (a fresh one converges 1e-3 to 1e-4 per iteration on the paper example)
SLOW = 0.01

#: the iterations stop with the update just prepared, without evaluating R once more to see it, when
#: the residual it leaves, estimated from the last two contractions, is below this fraction of the
#: tolerance. The contraction grows from pass to pass (the structured inverse solves the stiff part
#: of the first residual exactly; what is left contracts at the rate of the Coriolis coupling it
#: leaves out), up to ten times from one pass to the next: with 0.05 the residual that the update
#: left stayed below 0.82 of the tolerance on 1,200 steps of the paper example and the shaped tanks
#: (docs/benchmarks.md, the shaped tanks against their floor), and the step returns what the
#: iterations would have returned after that evaluation in all but the steps where they would have
#: gone on
EARLY = 0.05


class NewtonStatus(NamedTuple):
    """How a root was found: the evaluations of the residual after the first, the scaled residual's
    largest entry at the end (after an early stop, see EARLY, its estimate), and whether that is
    converged."""
    iterations: jax.Array
    error: jax.Array
    ok: jax.Array


class NewtonState(NamedTuple):
    """The iterations' carry: `dx` is the update prepared by the last pass (applied by the next),
    `it` counts evaluations of R from -1 (none yet), `fresh` says the update came from a
    preconditioner formed for it, `need` asks the next pass to form one, `data` its factors;
    `err1` the error of the pass before, `early` that `dx` leaves a residual estimated below the
    tolerance (EARLY; `est` the estimate): the iterations stop and the root is x + dx."""
    x: jax.Array
    dx: jax.Array
    it: jax.Array
    err: jax.Array
    fresh: jax.Array
    stalled: jax.Array
    need: jax.Array
    data: tuple
    err1: jax.Array
    early: jax.Array
    est: jax.Array


class StructuredNewton(eqx.Module):
    """Quasi-Newton iterations on R(x) = 0 (x: `ns` rigid and algebraic unknowns, then the liquid's
    and the structures' modal ones) with the structured approximate inverse of the Jacobian (the
    first `ns` rows and columns exact, the rest the constant block `Cinv`), formed at the first
    iteration of the step and formed again only when the residual stops falling fast (a rotation
    that changed a lot). A root finder in optimistix's shape: `init`, `step`, `terminate`, driven
    by `root` in one `lax.while_loop`.

    `floor`: the round-off floor of the scaled residual; the iterations stop below max(tol, floor).
    `adaptive=False`: the preconditioner is formed once before the iterations, never inside
    (vmapped batches, where a lax.cond computes both branches). `split` = (Rm, Rc, nr, parts_m):
    R = Rm + Rc, unknowns nr..ns enter R only through the cheap part Rc, and parts_m gives Rm in
    parts (see _precond_data_split). `parts`: R in parts (see _precond_data_parts)."""
    Cinv: object
    scale: jax.Array
    tol: jax.Array
    max_iter: int = eqx.field(static=True)
    adaptive: bool = eqx.field(static=True, default=True)
    ns: int = eqx.field(static=True, default=6)
    split: object = eqx.field(static=True, default=None)
    parts: object = eqx.field(static=True, default=None)

    def error(self, r):
        return jnp.max(jnp.abs(r / self.scale))

    @jax.named_scope("preconditioner")
    def precondition(self, R, x):
        """The factors of the structured inverse of R's Jacobian at x."""
        if self.split is not None:     # R = Rm + Rc, each part linearised once (not R, then Rc again)
            _, Rc, nr, parts_m = self.split
            _, jvp_c = jax.linearize(Rc, x)
            return _precond_data_split(parts_m, jvp_c, x, self.Cinv, nr, self.ns)
        if self.parts is not None:
            return _precond_data_parts(self.parts, x, self.Cinv, self.ns)
        _, jvp = jax.linearize(R, x)
        return _precond_data(jvp, x, self.Cinv, self.ns)

    def going(self, it, err, stalled):
        return (err > self.tol) & (it < self.max_iter) & jnp.isfinite(err) & ~stalled

    def init(self, R, x0, pre=None, fresh=None) -> NewtonState:
        """The state before the first evaluation. `pre` = (data, valid): a preconditioner carried
        from the previous step, used while it keeps the convergence fast (formed afresh when not
        valid). Not adaptive, with `pre` carried, `fresh` (a boolean that is the same for every run
        of a batch) says whether to form it anew or use the carried one through this step."""
        if not self.adaptive:
            if pre is not None and fresh is not None:
                # `fresh` only, never the carried validity flag, which is per run: the predicate
                # stays unbatched and the cond a branch (the first step of a run is always fresh)
                data0 = jax.lax.cond(fresh, lambda x: self.precondition(R, x), lambda _: pre[0], x0)
            else:
                data0 = self.precondition(R, x0)
            need0 = jnp.array(False)
            # whether the preconditioner was formed for this step (a carried one converges more
            # slowly without being stalled: see `step`)
            fresh0 = jnp.asarray(True) if pre is None or fresh is None else jnp.asarray(fresh)
            return NewtonState(x0, jnp.zeros_like(x0), jnp.array(-1), jnp.array(jnp.inf, x0.dtype), fresh0,
                               jnp.array(False), need0, data0, jnp.array(jnp.inf, x0.dtype), jnp.array(False),
                               jnp.array(jnp.inf, x0.dtype))
        elif pre is not None:
            data0, need0 = pre[0], ~(pre[1] > 0.5)
        else:    # placeholders of the shapes precondition returns (eval_shape would trace it again)
            n, ns = x0.shape[0], self.ns
            data0 = ((jnp.zeros((ns, ns), x0.dtype),) if n == ns else
                     (jnp.zeros((ns, ns), x0.dtype), jnp.zeros((ns, n - ns), x0.dtype),
                      jnp.zeros((n - ns, ns), x0.dtype)))
            need0 = jnp.array(True)
        return NewtonState(x0, jnp.zeros_like(x0), jnp.array(-1), jnp.array(jnp.inf, x0.dtype), jnp.array(False),
                           jnp.array(False), need0, data0, jnp.array(jnp.inf, x0.dtype), jnp.array(False),
                           jnp.array(jnp.inf, x0.dtype))

    def step(self, R, s: NewtonState) -> NewtonState:
        """One pass: apply the update the last pass prepared, evaluate R (R appears once in the
        program: a residual before the loop would be compiled a second time), judge the update, and
        prepare the next, forming the preconditioner again where the last update was slow. From the
        third evaluation on, an update whose residual, estimated from the last two contractions, is
        below EARLY times the tolerance is the last: the loop stops without evaluating R at it."""
        x = s.x + s.dx
        r = R(x)
        err = self.error(r)
        first = s.it < 0
        # a stale preconditioner that slows down is formed again; a fresh one that cannot is a stall.
        # Batches cannot form it again inside the iterations: a carried one (formed some steps
        # before, the rigid block's Jacobian since moved by large rotations) may contract by less
        # than half per pass and still converge; it stalls only where the residual stops falling
        stalled = ~first & jnp.where(s.fresh, err > 0.5 * s.err, (not self.adaptive) & (err >= s.err))
        need = jnp.where(first, s.need, err > jnp.where(s.fresh, 0.1, SLOW) * s.err)
        it = s.it + 1
        going = self.going(it, err, stalled)
        est = err * jnp.maximum(err / s.err, s.err / s.err1)   # the last two contractions' larger
        early = going & (it >= 2) & (est <= EARLY * self.tol)
        if self.adaptive:
            def prepare(data):   # (an early last update takes the factors it has: they contract enough)
                data = jax.lax.cond(need & ~early, lambda x_: self.precondition(R, x_), lambda _: data, x)
                return data, _precond_apply(data, self.Cinv, -r, self.ns)

            data, dx = jax.lax.cond(going, prepare, lambda d: (d, jnp.zeros_like(x)), s.data)
        else:    # batches: the preconditioner is fixed through the iterations (a cond on a per-run
            data, dx = s.data, _precond_apply(s.data, self.Cinv, -r, self.ns)  # test runs both branches)
        return NewtonState(x, dx, it, err, s.fresh if not self.adaptive else need, stalled, need, data, s.err, early,
                           est)

    def terminate(self, s: NewtonState):
        """(done, status): converged below the tolerance, stopped early (its last update's residual
        estimated below EARLY times it), or stalled at round-off within a factor 100 of it; out of
        iterations, or not finite."""
        done = (s.it >= 0) & (s.early | ~self.going(s.it, s.err, s.stalled))
        ok = jnp.isfinite(s.err) & ((s.err <= self.tol) | s.early | (s.stalled & (s.err <= 100.0 * self.tol)))
        return done, NewtonStatus(s.it, jnp.where(s.early, s.est, s.err), ok)

    def root(self, R, x0, pre=None, fresh=None):
        """The iterations from x0: returns x and the aux `lax.custom_root` carries (floats: its JVP
        rule cannot carry integer or boolean aux tangents), with the preconditioner used last and a
        valid flag when `pre` was carried in."""
        s = jax.lax.while_loop(lambda s: ~self.terminate(s)[0], lambda s: self.step(R, s), self.init(R, x0, pre, fresh))
        _, st = self.terminate(s)
        aux = (st.iterations.astype(float), st.error, st.ok.astype(float))
        if pre is not None:
            aux = aux + ((s.data, jnp.ones(())),)
        return jnp.where(s.early, s.x + s.dx, s.x), aux


def _newton(R, x0, Cinv, scale, tol, max_iter, pre=None, floor=0.0, adaptive=True, ns=6, split=None, fresh=None,
            parts=None):
    """`StructuredNewton(...).root(R, x0, pre, fresh)` with the tolerance raised to the round-off floor."""
    solver = StructuredNewton(Cinv, scale, jnp.maximum(tol, floor), max_iter, adaptive, ns, split, parts)
    return solver.root(R, x0, pre, fresh)


def _structured_linear_solve(A, b, Cinv, rtol=1e-13, max_sweeps=30, ns=6):
    """Solve A x = b to full precision: the structured preconditioner, then Richardson sweeps.
    The same code solves the transposed system (pass A^T), which reverse mode needs."""
    P_inv = _preconditioner(A, b, Cinv, ns)
    bnorm = jnp.max(jnp.abs(b)) + 1e-300

    def cond(c):
        _, res, k = c
        return (jnp.max(jnp.abs(res)) > rtol * bnorm) & (k < max_sweeps)

    def body(c):
        x, res, k = c
        x = x + P_inv(res)
        return x, b - A(x), k + 1

    x0 = P_inv(b)
    x, _, _ = jax.lax.while_loop(cond, body, (x0, b - A(x0), 0))
    return x


def _tangent_solver(Cinv, ns=6):
    def tangent_solve(g, y):
        return jax.lax.custom_linear_solve(
            g, y, solve=lambda A, b: _structured_linear_solve(A, b, Cinv, ns=ns),
            transpose_solve=lambda AT, b: _structured_linear_solve(AT, b, Cinv, ns=ns))
    return tangent_solve


def _root(R, x0, newton, Cinv, ns, implicit):
    """newton(R, x0), differentiable by the implicit function theorem when `implicit`."""
    if not implicit:
        return newton(R, x0)
    return jax.lax.custom_root(R, x0, newton, _tangent_solver(Cinv, ns), has_aux=True)


def solve_root(R, x0, Cinv, scale, tol, max_iter, ns=6, split=None, implicit=True, parts=None):
    """Root of R near x0; differentiable by the implicit function theorem (lax.custom_root), the
    tangent systems solved with the same structure as the Newton iterations (`implicit=False`: the
    iterations alone, for runs that no gradient goes through)."""
    x, (it, err, ok) = _root(R, x0, lambda f, x: _newton(f, x, Cinv, scale, tol, max_iter, ns=ns, split=split,
                                                         parts=parts), Cinv, ns, implicit)
    it, err, ok = jax.lax.stop_gradient((it, err, ok))
    return x, NewtonStatus(it.astype(jnp.int32), err, ok > 0.5)


def solve_root_carried(R, x0, Cinv, scale, tol, max_iter, pre=None, floor=0.0, adaptive=True, ns=6, split=None,
                       fresh=None, implicit=True, parts=None):
    """`solve_root` with a preconditioner carried in and out (`pre`, see `_newton`; None: formed
    here and not returned), a round-off floor and the batch mode. Returns x, (it, err, ok), pre."""
    out = _root(R, x0, lambda f, x: _newton(f, x, Cinv, scale, tol, max_iter, pre, floor, adaptive, ns, split, fresh,
                                            parts), Cinv, ns, implicit)
    x, aux = out
    it, err, ok = jax.lax.stop_gradient(aux[:3])
    new_pre = jax.lax.stop_gradient(aux[3]) if pre is not None else None
    return x, NewtonStatus(it.astype(jnp.int32), err, ok > 0.5), new_pre
