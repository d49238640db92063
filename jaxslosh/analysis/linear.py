"""The scene's equations of motion linearised about its rest state, by JAX, from the same residual
the time loop solves (physics/system.py): the frequency domain's one model (rao.py, coupled.py).

About the rest state c0 (the hydrostatic start of the liquid, the structures in static equilibrium
under their weight, zero velocities, t = 0), for small increments x of the unknowns

    M x'' + C x' + K x = f(t),
    M = dR/d acc,   C = dR/d v,   K = dR/d x,

taken by `jax.jacfwd`: x holds the vessel's increments (dX0 inertial, Theta body, on the group as
the step takes them), the deformable block's (liquid, elastic walls, vessel-frame structures; full
or modal), and with structures in their own frames their rigid and modal increments and the
interface frames and multipliers (algebraic: their rows and columns of M and C are zero). At rest
the Coriolis and centrifugal terms are quadratic in the velocities, so C holds only the linear
damping the scene has (viscous hull damping; liquid damping where a scene gives it).

The residual carries the hull's radiation as A_inf plus the memory force; the memory's states are
not unknowns here, so `added_mass_infinite` says what M holds on the vessel's block, and the
frequency domain replaces it by the tables' A(w) and adds B(w) (rao.py).
"""
from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..assemble.effects import structure_unknowns
from ..assemble.system import Built
from ..mooring.lumped_keys import quasi_static_lines
from ..physics.bodies import bodies_term
from ..physics.seakeeping import AddedMass
from ..run.loop import probe_positions
from ..run.simulate import is_traced, prepare
from ..scene.types import DOFS, Initial, Scene, SceneError
from ..physics.unknowns import Layout
from ..solve.integrator import static_equilibrium

#: above this many unknowns the dense matrices (3 n^2 doubles, and a complex factor per frequency)
#: outgrow a workstation: the liquid should be reduced to its modes ([tanks.reduction])
MAX_UNKNOWNS = 6000


class Linearisation(NamedTuple):
    """M, C, K (n, n) over the unknowns x (Newton order: vessel, structures' rigid, interface
    frames and multipliers, liquid, structures' modal); `dynamic` (n,) marks the unknowns with
    inertia; `probes` (P, 3, n) the probes' inertial displacement per unit x; `labels` (n,) a
    name per unknown ("surge" ... "yaw", "liquid", "structure NAME", "interface");
    `added_mass_infinite` (6, 6) the radiation added mass M holds on the vessel's rows (zero
    without); `built` the model (the rest scene's)."""
    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    dynamic: np.ndarray
    probes: np.ndarray
    probe_names: tuple
    labels: tuple
    added_mass_infinite: np.ndarray
    built: Built

    @property
    def n(self) -> int:
        return int(self.M.shape[0])


def rest_scene(scene: Scene) -> Scene:
    """The scene at rest: no initial offset, attitude or velocity (the hydrostatics' equilibrium).
    A scene the frequency domain cannot take raises SceneError naming the key."""
    ves = scene.vessel
    if ves.forced is not None:
        raise SceneError("vessel.forced", "the frequency domain needs a free vessel (its motion is prescribed)")
    if ves.hydrostatics is None:
        raise SceneError("vessel.hydrostatics", "the frequency domain needs a floating vessel at rest; without "
                                                "hydrostatics it falls")
    bodies = tuple(dataclasses.replace(b, initial=Initial()) for b in scene.bodies)
    # lumped mooring lines as their catenary: linearised with their nodes held, their last segment's
    # axial stiffness would stand for the line's (docs/guide/moorings-lumped.md)
    return quasi_static_lines(dataclasses.replace(scene, vessel=dataclasses.replace(ves, initial=Initial()), bodies=bodies))


def _labels(b: Built, L: Layout, scene: Scene) -> tuple:
    names = list(DOFS)
    for s in b.structures:
        names += [f"structure {s.name}"] * 6
    names += [f"{body.name} {dof}" for body in scene.bodies for dof in DOFS]   # [[bodies]]: their own frames
    # the structures in the vessel's frame: their nodal dofs the deformable block's last, in order
    held = [f"structure {s.name}" for s in scene.structures if s.frame == "vessel"
            for _ in range(structure_unknowns(s))] if L.nf else []
    names += ["interface"] * L.n_alg + ["liquid"] * (L.nf - len(held)) + held
    for s in b.structures:
        names += [f"structure {s.name}"] * s.model.Phi.shape[1]
    term = bodies_term(b.system)         # the bodies' tanks' liquid: the owner's deformable unknowns
    for name, body in zip(term.names, term.bodies) if term is not None else ():
        names += [f"{name} liquid"] * body.nf
    return tuple(names)


def linearise(scene: Scene, params=None) -> Linearisation:
    """M, C, K of the scene about its rest state (see the module's docstring). With traced
    `params` (under jax.grad or jax.jit) M, C, K and the probes' rows are JAX values that carry
    the gradient; otherwise NumPy arrays."""
    setup = prepare(rest_scene(scene), params)
    b, solver = setup.built, setup.solver
    sysm = b.system
    L = sysm.layout()
    n = L.n
    if n > MAX_UNKNOWNS:
        raise SceneError("tanks.reduction", f"the linearised model has {n} unknowns (dense matrices above "
                                            f"{MAX_UNKNOWNS}): reduce the liquid to its modes with [tanks.reduction]")
    c0, _, alg0, info = static_equilibrium(sysm, solver, b.c0, b.v0, b.alg0)
    # (no owner that settles, as the bodies: nothing solved, nothing to check, and under tracing no
    # concrete flag to read)
    if any(o.settles() for o in sysm.owners()) and not bool(info.ok):
        raise SceneError("structures", "no static equilibrium of the structures under their weight was found")
    # the interface rows as forces per metre of gap (any scale solves the same equations; the
    # structure's mass keeps them near the other rows' size for the factorisations)
    gscale, _ = sysm.alg_scales(1.0, lambda itf: 1.0)

    def rows(x, v, acc):
        dyn, alg = L.from_x(x)
        c = sysm.advance(c0, dyn)
        alg = alg0 + alg
        main = L.to_x(sysm.step_rows(c, v, acc, jnp.zeros(())), jnp.zeros(L.n_alg))
        return main + sysm.constraint_rows(c, alg, sysm.constraint(c, alg), gscale)

    def position(x):
        dyn, _ = L.from_x(x)
        return probe_positions(b, sysm.advance(c0, dyn))

    zx, zd = jnp.zeros(n), jnp.zeros(L.n_dyn)

    @jax.jit
    def matrices():
        K = jax.jacfwd(lambda x: rows(x, zd, zd))(zx)
        C = jax.jacfwd(lambda v: rows(zx, v, zd))(zd)
        M = jax.jacfwd(lambda a: rows(zx, zd, a))(zd)
        P = jax.jacfwd(position)(zx) if b.probes.names else jnp.zeros((0, 3, n))
        return M, C, K, P

    # velocities and accelerations are the dynamic unknowns: their columns go where those sit in x
    with jax.ensure_compile_time_eval():
        where = np.asarray(L.to_x(jnp.arange(L.n_dyn), -jnp.ones(L.n_alg, dtype=int)))
    dynamic = where >= 0
    if is_traced(params or {}):
        # traced params (jax.grad of a function of the RAOs): the matrices stay JAX values
        M_d, C_d, K, P = matrices()
        cols = np.flatnonzero(dynamic)
        M = jnp.zeros((n, n), dtype=M_d.dtype).at[:, cols].set(M_d[:, where[cols]])
        C = jnp.zeros((n, n), dtype=C_d.dtype).at[:, cols].set(C_d[:, where[cols]])
    else:
        M_d, C_d, K, P = (np.asarray(m) for m in matrices())
        M, C = np.zeros((n, n)), np.zeros((n, n))
        M[:, dynamic] = M_d[:, where[dynamic]]
        C[:, dynamic] = C_d[:, where[dynamic]]
    Ainf = np.zeros((6, 6))
    for term in sysm.terms:
        if isinstance(term, AddedMass):
            Ainf = np.asarray(term.matrix)
    return Linearisation(M, C, K, dynamic, P, b.probes.names, _labels(b, L, scene), Ainf, b)
