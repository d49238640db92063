"""The compiled time loop: one `lax.scan` over saved frames (each frame `save_every` steps) around
the step of solve/integrator.py. A step that fails (Newton not converged, non-finite values)
freezes the state; the carry remembers the first failure, so the host can report it."""
from __future__ import annotations

import math
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp

from ..build.system import Built
from ..physics import structures as mb
from ..physics.kinematics import rotation_matrix
from ..solve.integrator import State, initial_state, step_or_retry
from ..solve.linear import Solver


class Carry(NamedTuple):
    s: State
    k: jax.Array          # steps done
    failed: jax.Array     # a step has failed: the state is frozen since
    fail_step: jax.Array
    fail_err: jax.Array
    fail_it: jax.Array
    n: jax.Array          # steps attempted, failed or not: the same for every run of a batch (never batched)


class Frame(NamedTuple):
    t: jax.Array
    X0: jax.Array
    q: jax.Array
    omega: jax.Array
    probes: jax.Array
    ke: jax.Array
    pe: jax.Array
    iterations: jax.Array
    residual: jax.Array
    D: jax.Array          # liquid nodal displacement (N, 3), empty without liquid; a reduced liquid's eta (m,)
    failed: jax.Array
    gmax: jax.Array       # max |g| of the interface constraints (m), 0 without structures


def _frame(b: Built, s: State, it, err, failed) -> Frame:
    sysm = b.system
    flex = getattr(sysm, "flex", None)
    V0, om = s.v[:3], s.v[3:6]
    if flex is None:
        dd = s.v[6:]
    else:
        dd = mb.layout(sysm).split(s.v)[2]
    A = rotation_matrix(s.c.q)
    pr = b.probes
    if pr.modal is not None:       # reduced liquid: the frame keeps eta, mapped to nodes after the run
        D = s.c.d
        local = pr.points + jnp.einsum("pkc,k->pc", pr.modal, D)
    elif sysm.liquid is not None:
        D = sysm.liquid.full(s.c.d)
        local = pr.points + pr.weights @ D
    else:
        D = jnp.zeros((0, 3))
        local = pr.points
    probes = s.c.X0[None, :] + local @ A.T
    ke = sysm.kinetic_energy(s.c, V0, om, dd)
    pe = sysm.potential_energy(s.c)
    gmax = jnp.zeros(())
    if flex is not None:
        gmax = jnp.max(jnp.abs(mb.constraint(sysm, s.c, s.alg)))
        ke = ke + mb.structure_kinetic(sysm, s.c, s.v)
        pe = pe + mb.structure_potential(sysm, s.c)
        etas = mb.split_eta(flex, s.c.eta)
        for sp in pr.on_structures:
            body = flex.bodies[sp.index]
            x = sp.r + sp.W @ body.u(etas[sp.index])
            probes = probes.at[sp.rows].set(s.c.Xs[sp.index][None, :] + x @ rotation_matrix(s.c.qs[sp.index]).T)
    return Frame(s.t, s.c.X0, s.c.q, om, probes, ke, pe, it, err, D, failed, gmax)


def core(b: Built) -> Built:
    """What the compiled loop needs: the host-side tank blocks (NumPy meshes) stay out of it."""
    return b._replace(tanks=(), structures=())


def _select(pred, a, b):
    return jax.tree_util.tree_map(lambda x, y: jnp.where(pred, x, y), a, b)


@eqx.filter_jit
def start(b: Built, solver: Solver):
    s0, info = initial_state(b.system, solver, b.c0, b.v0, b.alg0)
    failed = ~info.ok
    carry = Carry(s0, jnp.array(0), failed, jnp.where(failed, 0, -1), info.residual, info.iterations, jnp.array(0))
    return carry, _frame(b, s0, info.iterations, info.residual, failed)


#: runs of at least this many steps are checkpointed in blocks (see advance)
REMAT_MIN_STEPS = 5000


@eqx.filter_jit
def advance(b: Built, solver: Solver, carry: Carry, n_frames: int, save_every: int):
    """n_frames frames of save_every steps each: one scan of scans, no Python loop in traced code."""

    def one_step(c: Carry, _):
        s_new, info = step_or_retry(b.system, solver, c.s, c.n)
        bad = ~info.ok & ~c.failed
        keep = c.failed | ~info.ok
        s = _select(keep, c.s, s_new)
        c2 = Carry(s, c.k + jnp.where(keep, 0, 1), c.failed | ~info.ok,
                   jnp.where(bad, c.k + 1, c.fail_step), jnp.where(bad, info.residual, c.fail_err),
                   jnp.where(bad, info.iterations, c.fail_it), c.n + 1)
        return c2, (info.iterations, info.residual)

    def one_frame(c: Carry, _):
        c, (its, errs) = jax.lax.scan(one_step, c, None, length=save_every)
        return c, _frame(b, c.s, its.max(), errs.max(), c.failed)

    def frames(c, n):
        return jax.lax.scan(one_frame, c, None, length=n)

    # Reverse mode through long runs: blocks of K ~ sqrt(n) frames are checkpointed (jax.checkpoint
    # keeps only the block boundaries and recomputes a block's steps when its gradient is taken), so
    # a gradient's memory stops growing with the steps. Measured on the paper example (peak RSS of
    # one gradient): 1.22 / 1.60 / 2.37 GB at 1,000 / 4,000 / 10,000 steps without, 1.76 / 1.67 /
    # 1.45 GB with (a larger compiled program); so only runs of REMAT_MIN_STEPS or more take it.
    K = _block_size(n_frames)
    if n_frames * save_every < REMAT_MIN_STEPS or K < 4:
        return frames(carry, n_frames)
    nb, rem = divmod(n_frames, K)
    carry, fr = jax.lax.scan(jax.checkpoint(lambda c, _: frames(c, K)), carry, None, length=nb)
    fr = jax.tree_util.tree_map(lambda x: x.reshape((nb * K,) + x.shape[2:]), fr)
    if rem:
        carry, tail = frames(carry, rem)
        fr = concat_frames([fr, tail])
    return carry, fr


def _block_size(n: int) -> int:
    """Frames per checkpointed block: a divisor of n near sqrt(n) where there is one (no remainder
    scan, so the step is compiled once), else sqrt(n)."""
    r = math.isqrt(n)
    for k in sorted(range(max(1, r // 2), 2 * r + 1), key=lambda k: abs(k - r)):
        if n % k == 0:
            return k
    return r


def concat_frames(frames):
    return jax.tree_util.tree_map(lambda *xs: jnp.concatenate(xs), *frames)


def nodal(b: Built, D):
    """Frames' liquid displacement as nodal fields (..., N, 3): a reduced liquid's frames hold its
    modal coordinates (storing the nodal field every step cost more than the step itself)."""
    if b.probes.modal is not None:
        return jnp.einsum("...k,knc->...nc", D, b.system.liquid.U)
    return D
