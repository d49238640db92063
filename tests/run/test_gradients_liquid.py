"""Tank parameters as traced values (issue 5): the liquid model built from tracers, the params keys
that reach it, and jax.grad of a trajectory loss with respect to the fill depth, the liquid's
density and sound speed, gravity and the hull's hydrostatics against central differences."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.scene.keys import TRACEABLE
from jaxslosh.assemble.system import build
from jaxslosh.solve.schemes import make_scheme
from jaxslosh.solve.linear import make_solver
from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.scene.types import SceneError

SIZE = (5.0, 5.0, 4.0)
LIQUID = ("fill_depth", "density", "sound_speed", "gravity")


def _model_arrays(p, mesh, element):
    m = build_liquid(SIZE, p["fill_depth"], mesh, p["density"], p["sound_speed"], p["gravity"], element=element)
    out = {"nodes": m.nodes, "mass": m.mass, "stiffness": m.stiffness}
    if m.rotation_coupling is not None:
        out |= {"coupling": m.rotation_coupling, "theta_theta": m.rotation_stiffness}
    return out


@pytest.mark.parametrize("mesh, element", [((3, 3, 2), "stabilized"), ((2, 3, 3), "paper")])
def test_liquid_model_from_traced_values_and_its_derivatives(mesh, element):
    """Built from tracers (JAX assembly) it equals the NumPy build; its forward derivatives match
    central differences. A slow sound speed (20 m/s) puts the acoustic, gravity and rotation terms
    on one scale, so that an error in any of them shows against the norm of the whole matrix. Odd
    counts (3) bring in the wall pairs of the rotation penalty."""
    base = {"fill_depth": 3.0, "density": 1000.0, "sound_speed": 20.0, "gravity": 9.81}
    concrete = _model_arrays(base, mesh, element)
    p0 = jnp.asarray([base[k] for k in LIQUID])
    # all four traced at once: one forward pass per direction (jacfwd), the values from the traced
    # build; jitted, one program instead of the ~140 small ones of its operations run one by one
    jac, traced = jax.jit(jax.jacfwd(lambda p: (lambda out: (out, out))(_model_arrays(dict(zip(LIQUID, p)), mesh, element)),
                                     has_aux=True))(p0)
    for k, v in concrete.items():
        assert isinstance(v, np.ndarray) and not isinstance(traced[k], np.ndarray)
        assert np.max(np.abs(np.asarray(traced[k]) - v)) <= 1e-13 * np.max(np.abs(v)), k
    for i, key in enumerate(LIQUID):
        fds = []
        for rel in (1e-4, 1e-5):
            h = rel * base[key]
            up = _model_arrays({**base, key: base[key] + h}, mesh, element)
            down = _model_arrays({**base, key: base[key] - h}, mesh, element)
            fds.append({k: (up[k] - down[k]) / (2 * h) for k in up})
        for k in concrete:
            d = np.asarray(jac[k])[..., i]
            scale = max(np.max(np.abs(fds[1][k])), np.max(np.abs(d)))
            if scale == 0.0:           # e.g. the nodes do not depend on the density
                continue
            assert np.max(np.abs(fds[0][k] - fds[1][k])) <= 1e-7 * scale, (key, k, "central differences not converged")
            assert np.max(np.abs(d - fds[1][k])) <= 1e-8 * scale, (key, k)
        if key == "fill_depth":        # the depth moves the geometry: nodes, mass and stiffness all change
            assert all(np.max(np.abs(np.asarray(jac[k])[..., i])) > 0 for k in ("nodes", "mass", "stiffness")), key


def test_liquid_derivatives_at_the_paper_values_follow_the_linear_scalings():
    """At rho = 1000, c = 1500 (rho c^2 / rho g h ~ 1e5) the derivatives in density, sound speed
    and gravity are exact identities: every term is ~ rho, the acoustic one ~ c^2, the rest ~ g."""
    base = {"fill_depth": 3.0, "density": 1000.0, "sound_speed": 1500.0, "gravity": 9.81}
    m = build_liquid(SIZE, 3.0, (3, 3, 2), 1000.0, 1500.0, 9.81)
    K, M, acoustic = m.stiffness, m.mass, m.parts["acoustic"].toarray()
    expected = {"density": {"stiffness": K / 1000.0, "mass": M / 1000.0},
                "sound_speed": {"stiffness": 2.0 * acoustic / 1500.0, "mass": 0.0 * M},
                "gravity": {"stiffness": (K - acoustic) / 9.81, "mass": 0.0 * M}}
    # round-off: K - acoustic cancels ~1e3 of K's size, so the gravity identity holds to ~1e-13 only
    tolerance = {"density": 1e-14, "sound_speed": 1e-14, "gravity": 1e-11}
    for key, want in expected.items():
        _, jvp = jax.jvp(lambda v: _model_arrays({**base, key: v}, (3, 3, 2), "stabilized"), (jnp.asarray(base[key]),),
                         (jnp.asarray(1.0),))
        for k, w in want.items():
            scale = np.max(np.abs(w)) if np.any(w) else 1.0
            assert np.max(np.abs(np.asarray(jvp[k]) - w)) <= tolerance[key] * scale, (key, k)
    # the gravity derivative is not lost under the acoustic term: it is the whole of K - acoustic
    assert np.max(np.abs(K - acoustic)) < 1e-3 * np.max(np.abs(K))


SCENE = """
title = "gradient test: light hull, heavy tank liquid"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
dt = 0.01
scheme = "hht"
alpha = 0.01
tolerance = {tolerance}
[vessel]
mass = 1.0e5
inertia = [1.5e6, 4.0e6, 4.5e6]
[vessel.hydrostatics]
waterplane_area = 120.0
displaced_volume = 170.73
gm_t = 1.2
gm_l = 8.0
[vessel.initial]
angular_velocity = [0.1, 0.05, 0.0]
position = [0.0, 0.0, 0.05]
[[tanks]]
name = "tank"
origin = [-2.5, -2.5, -1.0]
size = [5.0, 5.0, 4.0]
fill_depth = {fill}
mesh = [3, 3, 2]
[tanks.fluid]
density = 1000.0
sound_speed = {c}
[[probes]]
name = "A"
tank = "tank"
point = [2.5, 5.0, 0.0]
[[probes]]
name = "B"
tank = "tank"
point = [2.5, 5.0, {fill}]
"""


def _scene(duration=1.0, tolerance=1e-13, fill=3.0, c=50.0):
    return js.load_scene(SCENE.format(duration=duration, tolerance=tolerance, fill=fill, c=c))


def test_tank_keys_are_traceable_by_name_and_by_index_and_reach_the_liquid():
    scene = _scene(c=1500.0)
    for key in ("tanks.tank.fill_depth", "tanks.tank.fluid.density", "tanks.tank.fluid.sound_speed",
                "tanks.other.fill_depth"):
        assert key in TRACEABLE
    for key in ("tanks[0].fill_depth", "tanks.tank.origin", "tanks.tank.size", "tanks.a.b.fill_depth"):
        assert key not in TRACEABLE
    with pytest.raises(SceneError, match="tanks.nope.fill_depth"):
        build(scene, {"tanks.nope.fill_depth": 3.0})
    with pytest.raises(SceneError, match="same value"):
        build(scene, {"tanks[0].fill_depth": 2.5, "tanks.tank.fill_depth": 2.5})
    with pytest.raises(SceneError, match="tanks.tank.origin"):
        build(scene, {"tanks.tank.origin": (0.0, 0.0, 0.0)})
    # a concrete value in params gives the model of the scene that says it (probes aside)
    got = build(scene, {"tanks[0].fill_depth": 2.5, "tanks.tank.fluid.density": 900.0, "environment.gravity": 9.0})
    text = SCENE.format(duration=1.0, tolerance=1e-13, fill=2.5, c=1500.0)
    text = text.replace("density = 1000.0", "density = 900.0").replace("gravity = 9.81", "gravity = 9.0")
    want = build(js.load_scene(text))
    for f in ("r", "Ms", "K", "Kdt", "Ktt"):
        a, b = np.asarray(_liquid_parts(got.system)[f]), np.asarray(_liquid_parts(want.system)[f])
        assert np.max(np.abs(a - b)) <= 1e-13 * np.max(np.abs(b)), f
    assert np.max(np.abs(np.asarray(got.c0.d) - np.asarray(want.c0.d))) <= 1e-12 * np.max(np.abs(np.asarray(want.c0.d)))
    assert abs(float(got.system.liquid.Ms.sum()) - 900.0 * 5.0 * 5.0 * 2.5) < 1e-8 * 900.0 * 62.5
    # the host-side mesh (probe weights, result fields) stays the scene's
    assert np.isclose(np.max(got.tanks[0].nodes[:, 2]), 3.0)


def _liquid_parts(system):
    """The liquid's matrices and the rotation penalty's blocks (a term of their own)."""
    L = system.liquid
    pen = next(t for t in system.terms if type(t).__name__ == "RotationPenalty")
    return {"r": L.r, "Ms": L.Ms, "K": L.K, "Kdt": pen.Kdt, "Ktt": pen.Ktt}


def test_build_and_solver_under_jit_match_the_numpy_ones():
    """The model and make_solver's liquid-block inverses built under jit (JAX assembly and
    inverses; the integer mesh held concrete as `identify` does) against the concrete build."""
    scene = _scene(c=1500.0)
    scheme = make_scheme("hht", 0.01)

    def parts(h, rho):
        with jax.ensure_compile_time_eval():
            b = build(scene, {"tanks.tank.fill_depth": h, "tanks[0].fluid.density": rho})
            s = make_solver(b.system, 0.01, scheme, 1e-10, 20, substeps=2)
        L = _liquid_parts(b.system)
        return L["r"], L["Ms"], L["K"], L["Kdt"], L["Ktt"], b.c0.d, s.Cinv_step, s.Cinv_mass, s.Cinv_sub

    traced = jax.jit(parts)(2.8, 990.0)
    concrete = parts(2.8, 990.0)
    for i, (a, b) in enumerate(zip(traced, concrete)):
        b = np.asarray(b)
        tol = 1e-12 if i < 5 else 1e-9        # solves and inverses of K (cond ~ rho c^2 / rho g h): round-off
        assert np.max(np.abs(np.asarray(a) - b)) <= tol * np.max(np.abs(b)), i


KEYS = ["tanks.tank.fill_depth", "tanks[0].fluid.density", "tanks.tank.fluid.sound_speed", "environment.gravity",
        "vessel.hydrostatics.gm_t", "vessel.hydrostatics.waterplane_area"]
P0 = np.array([3.0, 1000.0, 50.0, 9.81, 1.2, 120.0])


def test_gradient_of_a_trajectory_loss_wrt_tank_parameters_matches_central_differences():
    """0.5 s (50 steps) of roll, pitch and heave of a light hull carrying 75 t of liquid (3 x 3 x 2 mesh): the
    loss sums the squared roll and pitch, the free-surface elevation at a wall relative to the tank
    bottom (probes B - A) and the heave. jax.grad (reverse mode) against central differences at
    relative steps 1e-4 and 1e-5, which must agree with each other first. The sound speed is 50 m/s
    so that the Newton iterations reach 1e-13 (at 1500 m/s round-off in rho c^2 stops them near
    1e-10, which leaves ~1e-5 of noise in a difference quotient) and so that it moves the motion.
    The differences are taken with the same program (its values), jitted as a whole, so that the 24
    evaluations neither compile again nor build the traced model op by op (63 -> 36 s); that the
    traced model equals the NumPy one is tested above."""
    scene = _scene(duration=0.5)

    def loss(p):
        r = js.simulate(scene, params=dict(zip(KEYS, p)))
        rpy = r.vessel.roll_pitch_yaw
        eta = r.probes["B"].displacement[:, 2] - r.probes["A"].displacement[:, 2]
        value = (jnp.sum(rpy[:, 0] ** 2) + jnp.sum(rpy[:, 1] ** 2) + 100.0 * jnp.sum(eta ** 2)
                 + 100.0 * jnp.sum(r.vessel.position[:, 2] ** 2))
        return value, jnp.max(r.solver.residual)

    value_and_grad = jax.jit(jax.value_and_grad(loss, has_aux=True))

    def value(p):
        (v, residual), _ = value_and_grad(jnp.asarray(p))
        assert float(residual) <= 1e-11, residual      # every step converged to the tight tolerance
        return float(v)

    (v0, residual), g = value_and_grad(jnp.asarray(P0))
    g = np.asarray(g)
    assert float(residual) <= 1e-11
    assert np.all(np.abs(g * P0) > 1e-4 * float(v0)), g      # every parameter moves the loss
    errors = {}
    for i, key in enumerate(KEYS):
        fds = []
        for rel in (1e-4, 1e-5):
            e = np.zeros(len(P0))
            e[i] = rel * P0[i]
            fds.append((value(P0 + e) - value(P0 - e)) / (2 * e[i]))
        assert abs(fds[0] - fds[1]) <= 5e-6 * abs(fds[1]), (key, fds, "central differences not converged")
        errors[key] = abs(g[i] - fds[1]) / abs(fds[1])
    print("gradient vs central differences, relative:", {k: f"{v:.1e}" for k, v in errors.items()})
    assert all(v <= 1e-5 for v in errors.values()), errors


def test_checkpointed_long_runs_give_the_same_frames_and_gradient(monkeypatch, steps=103):
    """Runs of run.REMAT_MIN_STEPS steps or more are checkpointed in blocks of ~sqrt(n) frames (103:
    10 blocks of 10 and a remainder of 3): the frames and the gradient equal the plain scan's."""
    import equinox as eqx
    import jaxslosh.run.loop as run_mod
    import jaxslosh.run.simulate as sim_mod
    from helpers import vessel_scene
    scene = vessel_scene(duration=steps * 0.01, omega=(0.03, 0.01, 0.0))

    def loss(gm):
        r = js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm})
        return jnp.sum(r.vessel.roll_pitch_yaw[:, 0] ** 2), r.vessel.quaternion

    (l0, q0), g0 = jax.value_and_grad(loss, has_aux=True)(1.5)
    monkeypatch.setattr(run_mod, "REMAT_MIN_STEPS", 50)
    calls, checkpoint = [], jax.checkpoint
    monkeypatch.setattr(run_mod.jax, "checkpoint", lambda f, *a, **k: calls.append(1) or checkpoint(f, *a, **k))
    # the compiled loop of the first run would be taken again: the run's loop through a jit of its
    # own (a new function, so no trace of the first is reused), not jax.clear_caches(), which would
    # also drop the many small programs of the model's build and compile them all again
    monkeypatch.setattr(sim_mod, "advance", eqx.filter_jit(lambda *a: run_mod.traced_advance(*a)))
    (l1, q1), g1 = jax.value_and_grad(loss, has_aux=True)(1.5)
    assert calls              # the checkpointed form ran
    assert q1.shape == q0.shape == (steps + 1, 4)
    np.testing.assert_allclose(np.asarray(q1), np.asarray(q0), rtol=0, atol=1e-14)
    assert abs(float(g1) / float(g0) - 1.0) < 1e-10 and float(g0) != 0.0
