"""A lumped-mass line as a term of the vessel's residual (jaxslosh/mooring/lumped_term.py) on the
rigid ship of scenes/vessel_only.toml: the start in the catenary's static shape, the line's states
advanced with the vessel's configuration at both ends of each step (replayed independently), the
force on the vessel in its equations of motion, and the lines restoring a surge with drag."""
import os
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.mooring import lumped as lm
from jaxslosh.mooring.lumped_term import (LumpedLineTerm, build_lumped_lines, line_states, lumped_line_term,
                                         lumped_observe, read_lumped, with_lines)
from jaxslosh.scene.types import SceneError
from jaxslosh.physics.kinematics import rotation_matrix
from lumped_reference import OC3, oc3_catenary

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "vessel_only.toml")
DT = 0.1


def moored_stepper(surge_velocity=0.5, balanced=False):
    scene = js.scene_with(js.load_scene(SCENE), {"vessel.initial.angular_velocity": [0.0, 0.0, 0.0],
                                                 "vessel.initial.velocity": [surge_velocity, 0.0, 0.0],
                                                 "simulation.dt": DT})
    st = js.Stepper(scene)
    c = OC3
    terms = [lumped_line_term(st.built.c0, DT, name=f"line{i}", fairlead=[s * 5.2, 0.0, -70.0],
                              anchor=[s * 853.87, 0.0, -320.0], length=c["length"], weight=c["weight"],
                              ea=c["ea"], depth=c["depth"], mass=c["mass"], balanced=balanced)
             for i, s in enumerate((-1.0, 1.0))]
    return with_lines(st, terms), terms


@pytest.fixture(scope="module")
def run():
    st, terms = moored_stepper()
    s = st.init()
    states = [s]
    for _ in range(250):
        s = st.step(s)
        states.append(s)
    return st, terms, states


def test_lines_start_in_the_catenary(run):
    st, terms, states = run
    H, V, _ = oc3_catenary()
    for term, sign in zip(terms, (-1.0, 1.0)):
        F = term.force(st.built.c0, jnp.zeros(3), jnp.zeros(3), term.state_init())
        assert float(F[0]) * sign > 0
        assert abs(abs(float(F[0])) / H - 1) < 5e-3 and abs(-float(F[2]) / V - 1) < 5e-3


def test_states_follow_the_vessel_and_force_enters_its_equations(run):
    """Each step's line states are lumped.advance of the previous ones with the fairlead driven by
    the vessel's configurations and velocities at both ends; the vessel's surge equation
    M dV/dt = F_x(lines) holds at t_{n+1} (the scene has no other surge force)."""
    st, terms, states = run
    assert st.status(states[-1]) == "ok"
    M = 4.1e5
    for k in (1, 30, 250):
        a, b = states[k - 1].s, states[k].s
        Fx = 0.0
        for name, (term, z) in line_states(st, states[k]).items():
            z_old = line_states(st, states[k - 1])[name][1]
            A0, A1 = rotation_matrix(a.c.q), rotation_matrix(b.c.q)
            p0 = a.c.X0 + A0 @ term.fairlead
            u0 = a.v[:3] + A0 @ jnp.cross(a.v[3:6], term.fairlead)
            p1 = b.c.X0 + A1 @ term.fairlead
            u1 = b.v[:3] + A1 @ jnp.cross(b.v[3:6], term.fairlead)
            s1 = lm.advance(term.line, term.split(z_old), p0, u0, p1, u1, DT, term.substeps)
            np.testing.assert_allclose(np.asarray(term.split(z).r), np.asarray(s1.r), rtol=0, atol=1e-9)
            Fx = Fx + float(term.force(b.c, b.v[:3], b.v[3:6], z)[0])
        assert M * float(b.acc[0]) == pytest.approx(Fx, rel=1e-6, abs=1e-6 * 7e5)


def test_lines_restore_surge_with_drag(run):
    """Set surging at 0.5 m/s, the vessel comes back through its rest position with a smaller
    excursion on the other side (the lines' drag and internal damping)."""
    st, terms, states = run
    x = np.array([float(s.s.c.X0[0]) for s in states])
    assert x.max() > 1.0
    assert x[-1] < 0.0 and x.min() < 0.0
    assert -x.min() < 0.95 * x.max()
    assert all(isinstance(t, LumpedLineTerm) for t in terms)


def test_balanced_vessel_at_rest_stays_at_rest():
    """Two opposite lines in their static shapes, the buoyancy of the linear hydrostatics carrying
    their pull at rest: the vessel left at rest stays there (no start-up transient of the lines)."""
    st, _ = moored_stepper(0.0, balanced=True)
    s = st.advance(st.init(), 100)
    assert st.status(s) == "ok"
    assert float(jnp.max(jnp.abs(s.s.c.X0))) < 1e-4
    assert float(jnp.max(jnp.abs(s.s.v))) < 1e-4


def test_observe_gives_tensions_and_nodes(run):
    st, terms, states = run
    b = states[-1].s
    lines = line_states(st, states[-1])

    @jax.jit        # one compiled program (eagerly, a hundred one-operation programs)
    def observed(b, zs):
        return (lumped_observe(st.built.system, b.z, b.c, b.v),
                {name: lines[name][0].tension(b.c, b.v[:3], b.v[3:6], z) for name, z in zs.items()})

    d, tension = observed(b, {name: z for name, (_, z) in lines.items()})
    for name, (term, z) in lines.items():
        assert float(d[f"mooring/{name}/fairlead_tension"]) == pytest.approx(float(tension[name]), rel=1e-12)
        nodes = np.asarray(d[f"mooring/{name}/nodes"])
        assert nodes.shape == (21, 3)
        np.testing.assert_allclose(nodes[0], np.asarray(term.line.anchor))
        assert 0 < float(d[f"mooring/{name}/anchor_tension"]) < float(d[f"mooring/{name}/fairlead_tension"])


def test_read_lumped_splits_and_checks_the_table():
    table = {"name": "l1", "model": "lumped", "length": 900.0, "segments": 12, "cd": [1.2, 0.2], "mass": 80.0}
    rest, lumped = read_lumped(table, "mooring[0]")
    assert rest == {"name": "l1", "model": "lumped", "length": 900.0}
    assert dict(lumped) == {"segments": 12, "cd": (1.2, 0.2), "mass": 80.0}
    for key, bad in (("segments", 1), ("diameter", -0.1), ("cd", [1.0]), ("ca", [1.0, -1.0]),
                     ("seabed_damping", -1.0), ("segments", 2.5)):
        with pytest.raises(SceneError) as e:
            read_lumped(dict(table, **{key: bad}), "mooring[0]")
        assert e.value.key == f"mooring[0].{key}"


def test_build_from_the_scene_tables():
    """The lines of a scene (the loader's records: name, fairlead, anchor, ..., model and the lumped
    pairs), with the COG above the still-water level and the balanced buoyancy."""
    c = OC3
    line = SimpleNamespace(name="a", fairlead=(-5.2, 0.0, -60.0), anchor=c["anchor"], length=c["length"],
                           weight=c["weight"], ea=c["ea"], model="lumped",
                           lumped=read_lumped({"mass": c["mass"], "segments": 20}, "mooring[0]")[1])
    cat = SimpleNamespace(name="b", model="catenary")
    scene = SimpleNamespace(mooring=(line, cat), environment=SimpleNamespace(depth=320.0, gravity=9.81,
                                                                             water_density=1025.0),
                            simulation=SimpleNamespace(dt=0.1, energy_projection=False),
                            vessel=SimpleNamespace(cog_height=-10.0, initial=SimpleNamespace(position=(0.0, 0.0, 0.0))))
    (term,) = build_lumped_lines(scene, balanced=True)
    np.testing.assert_allclose(np.asarray(term.line.anchor), [-853.87, 0.0, -310.0])
    assert float(term.line.seabed_z) == -310.0 and term.line.segments == 20
    H, V, _ = oc3_catenary()
    F = term.force(Config0(), jnp.zeros(3), jnp.zeros(3), term.state_init())
    assert abs(-float(F[2]) / V - 1) < 5e-3 and float(term.carried[2]) == pytest.approx(-float(F[2]))
    with pytest.raises(SceneError) as e:
        build_lumped_lines(SimpleNamespace(**dict(vars(scene), simulation=SimpleNamespace(
            dt=0.1, energy_projection=True))), balanced=False)
    assert e.value.key == "simulation.energy_projection"


def Config0():
    from jaxslosh.physics.terms import Config
    return Config(jnp.zeros(3), jnp.array([1.0, 0.0, 0.0, 0.0]), jnp.zeros(0))


@pytest.mark.slow
def test_gradient_through_a_moored_run():
    """d(surge after 3 s)/d(the line's drag coefficients' scale), reverse mode through the vessel's
    steps (the implicit function theorem on each step's Newton solve) and each line's sub-steps,
    against central differences (about 2 min, its reverse-mode compilation; the default suite's
    test_advance_gradient_matches_finite_differences checks the sub-steps' gradient)."""
    import dataclasses

    import equinox as eqx
    import jax

    st, _ = moored_stepper(0.5)
    st = eqx.tree_at(lambda s: s.solver, st, dataclasses.replace(st.solver, implicit=True))
    s0 = st.init()

    def line(s):
        return s.built.system.terms[-1].lines[-1].line     # the last line (the lines are one term)

    def surge(scale):
        b = eqx.tree_at(lambda s: line(s).cd, st, line(st).cd * scale)
        return b.advance(s0, 30).s.c.X0[0]

    g = jax.grad(surge)(1.0)
    e = 1e-4
    fd = (surge(1 + e) - surge(1 - e)) / (2 * e)
    assert float(g) == pytest.approx(float(fd), rel=1e-5)
    assert float(g) < 0      # more drag: less far


def test_quasi_static_lines_turn_lumped_lines_into_catenaries():
    from dataclasses import dataclass

    from jaxslosh.mooring.lumped_keys import quasi_static_lines

    @dataclass(frozen=True)
    class Line:
        name: str
        model: str = "catenary"
        lumped: tuple = ()

    @dataclass(frozen=True)
    class Scene:
        mooring: tuple = ()

    s = Scene((Line("a", "lumped", (("segments", 10),)), Line("b")))
    out = quasi_static_lines(s)
    assert [(m.model, m.lumped) for m in out.mooring] == [("catenary", ()), ("catenary", ())]
    plain = Scene((Line("b"),))
    assert quasi_static_lines(plain) is plain
