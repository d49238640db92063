"""From a validated scene to the static model: `System`, probes and the initial state.

Only what the scene has is built (docs/design.md: Python branches on static model data): a vessel
without tanks has no liquid block, a scene without `[vessel.hydrostatics]` no buoyancy.
Numbers named in `params` (dotted TOML paths, scene/keys.py) replace the scene's values and may be
JAX tracers, which is what makes `jax.grad` through `simulate(scene, params=...)` work.
"""
from __future__ import annotations

import dataclasses
from typing import NamedTuple, Optional

import jax.numpy as jnp
import numpy as np

from ..mooring.lumped_term import build_lumped_lines, group_lines
from ..mooring.term import build_mooring
from ..liquid.modal_damping import ModalDamping
from ..physics.bodies import bodies_term
from ..physics.kinematics import quat_from_rpy, rotation_matrix
from ..liquid.base import RotationPenalty, SpinStiffening
from ..physics.structures import Structures
from ..physics.system import System
from ..physics.terms import Config
from ..physics.vessel import (HarmonicMotion, RecordedMotion, RigidBody, SpinUpMotion,
                              Weight, record_coefficients)
from ..staging import one_blas_thread, staged
from ..scene.keys import resolve_params
from ..scene.types import DOFS, Scene
from .about import damping_about, flex_about, liquid_about, record_about, stiffening_about, weight_about
from .bodies import build_bodies, gravity_turns, hull_part, inertia_matrix, initial_values
from .damping import build_damping
from .hull import restoring, weight_term
from .liquid import LiquidBlock, build_liquid_block, outline_liquid_block, rigid_part
from .probes import Probes, build_probes
from .seakeeping import build_seakeeping, outline_seakeeping
from .structures import build_structures


class Built(NamedTuple):
    system: System
    c0: Config
    v0: jnp.ndarray
    probes: Probes
    tanks: tuple
    alg0: jnp.ndarray                    # algebraic unknowns at t = 0: interface frame positions, zero multipliers
    structures: tuple = ()               # host-side StructureBlock per structure (result fields)
    surfaces: tuple = ()                 # per tank, the stacked indices of its free-surface nodes (validity)
    body_tanks: tuple = ()               # assemble/bodies.BodyTanks per body that carries tanks (host-side)


#: the build's jax.numpy steps, each one compiled program (staging.staged), wrapped once per process
_quat_from_rpy = staged(quat_from_rpy)


def _owners_start(system: System, c0: Config, v0):
    return system.start(c0, v0)


_start = staged(_owners_start)


class _Model(NamedTuple):
    """The static model of a scene and what the build's initial state and probes need of it."""
    system: System
    block: LiquidBlock
    blocks: tuple             # StructureBlock per structure in its own frame
    body_tanks: tuple = ()    # assemble/bodies.BodyTanks


def build(scene: Scene, params: Optional[dict] = None) -> Built:
    with one_blas_thread():          # host algebra of small matrices (staging.one_blas_thread)
        return _build(scene, params)


def _build(scene: Scene, params: Optional[dict]) -> Built:
    params = resolve_params(scene, params)
    P = params.get
    ves = scene.vessel
    system, block, blocks, body_tanks = _model(scene, params)
    liquid, q0 = system.liquid, system.q_ref
    ini = initial_values(P, "vessel", ves.initial)      # a body's the same way (assemble/bodies.py)
    nf = system.nf
    d_init = jnp.zeros(nf)
    if nf:
        d_init = _hydrostatic_start(system, q0)
    c0 = Config(ini["position"], q0, d_init)
    v0 = jnp.concatenate([ini["velocity"], ini["angular_velocity"], jnp.zeros(nf)])
    for motion in system.prescribing():     # a prescribed motion sets the rigid state at t = 0
        c0, v0 = motion.start(c0, v0)
    # the terms that own unknowns (the structures) start them; nothing to compile without
    c0, v0, alg0 = _start(system, c0, v0) if system.owners() else (c0, v0, jnp.zeros(0))
    probes = build_probes(scene, block.tanks, liquid, blocks, block.vstructs, body_tanks, bodies_term(system))
    probes = probes._replace(modal=block.probe_modal(probes.weights))    # a modal liquid: probes from its coordinates
    return Built(system, c0, v0, probes, block.result_tanks(), alg0, blocks, block.surfaces(), body_tanks)


def outline(scene: Scene) -> System:
    """The scene's model as `build` assembles it, its terms and their descriptions (`describe`), but
    none of the arrays that cost time or memory: no mesh assembled, no basis, modes or radiation fit
    computed, nothing compiled, no initial state (the arrays are None). What `jaxslosh check` lists
    (assemble/check.py); tests/cli/test_check_effects.py holds it to the built model's terms."""
    return _model(scene, {}, outline=True).system


def _model(scene: Scene, params: dict, outline: bool = False) -> _Model:
    """The System of `build` (or of `outline`: the same terms, from the same branches, without their
    arrays), each term with its description (assemble/about.py)."""
    P = params.get
    env, ves, eff = scene.environment, scene.vessel, scene.effects
    g = jnp.asarray(P("environment.gravity", env.gravity), dtype=float)
    # the one rule of every floating body's restoring (assemble/hull.py): its hull's pressure (the
    # weight below), its linear springs, or none
    held = restoring(scene, ves, params, g, "vessel")
    terms = list(held.terms)
    # every liquid model's block from the one dispatch (liquid/forms.py block_form)
    block = outline_liquid_block(scene, g, include_liquid=eff.liquid) if outline else \
        build_liquid_block(scene, params, g, include_liquid=eff.liquid)
    has_liquid = not block.liquid.empty
    liquid = block.liquid.with_effects(eff.coriolis, eff.centrifugal, liquid_about(scene, eff.liquid))
    # a prescribed motion is a term that holds the vessel's rows (System.hold); a free vessel has none
    motion = None if ves.forced is None else _prescribed(ves.forced, P)
    q0 = None
    if not outline:
        q0 = _quat_from_rpy(initial_values(P, "vessel", ves.initial)["roll_pitch_yaw"])
        if motion is not None:     # the prescribed attitude at t = 0 (upright unless a phase or a record tilts it)
            q0 = _quat_from_rpy(motion.coordinates(jnp.zeros(()))[3:])
    if scene.waves is not None or ves.hydrodynamics is not None:
        terms += outline_seakeeping(scene) if outline else build_seakeeping(scene, params)
    own = [s for s in scene.structures if s.frame == "own"]
    structures, blocks = None, ()
    if own:
        structures, blocks = (Structures(bodies=(), interfaces=()), ()) if outline else build_structures(scene)
        structures = dataclasses.replace(structures, about=flex_about(scene))
    mass, inertia = jnp.asarray(P("vessel.mass", ves.mass), dtype=float), inertia_matrix(P("vessel.inertia", ves.inertia))
    hull_S = None
    carried = block.carried + tuple(rigid_part(b.model.mass, b.model.nodes + np.asarray(scene.structure(b.name).origin))
                                    for b in blocks)
    if carried:       # the ship's mass and inertia include these parts: the hull is the rest (docs/reference/scene.md)
        mass, inertia, hull_S = hull_part(mass, inertia, carried)
    body = RigidBody(mass=mass, inertia=inertia, S=hull_S)
    balanced = not held.weighs
    if not balanced:           # nothing holds the vessel up, or the hull's pressure does: its weight, liquid included
        weight = weight_about(scene, bool(held.terms))
        if outline:
            terms.append(Weight(mass=None, S=None, gravity=g, about=weight))
        else:
            terms.append(weight_term(mass, hull_S, liquid, g, weight))     # a body's too (assemble/hull.py)
    if any(m.model == "catenary" for m in scene.mooring):   # quasi-static catenary lines (jaxslosh/mooring/term.py)
        terms.append(build_mooring(scene, balanced, outline, params))
    # dynamic lumped-mass lines (mooring/lumped_term.py)
    terms.extend(group_lines(build_lumped_lines(scene, balanced, q0, params), len(scene.bodies)))
    bodies, body_tanks = build_bodies(scene, params, g, outline)   # [[bodies]] and [[connections]] (physics/bodies.py)
    if bodies is not None:
        terms.append(bodies)
    if block.penalty is not None:
        terms.append(RotationPenalty(Kdt=block.penalty[0], Ktt=block.penalty[1], q_ref=q0))
    if block.Kg is not None:
        terms.append(SpinStiffening(None if outline else block.Kg, about=stiffening_about(scene, "vessel"),
                                    offset=block.Kg_offset))
    if structures is not None:
        terms.append(structures)
    damping = None
    if outline:
        damping = ModalDamping(B=None, c=None) if any(t.damping is not None for t in scene.tanks) and has_liquid \
            and eff.liquid else None
    elif eff.liquid:
        damping, _ = build_damping(scene, params, block)
    if damping is not None:
        damping = dataclasses.replace(damping, about=damping_about(scene))
    if motion is not None:     # listed (and summed, with no share) first, after the hull's inertia
        terms.insert(0, motion)
    system = System(body=body, terms=tuple(terms), liquid=liquid, gravity=g, q_ref=q0,
                    gravity_turning=gravity_turns(scene, has_liquid), balanced=balanced,
                    tail=() if damping is None else (damping,))
    return _Model(system, block, blocks, body_tanks)


def _prescribed(f, P):
    """The motion of a `[vessel.forced]` table: one dof's profile, or a record's spline; the harmonic
    form's amplitude, frequency and phase from `params` where it names them (tracers too)."""
    if f.profile == "record":
        knots, coef = record_coefficients(f.times, f.columns, DOFS)
        return RecordedMotion(knots=jnp.asarray(knots), coef=jnp.asarray(coef), about=record_about(f))
    if f.profile == "spin-up":
        return SpinUpMotion(dof=DOFS.index(f.dof), rate=float(f.rate), duration=float(f.duration))
    value = lambda key: jnp.asarray(P(f"vessel.forced.{key}", getattr(f, key)), dtype=float)  # noqa: E731
    return HarmonicMotion(dof=DOFS.index(f.dof), amplitude=value("amplitude"), frequency=value("frequency"),
                          ramp=float(f.ramp), phase=value("phase"))


def _hydrostatic_start(system: System, q0):
    """Discrete hydrostatic equilibrium K d0 = F_g under the initial gravity direction (docs/theory.md
    item 6), so that the stiff acoustic modes are not excited by the start."""
    if not system.liquid.staged_start:        # the sparse nodal block's host solves
        return system.liquid.static_start(system.gravity_body(rotation_matrix(q0)))
    return _dense_static_start(system, q0)


@staged
def _dense_static_start(system: System, q0):
    return system.liquid.static_start(system.gravity_body(rotation_matrix(q0)))
