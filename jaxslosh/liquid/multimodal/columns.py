"""Derivatives of a three-dimensional multimodal tank's integrals column by column
(liquid/multimodal/tank3d.py).

Every integral over the liquid is a sum over the base's quadrature points q of what the column above
q holds, and that depends on the amplitudes beta only through the column's height H_q = h + F_q . beta:

    I(beta) = sum_q c_q(H_q),    dI/dbeta_j = sum_q c_q'(H_q) F_qj.

Automatic differentiation carries every direction in beta through the whole quadrature (Q columns
times NZ depth points times N modes, once per direction: a Jacobian in N directions costs N
evaluations, the Newton preconditioner's second derivatives N more). Here the columns' derivatives
in their own height are formed once, by one forward pass with a unit tangent on every column
(the columns are independent), and any direction's tangent is then that array times the direction's
height change H_dot_q: N directions cost one derivative evaluation and N products. The rule is its
own derivative one order up (`column_values` of order k + 1), so that Newton's Jacobian of the rows
(which hold first derivatives) and gradients through a run stay exact and cheap. Derivatives in the
geometry (traced scene parameters) go through ordinary forward differentiation."""
from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
from jax.custom_derivatives import SymbolicZero


def _derivative(fn, order: int):
    """fn's per-column derivative of the given order in H (nested forward passes, unit tangents)."""
    for _ in range(order):
        fn = (lambda f: lambda H, geo: jax.jvp(lambda h: f(h, geo), (H,), (jnp.ones_like(H),))[1])(fn)
    return fn


@functools.partial(jax.custom_jvp, nondiff_argnums=(0, 1))
def column_values(fn, order: int, H, geo):
    """The columns' values fn(H, geo) (a pytree of arrays, each with the column axis first, each
    column's entries functions of its own H alone), or their derivative of `order` in H."""
    return _derivative(fn, order)(H, geo)


def _column_jvp(fn, order, primals, tangents):
    H, geo = primals
    H_dot, geo_dot = tangents
    out = column_values(fn, order, H, geo)
    tan = jax.tree_util.tree_map(jnp.zeros_like, out)
    if not isinstance(H_dot, SymbolicZero):
        d = column_values(fn, order + 1, H, geo)
        tan = jax.tree_util.tree_map(lambda t, a: t + a * H_dot.reshape(H_dot.shape + (1,) * (a.ndim - 1)), tan, d)
    leaves = jax.tree_util.tree_leaves(geo_dot, is_leaf=lambda x: isinstance(x, SymbolicZero))
    if any(not isinstance(x, SymbolicZero) for x in leaves):
        # a traced geometry (scene parameters under differentiation): its tangents the ordinary way
        geo_dot = jax.tree_util.tree_map(lambda x, t: jnp.zeros_like(x) if isinstance(t, SymbolicZero) else t,
                                         geo, geo_dot, is_leaf=lambda x: isinstance(x, SymbolicZero))
        g = jax.jvp(lambda gg: _derivative(fn, order)(H, gg), (geo,), (geo_dot,))[1]
        tan = jax.tree_util.tree_map(jnp.add, tan, g)
    return out, tan


column_values.defjvp(_column_jvp, symbolic_zeros=True)


# The two-dimensional tank's (term.py) other derivative formed in products.
@jax.custom_jvp
def spd_inverse(A):
    """A^-1, its derivatives -X dA X in matrix products only: differentiated twice (the rows take
    the mass matrix's derivative, Newton the rows'), a solve's would factorise batches of matrices."""
    return jnp.linalg.inv(A)


@spd_inverse.defjvp
def _spd_inverse_jvp(primals, tangents):
    X = spd_inverse(primals[0])
    return X, -X @ tangents[0] @ X
