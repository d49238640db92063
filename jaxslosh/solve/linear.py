"""The constant blocks of the Newton matrix, inverted once per run: the liquid's (formed by the
liquid itself, AbstractLiquid.step_inverse) and the structures' modal block."""
from __future__ import annotations

import dataclasses
from typing import Any, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..physics.system import System
from .schemes import Scheme


class Solver(eqx.Module):
    """What the Newton iterations need besides the system: constant liquid-block inverses."""
    Cinv_step: jax.Array   # (nf, nf) inverse of c_a M_ff + K_ff (liquid block of the step matrix)
    Cinv_mass: jax.Array   # (nf, nf) inverse of M_ff (liquid block of the initial-acceleration matrix)
    h: jax.Array                     # step (traced: one compilation serves every step size)
    scheme: Scheme = eqx.field(static=True)
    tol: float = eqx.field(static=True)
    max_iter: int = eqx.field(static=True)
    substeps: int = eqx.field(static=True, default=0)   # retry a failed step as this many sub-steps
    Cinv_sub: Optional[jax.Array] = None                # liquid block inverse for the sub-step
    # Speed (none changes what a converged step is):
    # the round-off floor of the scaled residual per metre of liquid displacement, eps max_i
    # sum_j |K_ij| / scale_i: a tolerance below eps |K| |d| cannot be met, so the iterations stop there
    noise: Any = 0.0
    # carry the preconditioner from step to step, formed again only when convergence slows (single
    # runs); False: formed once at the start of every step
    reuse: bool = eqx.field(static=True, default=False)
    # refresh the preconditioner inside the iterations when convergence slows (a lax.cond); False
    # for vmapped batches, where a cond computes both branches
    adaptive: bool = eqx.field(static=True, default=True)
    # unknowns of the exact (Schur) block: the 6 rigid ones, and the owners' rigid and algebraic
    # unknowns (physics/unknowns.Layout.n_small); a nonlinear liquid's too
    ns: int = eqx.field(static=True, default=6)
    # after each step, scale the velocities so that the total energy is the initial one (the
    # `simulation.energy_projection` key: trapezoidal rule, conservative scenes only; see project_energy)
    project: bool = eqx.field(static=True, default=False)
    # with reuse and not adaptive (vmapped batches): the carried preconditioner is formed afresh at
    # every this-many-th step (the step counter is the same for every run of a batch, so the cond
    # stays a branch under vmap); 0: at every step
    refresh_every: int = eqx.field(static=True, default=0)
    # the vmapped runs' axis name (batches): a step that failed with the carried preconditioner is
    # redone with a fresh one, decided for the batch by a collective over this axis so that the
    # cond stays a branch (integrator.step_or_retry); None for single runs (adaptive)
    batch_axis: Optional[str] = eqx.field(static=True, default=None)
    # the Newton solves are differentiable (lax.custom_root: gradients by the implicit function
    # theorem). False where nothing a run depends on is traced for differentiation (run.prepare):
    # custom_root traces the linearisation and both tangent solves of every root even when no
    # gradient is taken, a fifth of a scene's tracing; the iterations and their result are the same
    implicit: bool = eqx.field(static=True, default=True)

    def sub_solver(self) -> "Solver":
        return Solver(self.Cinv_sub, self.Cinv_mass, self.h / self.substeps, self.scheme, self.tol, self.max_iter,
                      noise=self.noise, adaptive=self.adaptive, ns=self.ns, project=self.project,
                      implicit=self.implicit)

    @property
    def c_a(self):
        return self.scheme.c_a(self.h)


def make_solver(system: System, h: float, scheme: Scheme, tol: float, max_iter: int, substeps: int = 0,
                reuse: bool = False, adaptive: bool = True) -> Solver:
    """Factor the constant liquid blocks once (float64): NumPy for concrete matrices, JAX when the
    liquid was built from traced values (under jit); the terms that own deformable unknowns append
    their block, diagonal (the structures' modal one, Phi^T M Phi = I, Phi^T K Phi = omega^2:
    1 / (c_a + omega^2)) or a small dense one (the bodies' tanks' liquid, inverted here), and their
    rigid and algebraic unknowns join the exact block.

    The inverses only precondition the Newton iterations and the tangent solves, whose solutions do
    not depend on them (`lax.custom_root` drops their tangents), so they are formed from
    `stop_gradient` values: under `jax.grad` outside jit the matrices are then concrete again."""
    substeps = int(substeps) if substeps and substeps > 1 else 0
    base = _liquid_solver(system, h, scheme, tol, max_iter, substeps, reuse, adaptive)
    sub = _extended(base.Cinv_sub, system.deformable_block(scheme.c_a(h / substeps), 1.0)) if substeps else None
    return dataclasses.replace(base, Cinv_step=_extended(base.Cinv_step, system.deformable_block(scheme.c_a(h), 1.0)),
                               Cinv_mass=_extended(base.Cinv_mass, system.deformable_block(1.0, 0.0)), Cinv_sub=sub,
                               ns=system.exact_block())


def _liquid_solver(system: System, h, scheme: Scheme, tol, max_iter, substeps, reuse, adaptive) -> Solver:
    """The solver of the vessel and its liquid: the deformable block's inverses, which the liquid forms
    itself (AbstractLiquid.step_inverse: dense, the sparse factors, the box-grid solve, the face-normal
    Schur blocks)."""
    nf = system.nf
    if nf == 0 or system.liquid.nonlinear:      # a nonlinear liquid's few unknowns: linearised exactly
        z = jnp.zeros((0, 0))
        return Solver(z, z, jnp.asarray(h, dtype=float), scheme, tol, max_iter, substeps, z if substeps else None,
                      reuse=reuse, adaptive=adaptive, ns=6 + nf)
    blocks = system.liquid.step_inverse(scheme.c_a(h), scheme.c_a(h / substeps) if substeps else None)
    step_inv = damped(blocks.step, system, scheme, h)
    sub_inv = damped(blocks.sub, system, scheme, h / substeps) if substeps else None
    return Solver(step_inv, blocks.mass, jnp.asarray(h, dtype=float), scheme, tol, max_iter, substeps, sub_inv,
                  noise=_noise(system, blocks.stiffness_rows), reuse=reuse, adaptive=adaptive)


def _noise(system: System, rowsum):
    """The round-off floor of the scaled residual: eps times the largest row of |K| per unit scale."""
    scale = jax.lax.stop_gradient(system.scales()[6:])
    if isinstance(rowsum, jax.core.Tracer) or isinstance(scale, jax.core.Tracer):
        return jnp.finfo(jnp.float64).eps * jnp.max(jnp.asarray(rowsum).reshape(-1) / scale)
    return np.finfo(np.float64).eps * np.max(np.asarray(rowsum).reshape(-1) / np.asarray(scale))


def damped(base, system: System, scheme: Scheme, hh):
    """The step block's inverse with every term's constant velocity tangent c_v dR/d(d_dot) added
    (c_v = d v_{n+1} / d Delta = gamma / (beta h)): AbstractTerm.update_inverse, the modal
    damping's low-rank update (liquid/modal_damping.py); `base` itself from a term without one."""
    c_v = scheme.c_v(hh)
    for term in system.all_terms():
        base = term.update_inverse(base, c_v)
    return base


class BlockInverse(eqx.Module):
    """The constant-block inverse with the owners' deformable unknowns: the liquid's (a dense
    matrix, or the sparse factors of sparse.py) and theirs, diagonal (the structures' modal block)
    or a small dense block (the bodies' tank liquid)."""
    liquid: Any           # (nf, nf)
    modal: jax.Array      # (m,) a diagonal's inverse, or (m, m)

    @property
    def shape(self):
        n = self.liquid.shape[0] + self.modal.shape[0]
        return (n, n)

    def __matmul__(self, x):
        nf = self.liquid.shape[0]
        if self.modal.ndim == 2:
            bottom = self.modal @ x[nf:]
        else:
            bottom = self.modal[:, None] * x[nf:] if x.ndim == 2 else self.modal * x[nf:]
        return jnp.concatenate([self.liquid @ x[:nf], bottom])


def _extended(inv, block):
    """The inverse with the owners' block appended, a diagonal (m,) or a block (m, m) (itself where
    they have none: a size, static). Like the liquid's, it only preconditions: formed from
    `stop_gradient` values."""
    if block.shape[0] == 0:
        return inv
    if block.ndim == 2:
        return BlockInverse(inv, jnp.linalg.inv(jax.lax.stop_gradient(block)))
    return BlockInverse(inv, 1.0 / block)


def empty_pre(system: System):
    """A carried preconditioner of the right shapes, marked not valid (formed at the first step)."""
    L = system.layout()
    ns = system.exact_block()
    nz = L.n - ns
    data = (jnp.zeros((ns, ns)),) if nz == 0 else (jnp.zeros((ns, ns)), jnp.zeros((ns, nz)), jnp.zeros((nz, ns)))
    return data, jnp.zeros(())
