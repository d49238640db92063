"""The face-normal liquid at full order without dense matrices on the faces (liquid/face/schur.py,
liquid/face/blocks.py, liquid/face/inverse.py) against the dense blocks (liquid/face/build.py
with sparse=False) on small meshes: the stiffness, the Newton blocks' inverses, the static start and
the absolute-rotation penalty to round-off, a run to the Newton solver's floor, and the operators
under vmap and jax.export."""
import dataclasses
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.liquid.face.build import face_full_liquid
from jaxslosh.assemble.liquid import build_liquid_block
from jaxslosh.liquid.face.schur import face_schur
from jaxslosh.liquid.face.element import build_face_liquid
from jaxslosh.geometry import Baffle, Box, Prismatic
from jaxslosh.scene.liquids import FaceForm
from jaxslosh.liquid.face.inverse import FaceStepInverse, chebyshev_steps, face_solver_blocks


def _tank(origin):
    """What the face-normal block's builder reads of a tank: its place, rigid walls, full order."""
    return SimpleNamespace(origin=origin, wall_spec=None, form=FaceForm())


def _models():
    """A prismatic tank with hopper chamfers, and a box split by a plate through the surface (two
    pools: G has two null vectors)."""
    out = []
    for geo, depth, mesh in ((Prismatic(size=(1.0, 2.0, 1.5), chamfers=((0.5, 0.4), (0.0, 0.0))), 1.0, (2, 6, 4)),
                             (Box(size=(0.6, 1.0, 1.0), baffles=(Baffle("y", 0.5, "bottom", 0.9),)), 0.5, (2, 6, 3))):
        tm = geo.mesh(depth, mesh)
        out.append(build_face_liquid(tm.nodes, tm.elements, tm.depth, 450.0, 1450.0, 9.81))
    return out


def test_the_sparse_blocks_equal_the_dense_ones_to_round_off():
    models = _models()
    assert models[1].pools == 2
    tanks = [_tank((0.3, -1.0, -0.5)), _tank((-1.0, 0.5, -0.2))]
    dense, (Kdt0, Ktt0), _ = face_full_liquid(tanks, models)
    sparse, (Kdt1, Ktt1), _ = face_full_liquid(tanks, models, sparse=True)
    n = dense.nf
    V = np.random.default_rng(0).standard_normal((n, 5))
    K0, M0 = np.asarray(dense.K), np.asarray(dense.Mff)
    rel = lambda a, b: np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(np.asarray(b)).max()  # noqa: E731
    assert rel(sparse.K @ jnp.asarray(V), K0 @ V) < 1e-13
    assert rel(sparse.K @ jnp.asarray(V[:, 0]), K0 @ V[:, 0]) < 1e-13
    assert rel(sparse.K.abs_rowsum, np.abs(K0).sum(axis=1)) < 1e-13
    assert rel(Kdt1, Kdt0) < 1e-11 and rel(Ktt1, Ktt0) < 1e-11
    g = jnp.asarray([0.3, -0.2, -9.81])
    assert rel(sparse.static_start(g), np.linalg.solve(K0, np.asarray(dense.free_part(dense.m[:, None] * g)))) < 1e-8
    c = 4.0 / 0.01 ** 2
    step, mass, sub, _ = face_solver_blocks(sparse, c, 4.0 / 0.005 ** 2)
    assert rel(step @ jnp.asarray(V), np.linalg.solve(c * M0 + K0, V)) < 1e-10
    assert rel(sub @ jnp.asarray(V), np.linalg.solve(4.0 / 0.005 ** 2 * M0 + K0, V)) < 1e-10
    assert rel(mass @ jnp.asarray(V), np.linalg.solve(M0, V)) < 1e-13
    # the dense blocks formed from the products (analysis helpers): the same matrices
    Ms, Ks = sparse.constant_blocks()
    assert rel(Ms, M0) < 1e-14 and rel(Ks, K0) < 1e-13


def test_the_dense_step_block_is_the_operator_and_the_element_gathers_the_points_ones():
    """Below `dense_faces` the step block's inverse is the matrix of the Woodbury-Chebyshev operator
    (both the inverse of c M + K, as the other test has it); the liquid's fields and forces gathered and
    scattered over the elements' slots, and FaceOps.scatter as a gather, equal the points' own
    slots and segment_sum to round-off."""
    models = _models()
    tanks = [_tank((0.3, -1.0, -0.5)), _tank((-1.0, 0.5, -0.2))]
    dense, _, _ = face_full_liquid(tanks, models)
    sparse, _, _ = face_full_liquid(tanks, models, sparse=True)
    c = 4.0 / 0.01 ** 2
    matrix, operator = face_solver_blocks(sparse, c)[0], face_solver_blocks(sparse, c, dense_faces=0)[0]
    assert isinstance(operator, FaceStepInverse) and matrix.shape == (sparse.nf, sparse.nf)
    V = np.random.default_rng(2).standard_normal((sparse.nf, 3))
    exact = np.linalg.solve(c * np.asarray(dense.Mff) + np.asarray(dense.K), V)
    for inv in (matrix, operator):
        assert np.abs(np.asarray(inv @ jnp.asarray(V)) - exact).max() < 1e-10 * np.abs(exact).max()
    assert sparse._by_element() == 8 and dense._by_element() == 0
    d = jnp.asarray(V[:, 0])
    F = jnp.asarray(np.random.default_rng(3).standard_normal((sparse.r.shape[0], 3)))
    u0, u1 = np.asarray(dense.field(d)), np.asarray(sparse.field(d))
    f0, f1 = np.asarray(dense.free_part(F)), np.asarray(sparse.free_part(F))
    assert np.abs(u1 - u0).max() < 1e-14 * np.abs(u0).max() and np.abs(f1 - f0).max() < 1e-14 * np.abs(f0).max()
    ops = sparse.K.ops
    v = jnp.asarray(np.random.default_rng(4).standard_normal(ops.slots.shape + (2,)))
    by_segments = np.asarray(dataclasses.replace(ops, places=None).scatter(v))
    assert np.abs(np.asarray(ops.scatter(v)) - by_segments).max() < 1e-14 * np.abs(by_segments).max()


def test_the_generalized_inverse_is_the_W_weighted_one():
    """G G^+ G = G, and G^+ W^-1 N = 0 for the pools' null vectors N (the closed forms of the Newton
    block's inverse need this one of G's generalized inverses)."""
    s = face_schur(_models()[1])
    assert np.abs(s.G @ s.Gp @ s.G - s.G).max() < 1e-10 * np.abs(s.G).max()
    assert np.abs(s.Gp @ (s.winv[:, None] * s.N)).max() < 1e-10 * np.abs(s.Gp).max() * np.abs(s.winv).max()


def test_chebyshev_steps_reach_the_bound():
    """The iteration count from the bound 2 q^k <= tol: condition 4 (q = 1/3) to 1e-15 takes 33 steps."""
    assert chebyshev_steps(1.0, 4.0, 1e-15) == 33
    assert chebyshev_steps(1.0, 1.0, 1e-15) == 1


def test_the_operators_vmap_and_export():
    models = _models()
    liquid, _, _ = face_full_liquid([_tank((0.0, 0.0, 0.0))], models[:1], sparse=True)
    step, *_ = face_solver_blocks(liquid, 4.0 / 0.01 ** 2)
    X = jnp.asarray(np.random.default_rng(1).standard_normal((3, liquid.nf)))

    def f(x):
        return step @ (liquid.K @ x)
    batched = jax.vmap(f)(X)
    one = np.asarray(f(X[1]))
    assert np.abs(np.asarray(batched[1]) - one).max() < 1e-9 * np.abs(one).max()
    exported = jax.export.export(jax.jit(f))(jax.ShapeDtypeStruct((liquid.nf,), jnp.float64))
    back = jax.export.deserialize(exported.serialize())
    assert np.abs(np.asarray(back.call(X[1])) - one).max() < 1e-9 * np.abs(one).max()


ROLLING = """
title = "rolling ship, rt tank at full order"
[simulation]
duration = 0.2
dt = 0.01
tolerance = 1e-12
linear_solver = "{solver}"
[vessel]
mass = 2.0e4
inertia = [1.0e4, 2.0e4, 2.0e4]
[vessel.hydrostatics]
waterplane_area = 20.0
displaced_volume = 20.0
gm_t = 1.0
gm_l = 5.0
[vessel.initial]
angular_velocity = [0.2, 0.05, 0.0]
[[tanks]]
name = "tank"
shape = "prismatic"
chamfers = [[0.5, 0.4], [0.0, 0.0]]
origin = [-0.5, -1.0, -0.5]
size = [1.0, 2.0, 1.5]
fill_depth = 1.0
mesh = [2, 6, 4]
[tanks.fluid]
element = "rt"
density = 450.0
sound_speed = 1450.0
[[probes]]
name = "wall"
tank = "tank"
point = [0.5, 1.9, 1.0]
"""


def test_a_run_through_the_sparse_blocks_equals_the_dense_run():
    """The same rolling ship through both: the free-surface probe and the roll agree within 1e-10 m
    and rad (the Newton iterations' round-off floor), with the same iterations per step but where a
    step ends at that floor (one more or fewer)."""
    dense, sparse = (js.load_scene(ROLLING.format(solver=s)) for s in ("dense", "sparse"))
    assert build_liquid_block(sparse).liquid.sparse and not build_liquid_block(dense).liquid.sparse
    a, b = js.simulate(dense), js.simulate(sparse)
    pa, pb = np.asarray(a.probes["wall"].displacement), np.asarray(b.probes["wall"].displacement)
    assert np.abs(pa).max() > 1e-3
    assert np.abs(pa - pb).max() < 1e-10
    assert np.abs(np.asarray(a.vessel.roll_pitch_yaw) - np.asarray(b.vessel.roll_pitch_yaw)).max() < 1e-10
    ia, ib = np.asarray(a.solver.iterations), np.asarray(b.solver.iterations)
    assert np.abs(ia - ib).max() <= 1 and np.count_nonzero(ia != ib) <= 2


def test_scaled_sparse_blocks_equal_the_dense_ones():
    """Density, sound speed and gravity other than the model's (liquid/face/stack.py face_scales: the
    mass, the compression and the free surface scale with rho, rho c^2 and rho g): the sparse blocks
    equal the dense blocks at those values, the stiffness, row sums (a bound within the factors'
    spread), the static start and the Newton blocks' inverses; and traced (jit, grad) as well."""
    models = _models()
    tanks = [_tank((0.3, -1.0, -0.5)), _tank((-1.0, 0.5, -0.2))]
    scales = [(1.1, 0.9, 1.2), (0.8, 1.3, 0.95)]
    dense, (Kdt0, Ktt0), _ = face_full_liquid(tanks, models, scales)
    sparse, (Kdt1, Ktt1), _ = face_full_liquid(tanks, models, scales, sparse=True)
    V = np.random.default_rng(0).standard_normal((dense.nf, 5))
    K0, M0 = np.asarray(dense.K), np.asarray(dense.Mff)
    rel = lambda a, b: np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(np.asarray(b)).max()  # noqa: E731
    assert rel(sparse.K @ jnp.asarray(V), K0 @ V) < 1e-13
    exact = np.abs(K0).sum(axis=1)
    assert np.all(np.asarray(sparse.K.abs_rowsum) >= 0.8 * exact) and np.all(np.asarray(sparse.K.abs_rowsum) <= 1.4 * exact)
    assert rel(Kdt1, Kdt0) < 1e-11 and rel(Ktt1, Ktt0) < 1e-11
    g = jnp.asarray([0.3, -0.2, -9.81])
    assert rel(sparse.static_start(g), np.linalg.solve(K0, np.asarray(dense.free_part(dense.m[:, None] * g)))) < 1e-8
    c = 4.0 / 0.01 ** 2
    step, mass, _, _ = face_solver_blocks(sparse, c)
    assert rel(step @ jnp.asarray(V), np.linalg.solve(c * M0 + K0, V)) < 1e-10
    assert rel(mass @ jnp.asarray(V), np.linalg.solve(M0, V)) < 1e-13

    def both(a, sparse):
        liquid, _, _ = face_full_liquid(tanks, models, [(a, 1.3 * a, 0.9), (1.0, a, a)], sparse=sparse)
        start = liquid.static_start(g)
        if sparse:
            x = face_solver_blocks(liquid, c)[0] @ jnp.ones(liquid.nf)
        else:
            x = jnp.linalg.solve(c * liquid.Mff + liquid.K, jnp.ones(liquid.nf))
        return jnp.sum(start ** 2), x
    # each side one program (run eagerly, the dense build and its gradient compiled each of their
    # operations on its own)
    a, b = jax.jit(lambda s: both(s, True))(1.2), jax.jit(lambda s: both(s, False))(1.2)
    assert rel(a[0], b[0]) < 1e-9 and rel(a[1], b[1]) < 1e-10
    grad = jax.jit(jax.grad(lambda s: both(s, True)[0]))(1.2)
    assert abs(grad - jax.jit(jax.grad(lambda s: both(s, False)[0]))(1.2)) < 1e-8 * abs(grad)


@pytest.mark.slow
def test_a_run_with_traced_tank_values_through_the_sparse_blocks():
    """Density, sound speed and gravity from params (traced) on the sparse blocks: the run equals the
    dense one (the free-surface probe and the roll within 1e-12), and the gradient with respect to
    the density agrees with central differences within 1e-5."""
    dense, sparse = (js.load_scene(ROLLING.format(solver=s).replace("duration = 0.2", "duration = 0.05"))
                     for s in ("dense", "sparse"))
    p0 = {"tanks.tank.fluid.density": 500.0, "tanks.tank.fluid.sound_speed": 1300.0, "environment.gravity": 9.5}
    assert build_liquid_block(sparse, p0).liquid.sparse

    def value(scene, p):
        r = js.simulate(scene, params=p)
        return r.probes["wall"].displacement[-1, 2] + r.vessel.roll_pitch_yaw[-1, 0]
    a, b = value(sparse, p0), value(dense, p0)
    assert abs(float(a)) > 1e-3 and abs(float(a - b)) < 1e-12
    key, h = "tanks.tank.fluid.density", 0.5
    grad = float(jax.grad(lambda x: value(sparse, {**p0, key: x}))(p0[key]))
    fd = float(value(sparse, {**p0, key: p0[key] + h}) - value(sparse, {**p0, key: p0[key] - h})) / (2 * h)
    assert abs(grad - fd) < 1e-5 * abs(fd)
