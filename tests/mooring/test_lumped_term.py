"""A lumped-mass line as a term of the vessel's residual (jaxslosh/mooring/lumped_term.py) on the
rigid ship of scenes/vessel_only.toml: the start in the catenary's static shape, the line's states
advanced with the vessel's configuration at both ends of each step (replayed independently), the
force on the vessel in its equations of motion, and the lines restoring a surge with drag."""
import os

import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.mooring import lumped as lm
from jaxslosh.mooring.lumped_term import LumpedLineTerm, line_states, lumped_line_term, with_lines
from jaxslosh.physics.kinematics import rotation_matrix
from lumped_reference import OC3, oc3_catenary

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "vessel_only.toml")
DT = 0.1


def moored_stepper(surge_velocity=0.5):
    scene = js.scene_with(js.load_scene(SCENE), {"vessel.initial.angular_velocity": [0.0, 0.0, 0.0],
                                                 "vessel.initial.velocity": [surge_velocity, 0.0, 0.0],
                                                 "simulation.dt": DT})
    st = js.Stepper(scene)
    c = OC3
    terms = [lumped_line_term(st.built.c0, DT, name=f"line{i}", fairlead=[s * 5.2, 0.0, -70.0],
                              anchor=[s * 853.87, 0.0, -320.0], length=c["length"], weight=c["weight"],
                              ea=c["ea"], depth=c["depth"], mass=c["mass"])
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
