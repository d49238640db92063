"""Large-mesh path (sparse.py, boxsolve.py): the fast-diagonalization inverse and the stencil
products are the sparse matrices' own, and a run through them is the dense run."""
import os

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

import jaxslosh as js
from jaxslosh.boxsolve import box_inverse, stencil
from jaxslosh.liquid import build_liquid, surface_bending_scale

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
C_A = 1.0 / (0.25 * 1.01 ** 2 * 0.01 ** 2)        # the paper scene's step: HHT alpha 0.01, dt 0.01


def _blocks(mesh, element):
    m = build_liquid((5.0, 5.0, 4.0), 3.0, mesh, 1000.0, 1500.0, 9.81, element=element, sparse=True)
    free = np.flatnonzero(m.free)
    K = m.stiffness.tocsr()[free][:, free]
    M = sp.kron(m.mass, sp.eye(3), format="csr")[free][:, free]
    return m, free, M, 0.5 * (K + K.T)


@pytest.mark.parametrize("mesh, element", [((4, 4, 3), "stabilized"), ((3, 4, 2), "paper"), ((6, 2, 4), "stabilized")])
def test_box_inverse_solves_the_step_and_mass_blocks_to_round_off(mesh, element):
    m, _, M, K = _blocks(mesh, element)
    grids = (tuple(mesh) + (surface_bending_scale(m), element),)
    rng = np.random.default_rng(1)
    for A, bending in ((C_A * M + K, True), (M, False)):
        inv = box_inverse(A, grids, bending)
        assert inv is not None
        r = rng.standard_normal((A.shape[0], 2))
        x, ref = np.asarray(inv @ jnp.asarray(r)), spsolve(A.tocsc(), r)
        assert np.linalg.norm(x - ref) <= 1e-9 * np.linalg.norm(ref)


def test_box_inverse_declines_a_mesh_it_does_not_diagonalize():
    """An odd number of elements along x: the stabilized element pairs its top wall elements there,
    which no cosine series diagonalizes; the build's own check refuses it (the run keeps the LU)."""
    m, _, M, K = _blocks((3, 4, 2), "stabilized")
    assert box_inverse(C_A * M + K, ((3, 4, 2, surface_bending_scale(m), "stabilized"),)) is None


@pytest.mark.parametrize("mesh, element", [((4, 4, 3), "stabilized"), ((3, 5, 2), "paper")])
def test_stencil_products_equal_the_sparse_products(mesh, element):
    m, free, M, K = _blocks(mesh, element)
    Ms = sp.csr_matrix(m.mass)
    rng = np.random.default_rng(2)
    for A, k, rows, cols in ((K, 3, free, 1), (Ms, 1, np.arange(Ms.shape[0]), 3)):
        op = stencil(A, ((mesh, k, rows),))
        x = rng.standard_normal((A.shape[0], cols))
        y = np.asarray(op @ jnp.asarray(x))
        assert np.linalg.norm(y - A @ x) <= 1e-13 * np.linalg.norm(A @ x)


def _paper(solver, second_tank=True):
    text = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    text = text.replace("mesh = [5, 5, 5]", "mesh = [4, 4, 3]").replace("duration = 20.0", "duration = 0.5")
    text = text.replace("[vessel]", f'linear_solver = "{solver}"\n\n[vessel]')
    if second_tank:
        text += """
[[tanks]]
name = "aft"
origin = [-6.0, -1.0, -1.0]
size = [2.0, 2.0, 2.0]
fill_depth = 1.2
mesh = [2, 2, 2]
walls = "rigid"

[tanks.fluid]
density = 1000.0
sound_speed = 1500.0
element = "paper"
"""
    return js.load_scene(text)


def test_sparse_run_is_the_dense_run():
    """The paper scene with a second tank (the stacked blocks' offsets) through the dense inverses
    and products and through the box-grid ones: motion and probe B agree to the Newton tolerance's
    order over 50 steps."""
    dense = js.simulate(_paper("dense"))
    fast = js.simulate(_paper("sparse"))
    assert fast.status == "ok" and dense.status == "ok"
    om_d, om_s = np.asarray(dense.vessel.angular_velocity), np.asarray(fast.vessel.angular_velocity)
    assert np.max(np.abs(om_s - om_d)) <= 1e-9 * np.max(np.abs(om_d))
    pd, ps = np.asarray(dense.probes["B"].displacement), np.asarray(fast.probes["B"].displacement)
    assert np.max(np.abs(ps - pd)) <= 1e-9 * np.max(np.abs(pd))
    assert abs(float(np.mean(fast.solver.iterations)) - float(np.mean(dense.solver.iterations))) < 0.5
