"""A scene simulates only the effects it calls for: nothing else is traced, switches are exact."""
import jax
import numpy as np

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.cli import main
from jaxslosh.solve.integrator import initial_state, step
from jaxslosh.solve.schemes import make_scheme
from jaxslosh.solve.linear import make_solver

from helpers import vessel_scene


def _avals(jaxpr):
    for eqn in jaxpr.eqns:
        for v in list(eqn.invars) + list(eqn.outvars):
            if hasattr(v, "aval"):
                yield v.aval
        for p in eqn.params.values():
            sub = getattr(p, "jaxpr", None)
            if sub is not None:
                yield from _avals(getattr(sub, "jaxpr", sub))


def test_vessel_only_step_traces_no_liquid_operations():
    b = build(vessel_scene(omega=(0.01, 0.02, 0.0)))
    solver = make_solver(b.system, 0.01, make_scheme("hht", 0.01), 1e-10, 25)
    s0, _ = initial_state(b.system, solver, b.c0, b.v0)
    jaxpr = jax.make_jaxpr(lambda s: step(b.system, solver, s))(s0)
    shapes = {tuple(a.shape) for a in _avals(jaxpr.jaxpr) if hasattr(a, "shape")}
    biggest = max(max(s) if s else 0 for s in shapes)
    assert biggest <= 6, sorted(shapes)   # 6 rigid unknowns, 4 Euler parameters, nothing of a liquid
    assert len(jaxpr.jaxpr.eqns) > 0


def test_buoyancy_switched_off_equals_zeroed_coefficients():
    scene = vessel_scene(duration=3.0, omega=(0.05, 0.02, 0.01), position=(0, 0, 0.1))
    off = js.load_scene(scene.text + "\n[effects]\nbuoyancy = false\n")
    r_off = js.simulate(off)
    r_zero = js.simulate(scene, params={"vessel.hydrostatics.gm_t": 0.0, "vessel.hydrostatics.gm_l": 0.0,
                                        "vessel.hydrostatics.waterplane_area": 0.0}, check=False)
    np.testing.assert_allclose(np.asarray(r_off.vessel.quaternion), np.asarray(r_zero.vessel.quaternion), atol=1e-13)
    np.testing.assert_allclose(np.asarray(r_off.vessel.position), np.asarray(r_zero.vessel.position), atol=1e-13)
    # and it does something: with buoyancy the motion differs
    r_on = js.simulate(scene)
    assert np.max(np.abs(np.asarray(r_on.vessel.position) - np.asarray(r_off.vessel.position))) > 1e-3


def test_check_lists_effects_and_unknowns(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(vessel_scene().text + "\n[effects]\nbuoyancy = false\n")
    assert main(["check", str(p)]) == 0
    out = capsys.readouterr().out
    assert "rigid-body inertia" in out and "buoyancy" in out.split("switched off")[1]
    assert "unknowns per step: 6" in out
