"""Lumped-mass mooring lines on a body of [[bodies]] (docs/guide/moorings-lumped.md,
docs/guide/bodies-and-connections.md): the same hull on the same lumped lines moves the same as the
vessel and as a body beside a far-away free vessel (the roles swapped), its lines' tensions and nodes
the same in the result; its lines start in their static shape, whose pull is the catenary's within
the discretisation's tolerance; `check` lists them under the body."""
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.check import effects_summary
from jaxslosh.assemble.system import build
from jaxslosh.mooring.lumped_term import LumpedLines
from jaxslosh.mooring.term import mooring_term
from jaxslosh.physics.kinematics import rotation_matrix
from test_body_mooring import BODY_AT, HEAD, HULL, OFFSET, SPIN, _at_rest, _body_moored, _lines

LUMPED = 'model = "lumped"\nsegments = {n}\n'
SHORT = HEAD.replace("duration = 1.5", "duration = 0.3")


def _vessel(model: str) -> str:
    return SHORT + "[vessel]\n" + HULL.format(table="vessel", extra="", position=OFFSET, omega=SPIN) + _lines("vessel", model=model)


def _body(model: str) -> str:
    return _body_moored(model).replace("duration = 1.5", "duration = 0.3")


def _lines_of(system):
    return next(t for t in system.terms if isinstance(t, LumpedLines))


@pytest.mark.slow      # two moored runs compiled (37 s on a loaded 2-core machine); the rows' twin below is the fast check
def test_a_body_on_lumped_lines_moves_as_the_same_vessel_on_them():
    """Released from the same offset and rate, the body on three 4-segment lumped lines follows the
    vessel on the same lines to 1e-10 m (the lines' states advanced with the body's pose and rates,
    their force and moment on the body's rows, in its frame); the lines' tensions and nodes in the
    result are the vessel's (the nodes shifted by the body's place); the free vessel stays at rest."""
    model = LUMPED.format(n=4)
    ref = js.simulate(js.load_scene(_vessel(model)))
    r = js.simulate(js.load_scene(_body(model)))
    b = r.bodies["buoy"]
    X, q = np.asarray(ref.vessel.position), np.asarray(ref.vessel.quaternion)
    assert np.ptp(X[:, 2]) > 1e-2 and np.ptp(X[:, 0]) > 1e-2       # it moves
    np.testing.assert_allclose(np.asarray(b.position), X, rtol=0, atol=1e-10)
    np.testing.assert_allclose(np.asarray(b.quaternion), q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(r.vessel.position), 0.0, atol=1e-12)
    shift = np.array([BODY_AT[0], BODY_AT[1], 0.0])
    for name in ("l1", "l2", "l3"):
        want, got = ref.mooring[name], r.mooring[name]
        assert np.asarray(want.fairlead_tension).min() > 1e5 and np.ptp(np.asarray(want.fairlead_tension)) > 1e3
        for what in ("fairlead_tension", "anchor_tension"):
            np.testing.assert_allclose(np.asarray(getattr(got, what)), np.asarray(getattr(want, what)), rtol=1e-10)
        assert np.asarray(got.nodes).shape == (7, 5, 3)
        np.testing.assert_allclose(np.asarray(got.nodes) - shift, np.asarray(want.nodes), rtol=0, atol=1e-9)


def test_the_rows_and_states_of_a_turned_bodys_lumped_line_are_the_vessels():
    """The fast twin of the run: a body turned by a heading h, at a pose and rates that put its
    fairleads where the vessel's are and move them alike, takes the vessel's lines' force, their
    moment turned into its own axes, and advances the lines' nodes as the vessel's do."""
    h = 0.7
    c, s = np.cos(h), np.sin(h)
    Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    model = LUMPED.format(n=4)
    ves = build(js.load_scene(_at_rest(_vessel(model)))).system
    text = _at_rest(_body(model)).replace(f"position = {list(BODY_AT)}", f"position = {list(BODY_AT)}\nheading = {h!r}")
    for i in range(3):          # each fairlead as the turned body's frame sees it
        a = 2 * math.pi * i / 3 + 0.3
        r_b = Rz.T @ np.array([6 * math.cos(a), 6 * math.sin(a), -5.0])
        turned = text.replace(f"fairlead = [{6 * math.cos(a)!r}, {6 * math.sin(a)!r}, -5.0]", f"fairlead = {[float(x) for x in r_b]}")
        assert turned != text
        text = turned
    bod = build(js.load_scene(text)).system
    tv, tb = _lines_of(ves), _lines_of(bod)
    assert tb.ends == (0, 0, 0) and tb.n_bodies == 1 and not tv.on_bodies
    qv = jnp.array([0.99, 0.05, -0.03, 0.1]) / np.linalg.norm([0.99, 0.05, -0.03, 0.1])
    qturn = jnp.array([np.cos(h / 2), 0.0, 0.0, np.sin(h / 2)])
    qb = jnp.array([qv[0] * qturn[0] - qv[3] * qturn[3], qv[1] * qturn[0] + qv[2] * qturn[3],
                    qv[2] * qturn[0] - qv[1] * qturn[3], qv[0] * qturn[3] + qv[3] * qturn[0]])   # qv * qturn
    dx, V, W = jnp.array([2.0, -1.5, 0.3]), jnp.array([0.3, -0.2, 0.1]), jnp.array([0.01, -0.02, 0.03])
    shift = jnp.array([BODY_AT[0], BODY_AT[1], 0.0])

    @jax.jit
    def both(dx, qv, qb):
        cv = js_config(dx, qv)
        cb = js_config(jnp.zeros(3), jnp.array([1.0, 0, 0, 0]), shift + dx, qb)
        zv, zb = tv.state_init(), tb.state_init()
        # the body's rates in its own axes: the vessel's omega turned by -h
        vv, vb = jnp.concatenate([V, W]), jnp.concatenate([jnp.zeros(6), V, Rz.T @ W])
        kv = ves.kin(cv, V, W, jnp.zeros(0))._replace(z=zv)
        kb = bod.kin(cb, jnp.zeros(3), jnp.zeros(3), jnp.zeros(0), vs=vb[6:])._replace(z=zb)
        zv1 = tv.state_advance_config(zv, cv, vv, cv._replace(X0=cv.X0 + 0.01 * V), vv, 0.05)
        zb1 = tb.state_advance_config(zb, cb, vb, cb._replace(Xs=cb.Xs + 0.01 * V), vb, 0.05)
        return tv.rows(kv), tb.rows(kb), zv1, zb1, rotation_matrix(qb)

    rv, rb, zv1, zb1, Ab = both(dx, qv, qb)
    np.testing.assert_allclose(np.asarray(Ab), np.asarray(rotation_matrix(qv)) @ Rz, atol=1e-14)
    ref = np.asarray(rv.rigid)
    assert np.linalg.norm(ref[:3]) > 1e5 and np.linalg.norm(ref[3:]) > 1e5        # the lines pull and turn
    np.testing.assert_allclose(np.asarray(rb.rigid), 0.0, atol=0)                 # nothing on the free vessel
    got = np.asarray(rb.frames)
    np.testing.assert_allclose(got[:3], ref[:3], rtol=1e-10, atol=1e-6)
    np.testing.assert_allclose(got[3:], Rz.T @ ref[3:], rtol=1e-10, atol=1e-5)
    n = (zv1.shape[1] - 2) // 2          # the nodes' positions, then their velocities (shifted alike)
    pos = lambda z, d: np.asarray(z[:, :n]).reshape(3, -1, 3) - d  # noqa: E731
    np.testing.assert_allclose(pos(zb1, np.asarray(shift)), pos(zv1, 0.0), rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.asarray(zb1[:, n:]), np.asarray(zv1[:, n:]), rtol=1e-9, atol=1e-9)


def js_config(X0, q, Xs=None, qs=None):
    from jaxslosh.physics.terms import Config
    return Config(X0, q, jnp.zeros(0), None if Xs is None else Xs[None], None if qs is None else qs[None])


def test_a_bodys_lumped_lines_start_with_the_catenarys_pull():
    """At the body's initial pose (an offset, a tilt), each 20-segment lumped line's static pull on
    the body is the quasi-static elastic catenary's of the same line (mooring/term.py, the solver
    `jaxslosh mooring` uses) within 0.5 %; with the body's linear springs, the buoyancy carries its
    lumped lines' vertical pull at rest as it carries its catenary lines'."""
    scene = js.load_scene(_body_moored(LUMPED.format(n=20)))
    lumped = _lines_of(build(scene).system)
    cat = mooring_term(build(js.load_scene(_body_moored())).system)
    b = scene.bodies[0]
    X = jnp.array([BODY_AT[0], BODY_AT[1], 0.0]) + jnp.asarray(b.initial.position)
    A = rotation_matrix(js_q(b.initial.roll_pitch_yaw))
    F_cat = np.asarray(cat.state(jnp.broadcast_to(X, (3, 3)), jnp.broadcast_to(A, (3, 3, 3))).force)
    for i, t in enumerate(lumped.lines):
        F = np.asarray(t.force_at((X, A, jnp.zeros(3), jnp.zeros(3)), t.state_init()))
        assert np.linalg.norm(F_cat[i]) > 1e5
        np.testing.assert_allclose(F, F_cat[i], rtol=0, atol=5e-3 * np.linalg.norm(F_cat[i]))
    up = sum(float(t.carried[2]) for t in lumped.lines)
    assert up == pytest.approx(float(cat.carried_bodies[0, 2]), rel=5e-3) and up > 1e5


def js_q(rpy):
    from jaxslosh.physics.kinematics import quat_from_rpy
    return quat_from_rpy(jnp.asarray(rpy, dtype=float))


def test_check_lists_each_line_under_the_body_it_holds():
    """`check`: the vessel's catenary lines under "mooring" as before, the body's lumped lines right
    under the body's own line, indented."""
    text = _body_moored(LUMPED.format(n=4)) + _lines("vessel").replace('name = "l', 'name = "v')
    out = effects_summary(js.load_scene(text)).splitlines()
    body = next(i for i, line in enumerate(out) if line.startswith("  - floating body: 'buoy'"))
    assert [line.split(":")[0] for line in out[body + 1:body + 4]] == ["      - mooring"] * 3
    assert [line.split()[4] for line in out[body + 1:body + 4]] == ["l1:", "l2:", "l3:"]
    vessel = [line for line in out if line.startswith("  - mooring: 3 quasi-static")]
    assert len(vessel) == 1 and "'v1', 'v2', 'v3'" in vessel[0] and "'buoy'" not in vessel[0]
    cat = effects_summary(js.load_scene(_body_moored())).splitlines()
    body = next(i for i, line in enumerate(cat) if line.startswith("  - floating body: 'buoy'"))
    assert cat[body + 1].startswith("      - mooring: 3 quasi-static elastic catenary line(s) 'l1', 'l2', 'l3'")
    assert "its buoyancy carries their vertical pull at rest" in cat[body + 1]
