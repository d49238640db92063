"""The fast twin of a body's tank's run against the same tank on the lone vessel: the body's rows
and its liquid's at one state away from rest against the lone vessel's residual there."""
import jax.numpy as jnp
import numpy as np

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.physics.bodies import bodies_term
from jaxslosh.physics.kinematics import quat_from_rpy
from jaxslosh.physics.terms import Config


def rows_and_residual(on_body: str, alone: str, seed: int, sizes=(0.05, 0.1, 0.2)):
    """(the body's six rows and its liquid's, the lone vessel's residual) of the scene texts `on_body`
    (the tank on the first body) and `alone` (the body as the vessel), at a tilted, moving state with
    the liquid's unknowns displaced, moving and accelerating by `sizes`."""
    floating = bodies_term(build(js.load_scene(on_body)).system).bodies[0]
    vessel = build(js.load_scene(alone)).system
    assert floating.nf == vessel.nf
    rng = np.random.default_rng(seed)
    x, q = jnp.asarray(rng.normal(size=3) * 0.1), quat_from_rpy(jnp.asarray([0.05, -0.08, 0.3]))
    v, a = jnp.asarray(rng.normal(size=6) * 0.1), jnp.asarray(rng.normal(size=6) * 0.1)
    d, d_dot, d_acc = (jnp.asarray(rng.normal(size=floating.nf) * s) for s in sizes)
    rigid, rows_d = floating.rows(floating.kin(floating.rest + x, q, v, a, vessel.gravity, 0.0, d, d_dot, d_acc))
    ref = vessel.residual(Config(x, q, d), v[:3], v[3:], d_dot, jnp.concatenate([a, d_acc]))
    return np.concatenate([np.asarray(rigid), np.asarray(rows_d)]), np.asarray(ref)
