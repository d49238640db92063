"""The face-normal liquid's full-order stiffness without a dense matrix on the faces (pure JAX).

K = kappa M + B^T Y B (liquid/face/schur.py): the consistent mass M element by element (each element's
6 x 6 block on its faces' unknowns), B = [D; T] (each element's outward flux, each top face's flux)
by gathers, and Y = W - kappa G^+ dense on each tank's elements and top faces (ny = E + T per tank,
about nf / 2.7): a product streams ny^2 entries where the dense K streams nf^2, about 7 times more.
The products take d of shape (n,) or (n, k); they are linear, so they differentiate, transpose
and vmap as jnp code does.
"""
from __future__ import annotations

from typing import Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np


class FaceOps(eqx.Module):
    """The sparse structure of the stacked tanks' free faces: each element's six unknowns (`n` where
    the face is held), the signs that make them outward fluxes, the top faces' unknowns, and each
    tank's elements and top faces (static ranges; tank t's B rows are its elements' fluxes, then its
    top faces')."""
    slots: jax.Array        # (E, 6) int32
    signs: jax.Array        # (E, 6)
    top: jax.Array          # (T,) int32
    n: int = eqx.field(static=True)
    elements: tuple = eqx.field(static=True)     # per tank (start, stop) of its elements
    tops: tuple = eqx.field(static=True)         # per tank (start, stop) of its top faces
    # (n, 2) int32: each unknown's places in slots.reshape(-1) (a face has at most two elements; E * 6:
    # none), so that `scatter` is a gather and a sum (XLA's CPU scatter, a serial loop, took three
    # times as long); None: by segment_sum (`owners` builds it)
    places: Optional[jax.Array] = None
    # (n,) int32: each unknown's place among the top faces (T: not a top face), so that adding the top
    # faces' values is a gather of them padded with a zero, not XLA's CPU scatter; None: `.at[].add`
    top_of: Optional[jax.Array] = None

    def gather(self, d):
        """(n, ...) -> (E, 6, ...)"""
        dz = jnp.concatenate([d, jnp.zeros((1,) + d.shape[1:], d.dtype)])
        return dz[self.slots]

    def scatter(self, v):
        """(E, 6, ...) -> (n, ...), the transpose of gather."""
        flat = v.reshape((-1,) + v.shape[2:])
        if self.places is not None:
            flat = jnp.concatenate([flat, jnp.zeros((1,) + flat.shape[1:], flat.dtype)])
            return flat[self.places[:, 0]] + flat[self.places[:, 1]]
        return jax.ops.segment_sum(flat, self.slots.reshape(-1), self.n + 1)[:self.n]

    def elementwise(self, Ae, d):
        """sum_e P_e^T A_e P_e d for element blocks Ae (E, 6, 6)."""
        return self.scatter(jnp.einsum("efg,eg...->ef...", Ae, self.gather(d)))

    def B(self, d):
        """Per tank: its elements' outward fluxes, then its top faces' fluxes ((ny_t, ...) each)."""
        div = jnp.einsum("ef,ef...->e...", self.signs, self.gather(d))
        tp = d[self.top]
        return [jnp.concatenate([div[a:b], tp[c:e]]) for (a, b), (c, e) in zip(self.elements, self.tops)]

    def BT(self, ys):
        """The transpose of B: per-tank (ny_t, ...) -> (n, ...)."""
        div = jnp.concatenate([y[:b - a] for y, (a, b) in zip(ys, self.elements)])
        tp = jnp.concatenate([y[b - a:] for y, (a, b) in zip(ys, self.elements)])
        out = self.scatter(self.signs.reshape(self.signs.shape + (1,) * (div.ndim - 1)) * div[:, None])
        return self.add_top(out, tp)

    def add_top(self, out, tp):
        """out (n, ...) plus tp (T, ...) on the top faces' unknowns."""
        if self.top_of is None:
            return out.at[self.top].add(tp)
        return out + jnp.concatenate([tp, jnp.zeros((1,) + tp.shape[1:], tp.dtype)])[self.top_of]


def top_places(top, n: int):
    """`FaceOps.top_of` of the top faces' unknowns `top` (T,) (host)."""
    out = np.full(n, len(top), dtype=np.int32)
    out[np.asarray(top)] = np.arange(len(top), dtype=np.int32)
    return out


def owners(slots, n: int):
    """`FaceOps.places` of the (E, 6) slots (host; n: a held face): each unknown's one or two
    places, E * 6 (a zero) where it has one."""
    flat = np.asarray(slots).reshape(-1)
    order = np.argsort(flat, kind="stable")
    keys = flat[order]
    first = np.searchsorted(keys, np.arange(n))
    count = np.searchsorted(keys, np.arange(n), side="right") - first
    if np.any(count > 2) or np.any(count < 1):
        raise ValueError("a free face belongs to one or two elements")
    places = np.full((n, 2), flat.size, dtype=np.int32)
    places[:, 0] = order[first]
    two = count == 2
    places[two, 1] = order[first[two] + 1]
    return places


class FaceStiffness(eqx.Module):
    """K = kappa M + B^T Y B on the stacked tanks' free faces (`K @ d`, d: (n,) or (n, k))."""
    ops: FaceOps
    kappa_M: jax.Array      # (E, 6, 6) each element's mass block times its tank's kappa
    Y: tuple                # per tank (ny_t, ny_t): W - kappa G^+
    abs_rowsum: jax.Array   # (n,) sum_j |K_ij| (the Newton iterations' round-off floor)
    winv: tuple             # per tank (ny_t,) W^-1 (the Newton block's inverse is formed from Y, W, kappa)
    kappa_n: jax.Array      # (n,) each unknown's tank's kappa
    kappas: jax.Array       # (tanks,) each tank's kappa (an array: a static float would name the program)
    # at values other than the model's (traced density, sound speed, gravity): per tank its mass scale
    # rho_s and its pools' null vectors (ny_t, pools), from which the Newton block's inverse is formed
    # in JAX (liquid/face/inverse.py); None: the model's values, the inverse formed on the host
    rho: Optional[tuple] = None
    pools: Optional[tuple] = None

    @property
    def shape(self):
        return (self.ops.n, self.ops.n)

    def __matmul__(self, d):
        ys = self.ops.B(d)
        return self.ops.elementwise(self.kappa_M, d) + self.ops.BT([Y @ y for Y, y in zip(self.Y, ys)])
