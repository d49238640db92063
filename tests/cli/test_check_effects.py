"""`jaxslosh check` lists the assembled model's own terms: each term of the built model describes
itself, `check` prints exactly those lines (read from the model's outline, assembled without its
arrays), so an effect is listed when, and only when, its term is in the model."""
from __future__ import annotations

import itertools
import math
import os
import pickle

import jax
import pytest
from helpers import MULTIBODY_TANK, VESSEL, mast, multibody_vessel

import jaxslosh as js
from jaxslosh.assemble.check import GRAVITY_TURNING, model_effects, model_parts
from jaxslosh.assemble.system import build, outline
from jaxslosh.cli import main
from jaxslosh.physics.about import About
from jaxslosh.liquid.base import AbstractLiquid, NoLiquid
from jaxslosh.physics.vessel import AbstractPrescribedMotion

DATA = os.path.join(os.path.dirname(os.path.dirname(__file__)), "data")
BOX = open(os.path.join(DATA, "box_20x10x2.toml")).read()
BOX_HYDRO = BOX + "\n" + open(os.path.join(DATA, "box_20x10x2_hydro.toml")).read()    # the box with its tables
REGULAR = f'[waves]\ntype = "regular"\namplitude = 0.2\nperiod = 8.0\nheading = {math.pi / 2!r}\n'
TANK = ('[[tanks]]\nname = "{name}"\norigin = [{x}, -1.0, 0.0]\nsize = [2.0, 2.0, 1.0]\nfill_depth = 0.5\n'
        'mesh = [2, 2, 2]\n')
VESSEL_TEXT = VESSEL.format(duration=1.0, dt=0.05, scheme="newmark", alpha=0.0, omega=[0.0, 0.0, 0.0],
                            position=[0.0, 0.0, 0.0])

# name: (scene text, effects its model must have, effects it must not have)
SCENES = {
    "linear hull, damped tank, forced roll, Coriolis off": (
        VESSEL_TEXT + '[vessel.forced]\ndof = "roll"\namplitude = 0.01\nfrequency = 1.0\n'
        + TANK.format(name="damped", x=-2.0) + "[tanks.damping]\nratio = 0.05\n" + TANK.format(name="plain", x=0.5)
        + "[effects]\ncoriolis = false\n",
        {"rigid-body inertia", "buoyancy", "prescribed motion", "liquid in tank 'damped'", "liquid in tank 'plain'",
         "liquid damping in tank 'damped'", "rotation penalty", "centrifugal", GRAVITY_TURNING[0]},
        {"Coriolis", "gravity", "liquid damping in tank 'plain'", "waves"}),
    "nonlinear hull in waves, face-normal tank": (
        BOX.replace("[vessel.hull]", '[vessel.hydrostatics]\nmodel = "nonlinear"\n[vessel.hydrodynamics]\n'
                                     "viscous_damping = [0, 0, 0, 1e5, 0, 0]\n[vessel.hull]\ndepth = 4.0")
        + REGULAR + TANK.format(name="rt", x=-1.0) + '[tanks.fluid]\nelement = "rt"\n',
        {"buoyancy", "waves", "gravity", "viscous damping", "liquid in tank 'rt'", "rotation penalty"},
        {"wave diffraction", "radiation", "radiation memory"}),
    "linear hull with tables in waves, no liquid": (
        BOX_HYDRO.replace("[vessel.hydrodynamics]", "[vessel.hydrodynamics]\nviscous_damping = [0, 0, 0, 1e5, 0, 0]")
        + REGULAR,
        {"buoyancy", "waves", "radiation", "radiation memory", "viscous damping"},
        {"gravity", "rotation penalty", "Coriolis", GRAVITY_TURNING[0]}),
    "structures in both frames": (
        multibody_vessel() + MULTIBODY_TANK + mast(mesh=(1, 1, 2))
        + mast(name="arm", origin=(1.0, 0.5, 0.0), size=(0.3, 0.3, 1.0), mesh=(1, 1, 2)).replace(
            "[structures.material]", 'frame = "vessel"\nstiffening = "centrifugal"\n[structures.material]'),
        {"flexible structure 'mast'", "flexible structure 'arm'", "centrifugal stiffening of 'arm'",
         "liquid in tank 'tank'", "Coriolis"},
        {"centrifugal stiffening of 'mast'"}),
    "multimodal tank, damped, free fall": (
        VESSEL_TEXT.replace("[vessel.hydrostatics]\nwaterplane_area = 200.0\ndisplaced_volume = 390.0\ngm_t = 1.5\n"
                            "gm_l = 15.0\n", "")
        + '[[tanks]]\nname = "flat"\norigin = [-2.0, -0.2, 0.0]\nsize = [1.0, 0.4, 0.8]\nfill_depth = 0.5\n'
          'model = "multimodal"\nmodes = 2\n[tanks.damping]\nratio = 0.02\n',
        {"gravity", "liquid in tank 'flat'", "liquid damping in tank 'flat'", GRAVITY_TURNING[0]},
        {"buoyancy", "rotation penalty", "Coriolis"}),
}


def _kind(owner) -> str:
    """A line's owner as the outline can match it: the outline's liquid is of the nodal class
    whatever the element (only its description is read)."""
    return "liquid" if isinstance(owner, AbstractLiquid) else type(owner).__name__


def _printed_effects(out: str) -> list[str]:
    after = out.split("effects simulated:\n", 1)[1].splitlines()
    return [line[4:] for line in itertools.takewhile(lambda x: x.startswith("  - "), after)]


#: the multimodal tank's build compiles its integrals for half a minute: a long case
SLOW = {"multimodal tank, damped, free fall"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in SCENES])
def test_check_prints_the_lines_of_the_built_models_terms_and_no_other(name, tmp_path, capsys):
    text, present, absent = SCENES[name]
    path = tmp_path / "s.toml"
    path.write_text(text)
    scene = js.load_scene(str(path))
    system = build(scene).system
    full = model_effects(system)
    parts = model_parts(system)
    # every term of the model says what it adds (a vessel without liquid adds nothing)
    for part in parts:
        if isinstance(part, NoLiquid):
            assert part.describe() == ()
        else:
            assert part.describe(), f"{type(part).__name__} is in the model and has no line"
    # every line comes from a part of the model (or the System's own switch of gravity turning)
    owners = [id(p) for p in parts] + [id(system)]
    assert all(id(owner) in owners for *_, owner in full)
    effects = [e for e, _, _ in full]
    assert present <= set(effects), present - set(effects)
    assert not absent & set(effects), absent & set(effects)
    # a prescribed motion is a term of the model, with its own line; a free vessel has no such term
    motion = [o for e, _, o in full if e == "prescribed motion"]
    assert [type(o) for o in motion] == [type(t) for t in system.terms if isinstance(t, AbstractPrescribedMotion)]
    assert [id(t) for t in system.prescribing()] == [id(o) for o in motion]
    # what check assembles (the outline, no arrays) has the same lines from the same terms
    lite = model_effects(outline(scene))
    assert [(e, t, _kind(o)) for e, t, o in lite] == [(e, t, _kind(o)) for e, t, o in full]
    # and check prints exactly those lines
    assert main(["check", str(path)]) == 0
    assert _printed_effects(capsys.readouterr().out) == [f"{e}: {t}" for e, t, _ in full]


def test_a_term_left_out_of_the_model_leaves_its_line_out(tmp_path, capsys):
    """[effects] radiation = false leaves the hull's radiation and its linear damping out of the built
    model (one switch for the hull's damping): their lines go with their terms; waves = false takes
    the excitation alone."""
    text = BOX_HYDRO.replace("[vessel.hydrodynamics]", "[vessel.hydrodynamics]\nviscous_damping = [0, 0, 0, 1e5, 0, 0]")
    for off, left in (("radiation", ["waves"]), ("waves", ["radiation", "radiation memory", "viscous damping"])):
        path = tmp_path / f"{off}.toml"
        path.write_text(text + REGULAR + f"[effects]\n{off} = false\n")
        scene = js.load_scene(str(path))
        built = [type(t).__name__ for t in build(scene).system.terms]
        lines = model_effects(outline(scene))
        assert [e for e, _, _ in lines] == ["rigid-body inertia", "buoyancy"] + left
        assert [type(o).__name__ for _, _, o in lines[1:]] == built
        assert main(["check", str(path)]) == 0
        out = capsys.readouterr().out
        assert _printed_effects(out) == [f"{e}: {t}" for e, t, _ in lines]
        assert off in out.split("switched off in [effects]:")[1]


def test_a_description_is_no_part_of_the_program():
    """Two models that differ only in their descriptions have one tree structure (they share their
    compiled programs); a description pickles without its lines (the compile cache's key)."""
    a, b = About(("waves", "Hs 1 m")), About(("waves", "Hs 2 m"))
    assert a == b and hash(a) == hash(b) and a.lines != b.lines
    assert pickle.loads(pickle.dumps(a)).lines == ()
    one = outline(js.load_scene(BOX_HYDRO + REGULAR))
    two = outline(js.load_scene(BOX_HYDRO + REGULAR.replace("amplitude = 0.2", "amplitude = 0.4")))
    assert model_effects(one) != model_effects(two)
    assert jax.tree_util.tree_structure(one) == jax.tree_util.tree_structure(two)
