"""The fast twin of a body's tank's run against the same tank on the lone vessel: the body's rows
and its liquid's at one state away from rest against the lone vessel's residual there."""
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.physics.bodies import bodies_term
from jaxslosh.physics.kinematics import quat_from_rpy
from jaxslosh.physics.terms import Config


def _evaluate(floating, vessel, x, v, a, d, d_dot, d_acc):
    q = quat_from_rpy(jnp.asarray([0.05, -0.08, 0.3]))
    rigid, rows_d = floating.rows(floating.kin(floating.rest + x, q, v, a, vessel.gravity, 0.0, d, d_dot, d_acc))
    ref = vessel.residual(Config(x, q, d), v[:3], v[3:], d_dot, jnp.concatenate([a, d_acc]))
    return jnp.concatenate([rigid, rows_d]), ref


def rows_and_residual(on_body: str, alone: str, seed: int, sizes=(0.05, 0.1, 0.2), traced_build=True):
    """(the body's six rows and its liquid's, the lone vessel's residual) of the scene texts `on_body`
    (the tank on the first body) and `alone` (the body as the vessel), at a tilted, moving state with
    the liquid's unknowns displaced, moving and accelerating by `sizes`. `traced_build=False` for
    models that are built from concrete values only (elastic walls): built eagerly, evaluated in one
    compiled program."""
    scenes = js.load_scene(on_body), js.load_scene(alone)
    rng = np.random.default_rng(seed)
    x, v, a = rng.normal(size=3) * 0.1, rng.normal(size=6) * 0.1, rng.normal(size=6) * 0.1
    if not traced_build:
        floating = bodies_term(build(scenes[0]).system).bodies[0]
        vessel = build(scenes[1]).system
        assert floating.nf == vessel.nf
        d, d_dot, d_acc = (jnp.asarray(rng.normal(size=floating.nf) * s) for s in sizes)
        ours, ref = eqx.filter_jit(_evaluate)(floating, vessel, *map(jnp.asarray, (x, v, a)), d, d_dot, d_acc)
        return np.asarray(ours), np.asarray(ref)

    # built and evaluated in one compiled program: built eagerly, the two models cost hundreds of
    # one-operation programs (the same numbers, to round-off)
    @jax.jit
    def rows(x, v, a):
        floating = bodies_term(build(scenes[0]).system).bodies[0]
        vessel = build(scenes[1]).system
        assert floating.nf == vessel.nf
        # drawn here, where the number of the liquid's unknowns is known (the same draws as outside)
        d, d_dot, d_acc = (jnp.asarray(rng.normal(size=floating.nf) * s) for s in sizes)
        return _evaluate(floating, vessel, x, v, a, d, d_dot, d_acc)

    ours, ref = rows(jnp.asarray(x), jnp.asarray(v), jnp.asarray(a))
    return np.asarray(ours), np.asarray(ref)
