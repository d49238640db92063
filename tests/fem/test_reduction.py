"""Modal reduction of the liquid ([tanks.reduction]): the reduced model is the Galerkin projection of
the full one (same residual, same energies at d = V eta), keeps its natural frequencies, and a
reduced run approaches the full run as the number of modes grows."""
import functools
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.physics.kinematics import quat_exp
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.physics.terms import Config
from jaxslosh.liquid.modes import liquid_modes

ROOT = Path(__file__).resolve().parents[2]
PAPER = (ROOT / "scenes" / "paper_ship_tank.toml").read_text()


def reduced_text(modes, static=True, text=PAPER):
    return text.replace("[tanks.fluid]", f"[tanks.reduction]\nmodes = {modes}\n"
                                         f"static_correction = {'true' if static else 'false'}\n\n[tanks.fluid]")


@functools.lru_cache(maxsize=None)
def full_run(duration):
    return js.simulate(js.load_scene(PAPER), duration=duration)


@eqx.filter_jit
def _rows_and_energies(system, c, V0, om, d_dot, acc):
    """The residual, kinetic and potential energy in one program per system (eager, each operation
    would compile on its own)."""
    return (system.residual(c, V0, om, d_dot, acc), system.kinetic_energy(c, jnp.concatenate([V0, om, d_dot])),
            system.potential_energy(c))


def test_reduced_rows_and_energies_are_the_full_models_at_d_equal_V_eta():
    full = build(js.load_scene(PAPER))
    red = build(js.load_scene(reduced_text(12)))
    L = red.system.liquid
    V = np.asarray(L.U).reshape(L.nf, -1)[:, np.asarray(full.system.liquid.free)].T      # (nf, m)
    rng = np.random.default_rng(3)
    m = L.nf
    c_r = Config(jnp.asarray(rng.standard_normal(3)), quat_exp(jnp.asarray(0.4 * rng.standard_normal(3))),
                 jnp.asarray(0.02 * rng.standard_normal(m)))
    c_f = Config(c_r.X0, c_r.q, V @ c_r.d)
    V0, om = jnp.asarray(rng.standard_normal(3)), jnp.asarray(0.3 * rng.standard_normal(3))
    eta_dot = jnp.asarray(0.05 * rng.standard_normal(m))
    acc = jnp.asarray(rng.standard_normal(6 + m))
    r_r, T_r, V_r = _rows_and_energies(red.system, c_r, V0, om, eta_dot, acc)
    r_f, T_f, V_f = _rows_and_energies(full.system, c_f, V0, om, V @ eta_dot, jnp.concatenate([acc[:6], V @ acc[6:]]))
    np.testing.assert_allclose(r_r[:6], r_f[:6], rtol=1e-12, atol=1e-9 * float(jnp.abs(r_f[:6]).max()))
    np.testing.assert_allclose(r_r[6:], V.T @ r_f[6:], rtol=1e-10, atol=1e-10 * float(jnp.abs(r_r[6:]).max()))
    np.testing.assert_allclose(T_r, T_f, rtol=1e-12)
    np.testing.assert_allclose(V_r, V_f, rtol=1e-12)
    # the static correction makes the reduced hydrostatic start the full one
    np.testing.assert_allclose(V @ red.c0.d, full.c0.d, atol=1e-9 * float(jnp.abs(full.c0.d).max()))
    np.testing.assert_allclose(red.system.total_mass(), full.system.total_mass(), rtol=1e-13)


def test_reduced_frequencies_are_the_full_models():
    from jaxslosh.liquid.modal.reduction import tank_basis
    t = js.load_scene(PAPER).tanks[0]
    model = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed, 9.81)
    full = liquid_modes(model, 24)
    for n in (1, 8, 20):
        basis = tank_basis(model, t.origin, n)
        assert basis.n_modes >= n and basis.n_modes <= n + 1      # a degenerate pair is not split
        L = build(js.load_scene(reduced_text(n))).system.liquid
        lam = scipy.linalg.eigh(np.asarray(L.Kr), np.asarray(L.Mr), eigvals_only=True)
        omega = np.sqrt(lam)
        np.testing.assert_allclose(omega[:basis.n_modes], full.omega[:basis.n_modes], rtol=1e-8)
        # the static-correction Ritz vectors are orthogonal to the retained modes: by Courant-Fischer
        # their frequencies lie at or above the next natural one
        assert omega[basis.n_modes] >= full.omega[basis.n_modes] * (1 - 1e-9)
    assert tank_basis(model, t.origin, 1).n_modes == 2             # (1,0) and (0,1) of the square tank


def test_sparse_and_dense_liquid_give_the_same_ritz_basis():
    """Large meshes reduce from the sparse matrices (shift-invert Lanczos and a sparse LU for the
    static correction; a dense generalized eigh of the 15,666 unknowns of 20 x 20 x 12 crashed
    OpenBLAS): same frequencies and the same subspace as the dense path, on a mesh both can hold."""
    from jaxslosh.liquid.modal.reduction import tank_basis
    t = js.load_scene(PAPER).tanks[0]
    args = (t.size, t.fill_depth, (4, 4, 3), t.fluid.density, t.fluid.sound_speed, 9.81)
    dense = tank_basis(build_liquid(*args), t.origin, 8)
    sparse = tank_basis(build_liquid(*args, sparse=True), t.origin, 8)
    assert sparse.n_modes == dense.n_modes
    # measured: the natural frequencies agree to 4e-10, the static correction's Ritz values to 1e-8
    np.testing.assert_allclose(sparse.omega[:sparse.n_modes], dense.omega[:dense.n_modes], rtol=1e-8)
    np.testing.assert_allclose(sparse.omega, dense.omega, rtol=1e-6)
    # the two bases span the same space: projecting one on the other loses little (measured 4.8e-6
    # of the largest entry)
    Vd, Vs = dense.V, sparse.V
    P = np.linalg.lstsq(Vd, Vs, rcond=None)[0]
    assert np.abs(Vd @ P - Vs).max() < 2e-5 * np.abs(Vs).max()


def test_reduced_run_approaches_the_full_run_as_modes_grow():
    T = 4.0
    full = full_run(T)
    B_f = np.asarray(full.probes["B"].displacement[:, 2])
    roll_f = np.asarray(full.vessel.roll_pitch_yaw[:, 0])
    errs = []
    for n in (2, 20):
        r = js.simulate(js.load_scene(reduced_text(n)), duration=T)
        assert r.status == "ok"
        B = np.asarray(r.probes["B"].displacement[:, 2])
        roll = np.asarray(r.vessel.roll_pitch_yaw[:, 0])
        errs.append((np.abs(B - B_f).max() / np.abs(B_f).max(), np.abs(roll - roll_f).max() / np.abs(roll_f).max()))
    (b2, r2), (b20, r20) = errs
    # measured over 10 s: probe B 3.9 % (2 modes), 1.0 % (8), 0.16 % (20), 0.09 % (40) of its peak;
    # roll 9e-5, 2e-5, 9e-6, 7e-6
    assert b2 > 3 * b20 and b20 < 5e-3 and b2 < 0.1
    assert r20 < 5e-5 and r2 < 5e-4
    # kinetic energy of the whole system with 20 modes: measured 0.31 % of its peak
    assert np.abs(np.asarray(r.energy.kinetic) - np.asarray(full.energy.kinetic)).max() < 1e-2 * float(
        np.abs(np.asarray(full.energy.kinetic)).max())


def test_gradient_through_a_reduced_run_agrees_with_finite_differences():
    """jax.grad (reverse mode) of a 1 s reduced run against a central difference. The differences
    take their values from the same compiled program as the gradient (jax.value_and_grad), which
    spares a second compilation of the time loop (the forward-only run is tested above)."""
    scene = js.load_scene(reduced_text(4))

    def loss(gm):
        r = js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm}, duration=1.0)
        return jnp.sum(r.vessel.roll_pitch_yaw[:, 0] ** 2) + jnp.sum(r.probes["B"].displacement[:, 2] ** 2)

    value_and_grad = jax.jit(jax.value_and_grad(loss))
    g = float(value_and_grad(1.67)[1])
    eps = 1e-4
    fd = (float(value_and_grad(1.67 + eps)[0]) - float(value_and_grad(1.67 - eps)[0])) / (2 * eps)
    assert g == pytest.approx(fd, rel=1e-5)


def test_reduction_keys_are_checked():
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.reduction\.modes"):
        js.load_scene(reduced_text(0))
    bad = reduced_text(4).replace("static_correction = true", "static_correction = 3")
    with pytest.raises(js.SceneError, match="static_correction"):
        js.load_scene(bad)
