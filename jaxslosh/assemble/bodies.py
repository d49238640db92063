"""The `[[bodies]]` and `[[connections]]` of a scene as the term physics/bodies.py defines
(docs/guide/bodies-and-connections.md). A body's rigid terms come from the functions that make the
vessel's (`rigid_terms`): its inertia, its restoring by the vessel's rule (assemble/hull.py
`restoring`: linear springs, or on its hull the pressure there and its weight, or none with
`[effects] buoyancy` off) and its viscous damping."""
from __future__ import annotations

import dataclasses
import re
from typing import NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np

from ..liquid.base import RotationPenalty
from ..liquid.block import LiquidBlock
from ..physics.about import About
from ..physics.bodies import BAND, Bodies, Floating, Link, body_rest, end_index
from ..physics.kinematics import quat_from_rpy
from ..physics.seakeeping import LinearDamping, WaveExcitation
from ..physics.vessel import RigidBody
from ..scene.bodies import coupled_file
from ..scene.keys import toml_mapping
from ..scene.types import SceneError
from .about import damping_about, tank_line
from .bodyhydro import box_waves, time_terms
from .damping import build_damping
from .hull import body_restoring, restoring_words
from .liquid import build_liquid_block
from .seakeeping import make_excitation


def inertia_matrix(value):
    """(3, 3) inertia of a floating body's `inertia` key (the vessel's or a body's): its principal
    moments (3,) on the diagonal, or the matrix itself."""
    a = jnp.asarray(value, dtype=float)
    return jnp.diag(a) if a.ndim == 1 else a


def gravity_turns(scene, carries_liquid: bool) -> bool:
    """Whether a floating body's gravity turns with it (the vessel's and a body's alike:
    physics/floating.py gravity_attitude): `[effects] gravity_turning`, a load on the liquid it
    carries; without liquid it has nothing to load, and turns."""
    return scene.effects.gravity_turning or not carries_liquid


def initial_values(P, key: str, initial) -> dict:
    """A floating body's initial state (`<key>.initial`: the vessel's or a body's), each value traced
    where `P` (the params' get) names it: position, velocity, angular_velocity, roll_pitch_yaw."""
    return {k: jnp.asarray(P(f"{key}.initial.{k}", getattr(initial, k)), dtype=float)
            for k in ("position", "velocity", "angular_velocity", "roll_pitch_yaw")}


def rigid_terms(mass, inertia, restoring: tuple, viscous=None, S=None) -> tuple:
    """A floating body's rigid terms, as the vessel has them: inertia with its gyroscopic terms
    (RigidBody), its `restoring` terms (assemble/hull.py body_restoring: the vessel's rule) and
    linear viscous damping (6 x 6) where given; `S` the hull's first moment where parts carry their
    own mass (`hull_part`)."""
    terms = [RigidBody(mass=jnp.asarray(mass, dtype=float), inertia=inertia_matrix(inertia), S=S), *restoring]
    if viscous is not None:
        terms.append(LinearDamping(jnp.asarray(viscous, dtype=float)))
    return tuple(terms)


def hull_part(mass, inertia, parts, key: str = "vessel", what: str = "ship", carriers: str = "structures and elastic walls"):
    """The hull's own mass, inertia about the origin and first moment: the floating body's (`key`:
    the vessel's or a body's table; mass, inertia about its COG at the origin) less the parts that
    carry their own (structures, elastic walls: liquid/block.py rigid_part). SceneError naming its
    mass or inertia where they are not more than those parts'."""
    m = sum(p[0] for p in parts)
    S = sum(p[1] for p in parts)
    I = sum(p[2] for p in parts)
    if not isinstance(mass, jax.core.Tracer):
        if float(mass) <= m:
            raise SceneError(f"{key}.mass", f"{float(mass):.6g} kg is the whole {what} without its liquid, {carriers} "
                                            f"included, but those alone weigh {m:.6g} kg")
    if not isinstance(inertia, jax.core.Tracer):
        if np.min(np.linalg.eigvalsh(np.asarray(inertia) - I)) <= 0:
            raise SceneError(f"{key}.inertia", f"is the whole {what}'s about its COG, {carriers} "
                                               "included, but it is smaller than theirs alone (the hull's would not "
                                               f"be positive definite; theirs: {np.round(np.diag(I), 1).tolist()} kg m^2)")
    return mass - m, inertia - jnp.asarray(I), -jnp.asarray(S)


class BodyTanks(NamedTuple):
    """The host-side blocks of the tanks one body carries (the tanks a result keeps the fields of:
    liquid/block.py LiquidBlock.result_tanks), its index among the bodies, the offset of its liquid
    unknowns among the bodies' tanks' (physics/bodies.py Bodies.tank_slices) and the block its
    liquid's builder made (`block`: what the probes and the validity watch ask, as of the vessel's)."""
    body: int
    name: str
    offset: int
    tanks: tuple
    block: Optional[LiquidBlock] = None


def body_liquid(scene, body, q0, g, params=None):
    """(liquid, its terms, its block, the rigid parts of its elastic walls) of the tanks a body
    carries: the vessel's builder (assemble/liquid.py) on the scene with the body's tanks as its
    tanks and the probes in them as its probes, so that a tank is the same model on any body
    (whichever model its form takes: liquid/forms.py block_form), its elastic walls included, and
    takes the same traced `params` (`tanks.<name>.fill_depth`, ...: canonical keys, by the tank's
    name); the rotation penalty at the body's initial attitude, as the vessel's at its own. (None,
    (), None, ()) without tanks or with the liquid switched off."""
    eff = scene.effects
    if not body.tanks or not eff.liquid:
        return None, (), None, ()
    # dense: the body's liquid block is inverted whole as the Bodies term's deformable block
    names = {t.name for t in body.tanks}
    own = dataclasses.replace(scene, tanks=body.tanks, structures=(),
                              probes=tuple(p for p in scene.probes if p.tank in names),
                              simulation=dataclasses.replace(scene.simulation, linear_solver="dense"))
    params = params or {}
    try:
        block = build_liquid_block(own, params, g)
    except SceneError as e:          # the builder names the body's tanks by their index among its own
        raise SceneError(_scene_tank_key(scene, body, e.key), str(e)[len(e.key) + 2:]) from None
    # the [effects] switches through the liquid's own interface, as the vessel's (assemble/system.py); its
    # lines are the Bodies term's (assemble/bodies.py _about), so the liquid keeps its own
    liquid = block.liquid.with_effects(eff.coriolis, eff.centrifugal, block.liquid.about)
    terms = () if block.penalty is None else (RotationPenalty(Kdt=block.penalty[0], Ktt=block.penalty[1], q_ref=q0),)
    damping, _ = build_damping(own, params, block)        # [tanks.damping]: the vessel's modal damping
    return liquid, terms + (() if damping is None else (damping,)), block, block.carried


def _scene_tank_key(scene, body, key: str) -> str:
    """`tanks[i]...` of the body's i-th tank as the scene file numbers its [[tanks]] (the name form
    `tanks.<name>...` for a scene built without a file); other keys unchanged."""
    m = re.match(r"tanks\[(\d+)\](.*)", key or "")
    if m is None or int(m.group(1)) >= len(body.tanks):
        return key
    name = body.tanks[int(m.group(1))].name
    names = [t.get("name") for t in toml_mapping(scene.text).get("tanks", [])] if scene.text else []
    return f"tanks[{names.index(name)}]{m.group(2)}" if name in names else f"tanks.{name}{m.group(2)}"


def build_bodies(scene, params: dict, g, outline: bool = False) -> tuple[Optional[Bodies], tuple]:
    """The term of the scene's bodies and connections, or None without either; and BodyTanks per
    body that carries tanks (none in `outline`: no liquid is built, its lines are the term's)."""
    if not scene.bodies and not scene.connections:
        return None, ()
    P = params.get
    cog = scene.vessel.cog_height
    Ainf, memory, X = time_terms(scene, params)
    waves = scene.waves
    floating, hosts, offset = [], [], 0
    for s, b in enumerate(scene.bodies):
        rest = body_rest(b, cog)
        key = f"bodies.{b.name}"
        # its initial state as the vessel's (assemble/system.py), offsets from its rest pose, traced where params name them
        ini = initial_values(P, key, b.initial)
        q0 = quat_from_rpy(ini["roll_pitch_yaw"] + jnp.array([0.0, 0.0, b.heading]))
        tank, tank_terms, block, carried = (None, (), None, ()) if outline else body_liquid(scene, b, q0, g, params)
        if block is not None and block.result_tanks():
            hosts.append(BodyTanks(s, b.name, offset, block.result_tanks(), block))
            offset += tank.nf
        mass, inertia, S = jnp.asarray(P(f"{key}.mass", b.mass), dtype=float), P(f"{key}.inertia", b.inertia), None
        if carried:       # its elastic walls carry their own mass in its liquid: the hull is the rest, as the vessel's
            mass, inertia, S = hull_part(mass, inertia_matrix(inertia), carried, f"bodies[{s}]", "body",
                                         "its tanks' elastic walls")
        floating.append(Floating(
            terms=rigid_terms(mass, inertia, body_restoring(scene, b, params, g, tank, mass, S),
                              b.viscous_damping, S) + (
                () if X is None or not np.abs(X[s]).max() > 0 else
                (WaveExcitation(make_excitation(waves, X[s], P(waves.height_key,
                                                              waves.height))),)),
            rest=jnp.asarray(rest), x0=jnp.asarray(rest) + ini["position"],
            q0=q0, v0=jnp.concatenate([ini["velocity"], ini["angular_velocity"]]),
            tank=tank, tank_terms=tank_terms, gravity_turning=gravity_turns(scene, tank is not None)))
    index = end_index(b.name for b in scene.bodies)
    links = []
    for c in scene.connections:
        key = f"connections.{c.name}"
        if c.stiffness is not None:       # a straight curve, extended with its slope
            xs = jnp.array([0.0, 1.0])
            fs = jnp.stack([jnp.zeros(()), jnp.asarray(P(f"{key}.stiffness", c.stiffness), dtype=float)])
        else:
            xs, fs = jnp.asarray([p[0] for p in c.curve]), jnp.asarray([p[1] for p in c.curve])
        links.append(Link(ends=tuple(index[e] for e in c.ends), kind=c.kind, pa=jnp.asarray(c.points[0]),
                          pb=jnp.asarray(c.points[1]), length=jnp.asarray(P(f"{key}.length", c.length), dtype=float),
                          xs=xs, fs=fs, damping=jnp.asarray(P(f"{key}.damping", c.damping), dtype=float)))
    radiating = bool(np.abs(Ainf).max() > 0) or memory is not None
    return Bodies(bodies=tuple(floating), links=tuple(links), gravity=g,
                  added_mass=jnp.asarray(Ainf) if radiating else None, memory=memory, names=tuple(b.name for b in scene.bodies),
                  link_names=tuple(c.name for c in scene.connections), about=_about(scene)), tuple(hosts)


def _about(scene) -> About:
    lines = []
    coupled = (coupled_file(scene.vessel, scene.bodies) or ((), ()))[1]     # the bodies of a multibody file
    for b in scene.bodies:
        damp = ", viscous damping" if b.viscous_damping is not None else ""
        hd = b.hydrodynamics
        tabled = hd is not None and (hd.file or hd.added_mass is not None or hd.excitation_amplitude is not None)
        if tabled:
            damp += (f"; radiation and wave excitation from {hd.file}" if hd.file else
                     "; radiation and wave excitation from its tables") + " (at its place in the waves)"
        box = box_waves(b)
        if scene.waves is not None and (box == "only" or (box == "unless tabled" and not tabled and b.name not in coupled)):
            damp += "; the waves' Froude-Krylov force on its box hull (at its place in the waves)"
        statics = restoring_words(scene, b)
        lines.append(("floating body", f"{b.name!r}: 6 unknowns of its own floating frame at "
                                       f"({b.position[0]:g}, {b.position[1]:g}) m from the vessel, heading "
                                       f"{b.heading:g} rad, mass {b.mass:g} kg; rigid-body inertia and "
                                       f"{statics}{damp}"))
        damped = dict(damping_about(dataclasses.replace(scene, tanks=b.tanks)).lines)
        for t in b.tanks if scene.effects.liquid else ():      # the vessel's tank lines, on this body's frame
            what, text = tank_line(t)
            eff = scene.effects
            loads = ", ".join(["its element's rotation penalty"] + ["Coriolis"] * eff.coriolis
                              + ["centrifugal"] * eff.centrifugal)
            text, loads = t.form.carried_words(t, text, loads)     # the liquid's own loads, in its words
            loads += ", gravity " + ("turning with the body" if gravity_turns(scene, True) else
                                     "frozen at its initial attitude ([effects] gravity_turning off)")
            lines.append((what, f"{text}; carried by the body {b.name!r} (in its frame from its COG, its liquid's "
                                f"unknowns its own, its loads on the body's six rows: {loads})"))
            if f"liquid damping in tank {t.name!r}" in damped:
                lines.append((f"liquid damping in tank {t.name!r}", damped[f"liquid damping in tank {t.name!r}"]))
    shown = {"vessel": scene.vessel.name}       # the ends as the scene names them
    for c in scene.connections:
        law = f"stiffness {c.stiffness:g} N/m" if c.stiffness is not None else f"a {len(c.curve)}-point force curve"
        band = f", contact smoothed over {1e3 * BAND:g} mm" if c.kind != "spring" else ""
        damp = f", damping {c.damping:g} N s/m" if c.damping else ""
        lines.append(("connection", f"{c.name!r}: {c.kind} {shown.get(c.ends[0], c.ends[0])} - "
                                    f"{shown.get(c.ends[1], c.ends[1])}, length {c.length:g} m, "
                                    f"{law}{damp}{band}"))
    return About(*lines)
