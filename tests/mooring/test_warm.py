"""The catenary lines' warm start (mooring/catenary.solve_lines with a guess, the term's states):
the same solution and derivatives as the cold solve, from near and far guesses, on every branch."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.mooring.catenary import lines_inverse, solve_lines
from jaxslosh.mooring.term import mooring_term
from jaxslosh.physics.kinematics import rotation_matrix

# XF, ZF, L, w, EA, CB, hA: touchdown with friction, suspended (lifted off), buoyant, raised
# anchor (U-shaped), slack (piled on the seabed), near taut
LINES = np.array([[395.0, 99.0, 420.0, 600.0, 3e8, 0.5, 0.0],
                  [400.0, 200.0, 500.0, 800.0, 7.51e12, 0.0, 0.0],
                  [37.97, 20.49, 100.0, -881.05, 7.51e8, 0.0, 0.0],
                  [89.9, 59.2, 130.0, 881.05, 7.51e8, 0.0, 20.0],
                  [50.0, 60.0, 300.0, 700.0, 3e8, 0.0, 0.0],
                  [246.22, 263.56, 360.64, 3.087, 7e8, 0.0, 0.0]])


def _cols(a):
    return [jnp.asarray(a[:, i]) for i in range(7)]


def _close(a, b, rel):
    """|a - b| within rel of each column's largest |b| (H and V have their own scales)."""
    a, b = np.asarray(a), np.asarray(b)
    assert np.all(np.abs(a - b) <= rel * np.abs(b).max(axis=0)), np.abs(a - b) / np.abs(b).max(axis=0)


@pytest.mark.slow      # six branches from many guesses: minutes of compiling; test_term_states_are_the_solution_at_the_step_end is the fast check
def test_warm_equals_cold_from_near_and_far_guesses():
    cold = np.asarray(solve_lines(*_cols(LINES)))
    for dx in (1e-4, 1e-2, 0.5, 5.0, -3.0):
        moved = LINES.copy()
        moved[:, 0] += dx
        # the guess: the solution at spans dx away (a step's motion, a large one, a wrong branch)
        guess = solve_lines(*_cols(moved))
        warm = np.asarray(solve_lines(*_cols(LINES), guess=guess))
        _close(warm, cold, 1e-10)
        # chord steps with the Jacobian kept from the guess's own spans
        inverse = lines_inverse(*_cols(moved), guess)
        _close(solve_lines(*_cols(LINES), guess=guess, inverse=inverse), cold, 1e-10)
    # a guess from nowhere near (another line's solution): the cold solve takes over
    warm = np.asarray(solve_lines(*_cols(LINES), guess=cold[::-1]))
    _close(warm, cold, 1e-10)


@pytest.mark.slow      # four derivatives of six branches: minutes of compiling; the catenary gradients test checks the same tangent
def test_warm_derivatives_equal_cold():
    cols = _cols(LINES)
    guess = solve_lines(*_cols(LINES + np.array([0.3, 0.1, 0, 0, 0, 0, 0])))
    for i in (0, 1, 2, 3):          # XF, ZF, L, w
        f = lambda v, g: solve_lines(*cols[:i], v, *cols[i + 1:], guess=g)  # noqa: E731
        Jc = jax.jacfwd(f)(cols[i], None)
        Jw = jax.jacfwd(f)(cols[i], guess)
        np.testing.assert_allclose(Jw, Jc, rtol=1e-8, atol=1e-8 * float(jnp.abs(Jc).max()))
        gw = jax.grad(lambda v: jnp.sum(f(v, guess) ** 2))(cols[i])
        gc = jax.grad(lambda v: jnp.sum(f(v, None) ** 2))(cols[i])
        np.testing.assert_allclose(gw, gc, rtol=1e-8, atol=1e-8 * float(jnp.abs(gc).max()))


def test_term_states_are_the_solution_at_the_step_end():
    scene = js.load_scene("scenes/oc3_hywind.toml")
    st = js.Stepper(scene)
    c = st.advance(st.init(), 4)
    term = mooring_term(st.built.system)
    i = st.built.system.all_terms().index(term)
    z = np.asarray(c.s.z[i]).reshape(-1, 8)[:, :2]
    cold = np.asarray(term.solve(c.s.c.X0, rotation_matrix(c.s.c.q)))
    np.testing.assert_allclose(z, cold, rtol=1e-10)
