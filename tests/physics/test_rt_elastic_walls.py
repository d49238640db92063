"""Runs of the face-normal liquid ("rt") in elastic walls (liquid/face/term.py with walls,
liquid/face/build.py): the particles carry the coupled mass, a still tank stays still, the
trapezoidal rule keeps the energy, very stiff walls give the rigid tank, and the vessel moves as
with the stabilized element in the same walls."""
import functools
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.liquid.face.element import build_face_liquid
from jaxslosh.liquid.face.walls import build_face_tank_with_walls

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _text(young=2.1e11, duration=1.5, initial="angular_velocity = [0.05, 0.02, 0.0]", element="rt"):
    text = open(os.path.join(ROOT, "scenes", "paper_ship_elastic_tank.toml")).read()
    text = text.replace("mesh = [5, 5, 5]", "mesh = [3, 3, 2]").replace("duration = 20.0", f"duration = {duration!r}")
    text = text.replace('scheme = "hht"\nalpha = 0.01', 'scheme = "newmark"')
    text = text.replace("young = 2.1e11", f"young = {young!r}")
    text = text.replace("angular_velocity = [0.1, 0.05, 0.0]", initial)
    return text.replace("[tanks.fluid]", f'[tanks.fluid]\nelement = "{element}"')


@functools.lru_cache(maxsize=None)
def _run(text):
    return js.simulate(js.load_scene(text))


@eqx.filter_jit
def points_products(liquid, F, d):
    """One program (eager, each operation would compile on its own): the points' mass
    sum_g m_g J_g^T J_g from the Jacobian J of `field`, `free_part` of F beside J^T F, and the
    nodal fields of d."""
    J = jax.jacfwd(liquid.field)(jnp.zeros(liquid.nf))                              # (G, 3, nf)
    return (jnp.einsum("gin,g,gim->nm", J, liquid.m, J), liquid.free_part(F), jnp.einsum("gin,gi->n", J, F),
            liquid.nodal_fields(d))


def test_the_points_carry_the_coupled_mass():
    """The liquid's Gauss points and the walls' (each moving with its element's field) give, as
    sum_g m_g J_g^T J_g, the Newton block's mass, which is T^T M T plus the walls' consistent mass
    (liquid/face/walls.py), to round-off; `free_part` is the transpose of `field`."""
    scene = js.load_scene(_text())
    liquid = build(scene).system.liquid
    nf = liquid.nf
    F = jax.random.normal(jax.random.PRNGKey(0), (liquid.r.shape[0], 3), dtype=jnp.float64)
    d = jax.random.normal(jax.random.PRNGKey(1), (nf,), dtype=jnp.float64)
    Mp, FJ, JF, U = (np.asarray(x) for x in points_products(liquid, F, d))
    t = scene.tanks[0]
    tm = t.geometry.mesh(t.fill_depth, t.mesh)
    tw = build_face_tank_with_walls(t, build_face_liquid(tm.nodes, tm.elements, tm.depth, 1000.0, 1500.0, 9.81))
    scale = np.abs(tw.mass).max()
    assert np.abs(Mp - np.asarray(liquid.Mff)).max() < 1e-12 * scale
    assert np.abs(tw.mass - np.asarray(liquid.Mff)).max() < 1e-12 * scale
    np.testing.assert_allclose(FJ, JF, rtol=1e-12, atol=1e-12)
    # the walls' nodes follow the liquid's in the nodal fields
    n_liquid = tw.model.n_nodes
    np.testing.assert_allclose(U[n_liquid:].reshape(-1)[tw.wall_dofs], np.asarray(d)[tw.nq:], rtol=1e-14)


def test_still_tank_stays_still_and_a_rolling_one_keeps_its_energy():
    """At rest the hydrostatic start (liquid and walls in equilibrium together) keeps every
    displacement below 1e-9 m; rolling, the trapezoidal rule (no damping) keeps the energy within
    1e-6 over 150 steps (measured 1e-7)."""
    rest = _run(_text(initial=""))
    assert rest.status == "ok"
    D = np.asarray(rest.tanks["tank"].displacement)
    assert np.abs(D - D[0]).max() < 1e-9
    r = _run(_text())
    assert r.status == "ok"
    E = np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)
    print("energy drift", np.abs(E / E[0] - 1).max())
    assert np.abs(E / E[0] - 1).max() < 1e-6


def test_rolls_as_with_the_stabilized_element():
    """The same scene with the stabilized element in the same walls: the roll and pitch within 1 % of
    their peaks over 1.5 s (measured 0.5 %; the free surface near a wall differs between the elements
    on so coarse a mesh as it does with rigid walls, docs/guide/flexible-structures.md)."""
    a, b = _run(_text()), _run(_text(element="stabilized"))
    for k in (0, 1):
        x, y = np.asarray(a.vessel.roll_pitch_yaw)[:, k], np.asarray(b.vessel.roll_pitch_yaw)[:, k]
        print("axis", k, np.abs(x - y).max() / np.abs(y).max())
        assert np.abs(x - y).max() < 0.01 * np.abs(y).max()


def test_very_stiff_walls_move_like_the_rigid_tank():
    """Forced pitch (0.02 rad at 2 rad/s, faded in over 1 s): with walls of E = 2.1e14 Pa the free
    surface at probe B follows the rigid "rt" tank's within 1e-4 of its range over 1.5 s."""
    forced = '[vessel.forced]\ndof = "pitch"\namplitude = 0.02\nfrequency = 2.0\nramp = 1.0\n'
    text = _text(2.1e14, initial="").replace("[[tanks]]", forced + "\n[[tanks]]")
    stiff = _run(text)
    start = text.index("[tanks.walls]")
    rigid = _run(text[:start] + text[text.index("[tanks.fluid]"):])
    a = np.asarray(stiff.probes["B"].displacement)[:, 2]
    b = np.asarray(rigid.probes["B"].displacement)[:, 2]
    rng = np.ptp(b)
    print("B range", rng, "max difference", np.abs(a - b).max())
    assert rng > 1e-3
    assert np.abs(a - b).max() < 1e-4 * rng


def test_modes_of_the_liquid_in_its_walls():
    """`js.sloshing_modes` (`jaxslosh modes`) of an "rt" tank in 5 cm steel walls: the liquid and
    its walls together, circulation modes left out and counted; the sloshing modes within 0.5 % of
    the same liquid's in rigid walls (the walls soften them: never above)."""
    from jaxslosh.liquid.face.element import face_modes
    scene = js.load_scene(_text())
    md = js.sloshing_modes(scene, n=8)
    t = scene.tanks[0]
    tm = t.geometry.mesh(t.fill_depth, t.mesh)
    rigid = face_modes(build_face_liquid(tm.nodes, tm.elements, tm.depth, 1000.0, 1500.0, 9.81), 8)
    assert md.kind == ("sloshing",) * 8 and md.circulation == rigid.circulation > 0
    assert np.all(md.omega <= rigid.omega * (1 + 1e-9)) and np.all(md.omega > 0.995 * rigid.omega)
