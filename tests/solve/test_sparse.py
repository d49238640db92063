"""Large-mesh path (sparse.py, boxsolve.py): the fast-diagonalization inverse, the element-by-element
and the stencil products are the sparse matrices' own, and a run through them is the dense run."""
import os

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

import jaxslosh as js
from jaxslosh.liquid.nodal.boxsolve import box_inverse, elements, stencil
from jaxslosh.liquid.nodal.model import build_liquid, surface_bending_scale

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
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


@pytest.mark.parametrize("mesh, element", [((4, 4, 3), "stabilized"), ((3, 5, 2), "paper")])
def test_element_by_element_products_equal_the_sparse_products(mesh, element):
    """The stiffness and mass applied element by element (one element matrix per layer, the top
    faces' terms, the surface bending) are the assembled sparse matrices: measured 3e-16."""
    m, free, M, K = _blocks(mesh, element)
    Ms = sp.csr_matrix(m.mass)
    rng = np.random.default_rng(4)
    for A, k, rows, cols in ((K, 3, free, 1), (Ms, 1, np.arange(Ms.shape[0]), 3)):
        op = elements(A, ((mesh, k, rows, m.layers),), check=np.inf)
        x = rng.standard_normal((A.shape[0], cols))
        y = np.asarray(op @ jnp.asarray(x))
        assert np.linalg.norm(y - A @ x) <= 1e-13 * np.linalg.norm(A @ x)


def test_element_products_are_declined_where_layers_differ():
    """The stabilized element with an odd number of elements along x pairs its top wall elements:
    no element matrix per layer holds that, so the model carries none and the general sparse
    product stays (the pairs are too far apart for a stencil too)."""
    from jaxslosh.liquid.nodal.sparse import host_sparse
    m, free, _, K = _blocks((3, 4, 2), "stabilized")
    assert m.layers is None
    assert elements(K, (((3, 4, 2), 3, free, m.layers),)) is None
    op = host_sparse(K, (((3, 4, 2), 3, free),), (m.layers,))
    assert op.grid is None and op.bcoo is not None


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


def test_sparse_system_has_the_dense_residual_and_inverses():
    """The paper scene with a second tank (the stacked blocks' offsets) built the dense way and the
    box-grid way: the residual at a disturbed state and the step and mass inverses applied to it
    agree to round-off, so the Newton iterations of the two are the same (a whole run of each is left
    to the benchmarks: its compilation would cost the suite a minute)."""
    import jax
    from jaxslosh.liquid.nodal.boxsolve import BoxInverse, Elements
    from jaxslosh.run.loop import core as _core
    from jaxslosh.run.simulate import prepare
    from jaxslosh.scene.keys import with_overrides

    out = {}
    for solver in ("dense", "sparse"):
        setup = prepare(with_overrides(_paper(solver), duration=0.5))
        b, slv = _core(setup.built), setup.solver
        rng = np.random.default_rng(3)
        c = b.c0._replace(d=b.c0.d + 1e-3 * jnp.asarray(rng.standard_normal(b.c0.d.shape)))
        nf = c.d.shape[0]
        dd, acc = (jnp.asarray(rng.standard_normal(k)) for k in (nf, 6 + nf))
        sysm = b.system
        r = jax.jit(lambda c, dd, acc: sysm.residual(c, jnp.array([0.1, 0.0, 0.2]), jnp.array([0.1, 0.05, 0.0]),
                                                     dd, acc, 0.0, None))(c, dd, acc)
        out[solver] = (np.asarray(r), np.asarray(slv.Cinv_step @ r[6:]), np.asarray(slv.Cinv_mass @ r[6:]), b, slv)
    assert isinstance(out["sparse"][3].system.liquid.K.grid, Elements)
    assert isinstance(out["sparse"][3].system.liquid.Ms.grid, Elements)
    assert isinstance(out["sparse"][4].Cinv_step, BoxInverse)
    # the residual to round-off; the inverses to the dense explicit inverse's own error (about
    # cond(C) eps, 3e-10 here; the box solve agrees with SciPy's sparse solve to 1e-9, test above)
    for k, tol in ((0, 1e-10), (1, 1e-8), (2, 1e-8)):
        d, f = out["dense"][k], out["sparse"][k]
        assert np.linalg.norm(f - d) <= tol * np.linalg.norm(d), k
