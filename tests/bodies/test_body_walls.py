"""Elastic tank walls on a body (docs/guide/bodies-and-connections.md, tanks on a body): a body's tank
with `[tanks.walls]` is the vessel's liquid-and-walls block on the body's frame, the walls' mass
carried by that block and the body's own the rest, as the vessel's. The carrier with its walled
tank beside the vessel has the coupled modes, and moves, as the same carrier with the same tank as
the only vessel of a scene (an independent path: the vessel's own block and hull)."""
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.analysis.coupled import coupled_modes
from jaxslosh.assemble.effects import count_unknowns

from body_rows import rows_and_residual
from test_body_tanks import scene_alone, scene_on_body

# 2 cm walls of a soft material (E = 2 GPa): they lower the carrier's roll and sloshing frequencies by
# about 1.5 % (against rigid walls), enough to tell the walls were built
WALLS = ('mesh = [2, 4, 3]\n[tanks.walls]\nthickness = 0.02\n[tanks.walls.material]\nyoung = 2.0e9\npoisson = 0.3\n'
         'density = 7850.0\n')


def walled(scene, duration=1.0, walls=WALLS):
    """The scene's tank at full order with elastic walls (the Newton tolerance above the walls'
    stiff rows' round-off)."""
    text = scene.text.replace("[tanks.reduction]\nmodes = 6\n", "").replace("mesh = [2, 4, 3]\n", walls)
    return js.load_scene(text.replace("duration = 6.0", f"duration = {duration}").replace("tolerance = 1e-10",
                                                                                          "tolerance = 1e-7"))


def _first(modes, label):
    return next(w for w, d in zip(modes.omega, modes.dominant) if d == label)


def test_a_body_tank_with_elastic_walls_has_the_lone_vessels_rows():
    """The fast twin of the two below: at a state away from rest (tilted, moving, the liquid and the
    walls displaced and accelerating), the body's six rows and its tank's rows equal the lone
    vessel's residual to round-off, 1e-12 of their size: the same block, the walls' mass in it and
    the body's hull the rest (with its first moment)."""
    ours, ref = rows_and_residual(walled(scene_on_body()).text, walled(scene_alone()).text, seed=4,
                                  sizes=(1e-4, 1e-3, 1e-2), traced_build=False)
    assert np.abs(ours).max() > 1e4
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-12 * np.abs(ours).max())


@pytest.mark.slow      # about 20 s of CPU, 100 s on a loaded 2-core machine; the rows above are its fast twin
def test_a_body_tank_with_elastic_walls_has_the_lone_vessels_coupled_modes():
    """`modes --coupled`: the carrier's roll and its liquid's first sloshing mode equal the lone
    carrier's with the same walled tank within 1e-6 (relative; measured: 2e-8), and differ from the rigid-walled
    tank's by more than 0.5 % (measured: 1.5 % and 1.4 %)."""
    on_body = coupled_modes(walled(scene_on_body()), n=12)
    alone = coupled_modes(walled(scene_alone()), n=12)
    rigid = coupled_modes(walled(scene_alone(), walls="mesh = [2, 4, 3]\n"), n=12)
    for ours, lone in (("carrier roll", "roll"), ("carrier liquid", "liquid")):
        assert _first(on_body, ours) == pytest.approx(_first(alone, lone), rel=1e-6), ours
        assert abs(_first(alone, lone) / _first(rigid, lone) - 1) > 5e-3, lone


@pytest.mark.slow      # about 15 s of CPU, 50 s on a loaded 2-core machine; the rows above are its fast twin
def test_a_body_tank_with_elastic_walls_moves_as_on_the_lone_vessel():
    """50 steps of a roll decay: the carrier's motion equals the lone carrier's within 1e-10 (rad, m),
    its tank's field and the probe on its wall's free surface within 1e-9 m (measured: 3e-13, 1e-12,
    6e-11 and 2e-11)."""
    a, b = js.simulate(walled(scene_on_body())), js.simulate(walled(scene_alone()))
    body = a.bodies["carrier"]
    assert np.ptp(b.vessel.roll_pitch_yaw[:, 0]) > 0.02
    np.testing.assert_allclose(body.roll_pitch_yaw, b.vessel.roll_pitch_yaw, rtol=0, atol=1e-10)
    np.testing.assert_allclose(body.position, b.vessel.position, rtol=0, atol=1e-10)
    Da, Db = np.asarray(a.tanks["cargo"].displacement), np.asarray(b.tanks["cargo"].displacement)
    assert np.abs(Db).max() > 1e-2
    np.testing.assert_allclose(Da, Db, rtol=0, atol=1e-9)
    np.testing.assert_allclose(a.probes["crest"].displacement, b.probes["crest"].displacement, rtol=0, atol=1e-9)


@pytest.mark.parametrize("old,new,words", [
    ("mass = 3.0e5\n", "mass = 1.0e4\n", r"bodies\[0\]\.mass: 10000 kg is the whole body without its liquid, its "
                                          r"tanks' elastic walls included, but those alone weigh 16441.3 kg"),
    ("inertia = [2.0e6,", "inertia = [2.0e4,", r"bodies\[0\]\.inertia: is the whole body's about its COG, its tanks' "
                                               r"elastic walls included, but it is smaller than theirs alone"),
])
def test_a_body_lighter_than_its_walls_is_refused_naming_the_key(old, new, words):
    """The body's mass and inertia are the whole body's, its walls' included (as the vessel's): below
    the walls' own (2 cm of steel on the floor and sides: 16.4 t as the walls' mesh carries it) they
    are refused naming the key."""
    text = walled(scene_on_body(), duration=0.02).text
    with pytest.raises(js.SceneError, match=words):
        js.simulate(js.load_scene(text.replace(old, new, 1)))


def test_check_counts_a_body_tanks_wall_unknowns():
    """`jaxslosh check` counts the body's tank with its walls' unknowns as the lone vessel's: six more
    (the vessel's frame) than the lone carrier's 788."""
    assert count_unknowns(walled(scene_alone())) == 788
    assert count_unknowns(walled(scene_on_body())) == 788 + 6


def test_reduced_walls_on_a_body_are_refused_naming_the_scenes_tank():
    """Elastic walls need the full-order liquid, on a body as on the vessel: the reduced walled tank is
    refused naming it by its place among the scene's [[tanks]] (the second: a tank on the vessel comes first)."""
    vessel_tank = ('[[tanks]]\nname = "other"\norigin = [-4.0, -2.0, 1.0]\nsize = [8.0, 4.0, 3.0]\nfill_depth = 1.0\n'
                   'mesh = [2, 2, 2]\n')
    text = scene_on_body(duration=0.02).text.replace("mesh = [2, 4, 3]\n", WALLS)
    with pytest.raises(js.SceneError, match=r"tanks\[1\]\.walls: elastic walls, and structures in the vessel's frame, "
                                            r"need the full-order dense liquid"):
        js.simulate(js.load_scene(text.replace("[[tanks]]", vessel_tank + "[[tanks]]", 1)))
