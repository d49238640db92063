"""A body with a box hull on linear hydrostatics takes the waves' Froude-Krylov force on its box, as
the vessel does (docs/guide/bodies-and-connections.md, a body's hull): a box body far from the
vessel has the RAO of the same box as the lone vessel, moved to its place in the incident field,
and a run in regular waves moves it as the lone vessel moves; `excitation = "froude-krylov"` on a
body without a box is refused naming it."""
import math

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.bodyhydro import box_waves
from jaxslosh.hydro.spectra import wavenumber
from jaxslosh.scene.types import SceneError

G = 9.81
L, B, T, KG = 20.0, 10.0, 2.0, 2.5
BOX = f"""mass = {1025.0 * L * B * T!r}
inertia = [6.0e6, 1.6e7, 2.0e7]
{{damping}}
[{{table}}.hull]
length = {L}
beam = {B}
draft = {T}
kg = {KG}
[{{table}}.hydrostatics]
model = "linear"
"""
# viscous damping in sway and roll (the run settles in a few periods); the box's closed forms fill
# its hydrostatics
DAMPED = "[{table}.hydrodynamics]\nviscous_damping = [0.0, 5.0e4, 0.0, 2.0e6, 0.0, 0.0]\n"


def _text(waves: str, position=None, duration=1.0, dt=0.1) -> str:
    head = f"[environment]\ngravity = {G}\n[simulation]\nduration = {duration}\ndt = {dt}\ntolerance = 1e-10\n{waves}\n"
    vessel = "[vessel]\n" + BOX.format(table="vessel", damping="").replace("[vessel.hydrostatics]", DAMPED.format(
        table="vessel") + "[vessel.hydrostatics]")
    if position is None:
        return head + vessel
    body = ('[[bodies]]\nname = "barge"\n' + f"position = {list(position)!r}\n"
            + BOX.format(table="bodies", damping="").replace("[bodies.hydrostatics]", DAMPED.format(table="bodies")
                                                            + "[bodies.hydrostatics]"))
    return head + vessel + body


def test_a_far_box_body_has_the_lone_boxs_rao_at_its_place():
    """1,000 m away: the body's RAO is the lone vessel's (the same box and damping) times the incident
    phase at its place, e^{-i k (x cos b + y sin b)}, to 1e-9 of its size, in beam, quartering and
    head seas; the vessel beside it keeps its own."""
    w = np.linspace(0.3, 1.5, 7)
    heads = np.array([0.0, math.pi / 4, math.pi / 2])
    pos = (600.0, 800.0)
    pair = js.load_scene(_text("", pos))
    assert box_waves(pair.bodies[0]) == "unless tabled"
    r = js.rao(pair, frequencies=w, headings=heads)
    alone = js.rao(js.load_scene(_text("")), frequencies=w, headings=heads).vessel
    k = wavenumber(w, G)
    shift = np.exp(-1j * k[:, None] * (pos[0] * np.cos(heads) + pos[1] * np.sin(heads))[None, :])[:, :, None]
    size = np.abs(alone).max()
    assert np.abs(alone[:, 2, 3]).max() > 0.1 * size                        # it rolls in beam seas
    np.testing.assert_allclose(r.bodies["barge"], alone * shift, rtol=0, atol=1e-9 * size)
    np.testing.assert_allclose(r.vessel, alone, rtol=0, atol=1e-9 * size)


def test_a_box_body_in_regular_waves_moves_as_the_lone_box():
    """Head seas (waves along x), the body 1,000 m along the crests (the same incident phase as the vessel's COG):
    30 steps of its motion equal the lone vessel's within 1e-9 (m, rad), and it moves."""
    waves = "[waves]\ntype = \"regular\"\namplitude = 0.5\nperiod = 6.0\nheading = 0.0\nramp = 1.0\n"
    pair = js.load_scene(_text(waves, (0.0, 1000.0), duration=3.0))
    assert not any("exert no force" in w for w in pair.warnings)
    a, b = js.simulate(pair), js.simulate(js.load_scene(_text(waves, duration=3.0)))
    body = a.bodies["barge"]
    assert np.abs(np.asarray(b.vessel.position)[:, 0]).max() > 1e-3       # the waves move it (surge, heave, pitch)
    np.testing.assert_allclose(body.position, b.vessel.position, rtol=0, atol=1e-9)
    np.testing.assert_allclose(body.roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-9)
    np.testing.assert_allclose(a.vessel.position, b.vessel.position, rtol=0, atol=1e-9)


def test_froude_krylov_on_a_body_needs_its_box():
    text = _text("", (0.0, 60.0)).replace("[bodies.hydrodynamics]\n", "[bodies.hydrodynamics]\nexcitation = \"froude-krylov\"\n")
    scene = js.load_scene(text)
    assert box_waves(scene.bodies[0]) == "only"
    bad = text.replace('model = "linear"', 'model = "nonlinear"').replace(f"kg = {KG}", f"kg = {KG}\ndepth = 4.0")
    with pytest.raises(SceneError, match=r"bodies\[0\]\.hydrodynamics\.excitation"):
        js.load_scene(bad)
