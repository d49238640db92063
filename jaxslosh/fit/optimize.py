"""The optimisers of `identify`: damped Gauss-Newton (Levenberg-Marquardt) on the residual, and
optax's L-BFGS or Adam on the loss."""
from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import optax

from .problem import Problem

_FTOL, _XTOL, _GTOL = 1e-10, 1e-8, 1e-8


_LBFGS_MAX_STEP = 0.25


def gauss_newton(pb: Problem, theta, max_iter, callback, history):
    res, J, ok = pb.residual_jacobian(theta)
    last = (res, J, ok)
    if not ok:
        return theta, 0, False, "the simulation at the start failed (Newton not converged or non-finite values)", last
    ssr = float(res @ res)
    history.append(ssr / pb.n)
    lam = 1e-3
    it, converged, message = 0, False, f"stopped after max_iter = {max_iter} iterations"
    while it < max_iter:
        g = J.T @ res
        A = J.T @ J
        d = np.maximum(np.diag(A), 1e-12 * max(1.0, float(np.max(np.diag(A)))))
        colnorm = np.sqrt(np.diag(A))
        if np.all(np.abs(g) <= _GTOL * np.maximum(colnorm, 1e-300) * math.sqrt(ssr)) or ssr == 0.0:
            converged, message = True, "gradient orthogonal to the residual"
            break
        accepted, any_ok = False, False
        for _ in range(12):
            try:
                step = np.linalg.solve(A + lam * np.diag(d), -g)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            t_new = theta + step
            r_new, J_new, ok_new = pb.residual_jacobian(t_new)
            ssr_new = float(r_new @ r_new) if ok_new else math.inf
            any_ok = any_ok or ok_new
            if ssr_new < ssr:
                accepted = True
                break
            lam *= 10.0
        if not accepted:
            if any_ok:      # no damping lowers the SSR: a minimum to round-off
                converged, message = True, "no step lowers the loss (a minimum to round-off)"
            else:
                message = "every trial step failed to simulate (Newton did not converge or non-finite values)"
            break
        it += 1
        rel = (ssr - ssr_new) / ssr
        theta, res, J, ssr = t_new, r_new, J_new, ssr_new
        last = (res, J, True)
        lam = max(lam / 10.0, 1e-12)
        history.append(ssr / pb.n)
        if callback is not None and callback(it, pb.values(theta), ssr / pb.n):
            message = "stopped by the callback"
            break
        if rel < _FTOL:
            converged, message = True, f"relative loss decrease {rel:.2g} < {_FTOL:g}"
            break
        if np.max(np.abs(step)) < _XTOL:
            converged, message = True, f"step {np.max(np.abs(step)):.2g} < {_XTOL:g}"
            break
    return theta, it, converged, message, last


def optax_loop(pb: Problem, theta, method, max_iter, callback, history, learning_rate):

    theta = jnp.asarray(theta)
    if method == "adam":
        lr = learning_rate if learning_rate is not None else 0.02
        opt = optax.adam(lr)

        def update(th, state, data):
            value, grad = jax.value_and_grad(pb.loss)(th, data)
            upd, state = opt.update(grad, state, th)
            return optax.apply_updates(th, upd), state, value, 1
    else:
        # optax.lbfgs, with the quasi-Newton direction capped at _LBFGS_MAX_STEP in theta before the
        # line search (which may still lengthen it): without the cap the first step (a unit ball in
        # theta) jumps into the wrong valley of an oscillation fit (GM_L 30 % low -> 3 x too high)
        opt = optax.chain(optax.scale_by_lbfgs(), optax.clip_by_global_norm(_LBFGS_MAX_STEP),
                          optax.scale(-1.0) if learning_rate is None else optax.scale_by_learning_rate(learning_rate),
                          optax.scale_by_zoom_linesearch(max_linesearch_steps=20))
        lr = learning_rate

        def update(th, state, data):
            loss = lambda x: pb.loss(x, data)  # noqa: E731
            value, grad = optax.value_and_grad_from_state(loss)(th, state=state)
            upd, state = opt.update(grad, state, th, value=value, grad=grad, value_fn=loss)
            n_ls = optax.tree_utils.tree_get(state, "info").num_linesearch_steps
            return optax.apply_updates(th, upd), state, value, n_ls

    state = opt.init(theta)
    update = pb.compiled((method, lr), update, theta, state, pb.data)
    it, converged, message, flat = 0, False, f"stopped after max_iter = {max_iter} iterations", 0
    final_known = False          # whether history[-1] is the loss at the returned theta
    while it < max_iter:
        t_new, state, value, n_eval = update(theta, state, pb.data)
        value = float(value)      # the loss at theta (before this update)
        pb.evaluations += int(n_eval) if method == "lbfgs" else 1
        history.append(value)
        final_known = True
        if len(history) == 1:
            if not math.isfinite(value):
                return np.asarray(theta), 0, False, "the simulation at the start failed", True
        else:
            prev = history[-2]
            flat = flat + 1 if abs(prev - value) <= _FTOL * max(abs(prev), 1e-300) else 0
            if callback is not None and callback(it, pb.values(theta), value):
                message = "stopped by the callback"
                break
            if flat >= 5:
                converged, message = True, f"loss changed by < {_FTOL:g} relative over 5 iterations"
                break
        if not bool(jnp.all(jnp.isfinite(t_new))):
            message = "the optimiser produced non-finite parameters"
            break
        step = float(jnp.max(jnp.abs(t_new - theta)))
        theta = t_new
        final_known = False
        it += 1
        if step < _XTOL:
            converged, message = True, f"step {step:.2g} < {_XTOL:g}"
            break
    return np.asarray(theta), it, converged, message, final_known
