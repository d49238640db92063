"""Scene loader: valid scenes load; every bad-input rule raises one SceneError naming the key."""
import copy
import math
import tomllib

import pytest

from jaxslosh.scene.types import ELEMENT_FORMS
from jaxslosh.scene.keys import canonical_key, check_param_keys, scene_values
from jaxslosh.assemble.effects import describe
from jaxslosh.scene.load import load_scene, parse_scene
from jaxslosh.scene.types import SceneError

# SPEC.md section 1, both examples together.
SPEC_EXAMPLE = """
title = "Rigid ship carrying a rigid tank with 75 m3 of water"

[environment]
gravity = 9.81
water_density = 1025.0

[simulation]
duration = 20.0
dt = 0.01
scheme = "hht"
alpha = 0.01
save_every = 1

[vessel]
mass = 3.25e5
inertia = [4.9e6, 1.45e7, 1.6e7]

[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 400.0
gm_t = 1.67
gm_l = 14.2

[vessel.initial]
velocity = [0.0, 0.0, 0.0]
angular_velocity = [0.1, 0.05, 0.0]
roll_pitch_yaw = [0.0, 0.0, 0.0]

[[tanks]]
name = "tank"
origin = [-2.5, -2.5, -1.0]
size = [5.0, 5.0, 4.0]
fill_depth = 3.0
mesh = [5, 5, 5]
walls = "rigid"

[tanks.fluid]
density = 1000.0
sound_speed = 1500.0

[[probes]]
name = "A"
tank = "tank"
point = [4.5, 2.5, 0.0]
[[probes]]
name = "B"
tank = "tank"
point = [4.5, 2.5, 3.0]

[[structures]]
name = "mast"
origin = [-0.15, -0.15, 1.0]
size = [0.3, 0.3, 5.0]
mesh = [2, 2, 20]
attach = "z-"
[structures.material]
young = 2.1e11
poisson = 0.3
density = 7850.0

[[probes]]
name = "tip"
structure = "mast"
point = [0.15, 0.15, 5.0]
"""

VESSEL_ONLY = """
title = "vessel alone"
[simulation]
duration = 2.0
dt = 0.01
[vessel]
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 390.0
gm_t = 1.5
gm_l = 15.0
"""

ELASTIC_WALLS = {"thickness": 0.02, "material": {"young": 2.1e11, "poisson": 0.3, "density": 7850.0}}


def base():
    return tomllib.loads(SPEC_EXAMPLE)


def at(d, path):
    """The container holding the last part of a dotted path ('tanks.0.fluid.density'), and that part."""
    parts = [int(p) if p.isdigit() else p for p in path.split(".")]
    for p in parts[:-1]:
        d = d[p]
    return d, parts[-1]


def mutated(*edits):
    d = base()
    for path, value in edits:
        c, k = at(d, path)
        if value is DELETE:
            del c[k]
        else:
            c[k] = value
    return d


DELETE = object()


# --------------------------------------------------------------------------------------------
# Valid scenes


def test_spec_example_loads():
    s = parse_scene(base(), text=SPEC_EXAMPLE, path="spec.toml")
    assert s.title.startswith("Rigid ship")
    assert s.text == SPEC_EXAMPLE and s.path == "spec.toml"
    assert s.environment.gravity == 9.81 and s.environment.water_density == 1025.0
    assert s.simulation.scheme == "hht" and s.simulation.alpha == 0.01 and s.simulation.n_steps == 2000
    assert s.simulation.tolerance == 1e-10 and s.simulation.max_iterations == 25 and s.simulation.chunk == 0
    assert s.vessel.mass == 3.25e5
    assert s.vessel.inertia == ((4.9e6, 0.0, 0.0), (0.0, 1.45e7, 0.0), (0.0, 0.0, 1.6e7))
    assert s.vessel.hydrostatics.gm_t == 1.67 and s.vessel.hydrostatics.moment == "conservative"
    assert s.vessel.initial.angular_velocity == (0.1, 0.05, 0.0) and s.vessel.initial.position == (0, 0, 0)
    (tank,) = s.tanks
    kind = tank.walls            # the scene key `walls` (rigid or elastic tank sides)
    assert tank.name == "tank" and tank.size == (5.0, 5.0, 4.0) and tank.mesh == (5, 5, 5) and kind == "rigid"
    assert tank.fluid.element == ELEMENT_FORMS[0] == "stabilized"
    assert math.isclose(tank.liquid_mass, 75_000.0)
    assert [p.name for p in s.probes] == ["A", "B", "tip"]          # file order
    assert s.probes[2].structure == "mast" and s.probes[2].tank is None
    assert s.structures[0].material.young == 2.1e11 and s.structures[0].attach == "z-"
    assert s.tank("tank") is tank and s.structure("mast") is s.structures[0]
    # 325 t + 75 t of liquid against 1025 * 400 = 410 t: 2.4 % off, warned, not an error
    assert len(s.warnings) == 1 and "static imbalance" in s.warnings[0]


def test_vessel_only_from_text_and_file(tmp_path):
    s = load_scene(VESSEL_ONLY)
    assert s.tanks == () and s.probes == () and s.structures == () and s.path == ""
    assert s.environment.gravity == 9.81 and s.simulation.scheme == "hht" and s.simulation.alpha == 0.0
    assert s.warnings == ()                                       # 4.0e5 kg vs 1025 * 390 = 399750 kg
    f = tmp_path / "vessel.toml"
    f.write_text(VESSEL_ONLY)
    s2 = load_scene(f)
    assert s2.path == str(f) and s2.text == VESSEL_ONLY and s2.vessel == s.vessel
    assert load_scene(str(f)).vessel == s.vessel


def test_extra_keys_and_forms():
    d = mutated(("simulation.tolerance", 1e-8), ("simulation.max_iterations", 10), ("simulation.chunk", 100),
                ("simulation.scheme", "generalized-alpha"), ("simulation.alpha", DELETE), ("simulation.rho_inf", 0.8),
                ("vessel.hydrostatics.moment", "conservative"), ("vessel.initial.position", [0, 0, 1]),
                ("tanks.0.fluid.element", "paper"), ("vessel.mass", 335000),          # an int for a float
                ("vessel.inertia", [[4.9e6, 0, -1e5], [0, 1.45e7, 0], [-1e5, 0, 1.6e7]]),
                ("tanks.0.walls", dict(ELASTIC_WALLS, mesh=[5, 5, 4])))
    s = parse_scene(d)
    assert s.simulation.tolerance == 1e-8 and s.simulation.chunk == 100 and s.simulation.rho_inf == 0.8
    assert s.vessel.hydrostatics.moment == "conservative" and s.vessel.initial.position == (0.0, 0.0, 1.0)
    assert s.tanks[0].fluid.element == "paper" and isinstance(s.vessel.mass, float)
    assert s.vessel.inertia[0][2] == s.vessel.inertia[2][0] == -1e5
    tank = s.tanks[0]
    kind, sides = tank.walls, tank.wall_spec    # the scene's `walls` table: elastic tank sides
    assert kind == "elastic" and sides.thickness == 0.02 and sides.mesh == (5, 5, 4)
    assert sides.material.poisson == 0.3
    assert s.warnings == ()                                       # 335 t + 75 t = 410 t: balanced


def test_optional_tables_default():
    d = tomllib.loads(VESSEL_ONLY)
    del d["vessel"]["hydrostatics"]
    d["environment"] = {"gravity": 0}
    s = parse_scene(d)
    assert s.vessel.hydrostatics is None and s.environment.gravity == 0.0 and s.warnings == ()


def test_forced_motion_without_hydrostatics_does_not_say_the_vessel_falls():
    """Issue 21: [vessel.forced] holds every rigid dof (one prescribed, five at zero), so a scene
    without hydrostatics under gravity does not fall; the free-fall warning is for free vessels."""
    d = tomllib.loads(VESSEL_ONLY)
    del d["vessel"]["hydrostatics"]
    free = parse_scene(d)
    assert len(free.warnings) == 1 and "falls freely" in free.warnings[0]
    d["vessel"]["forced"] = {"dof": "surge", "amplitude": 0.001, "frequency": 1.5, "ramp": 3.0}
    s = parse_scene(d)
    assert s.vessel.forced is not None and s.environment.gravity > 0
    assert not any("falls" in w or "holds the vessel" in w for w in s.warnings), s.warnings


def test_scene_differences_name_values_and_structure():
    """scene/compare.py (identify's check of a record's scene): loaded scenes are compared, so a
    default written out is no difference; values, meshes, dt, save_every and tables present in one
    scene only are, named by dotted key; the duration and the fitted keys are not."""
    from jaxslosh.scene.compare import differences
    a = parse_scene(base())
    assert differences(a, parse_scene(mutated(("effects", {"liquid": True}), ("simulation.duration", 5.0)))) == []
    b = parse_scene(mutated(("simulation.dt", 0.02), ("simulation.save_every", 2), ("tanks.0.mesh", [4, 4, 4]),
                            ("tanks.0.fluid", {"density": 1025.0}), ("vessel.hydrostatics.gm_t", 1.2),
                            ("probes.1.point", [4.5, 2.5, 2.9]), ("structures", DELETE), ("probes.2", DELETE)))
    diff = {k: (x, y) for k, x, y in differences(a, b)}
    assert diff.pop("simulation.dt") == (0.01, 0.02) and diff.pop("simulation.save_every") == (1, 2)
    assert diff.pop("tanks.tank.mesh") == ((5, 5, 5), (4, 4, 4))
    assert diff.pop("tanks.tank.fluid.density") == (1000.0, 1025.0)
    assert diff.pop("vessel.hydrostatics.gm_t") == (1.67, 1.2)
    assert diff.pop("probes.B.point")[1] == (4.5, 2.5, 2.9)
    assert diff.pop("structures.mast")[1] is None and diff.pop("probes.tip")[1] is None    # not key by key
    assert diff == {}, diff
    assert "vessel.hydrostatics.gm_t" not in {k for k, _, _ in differences(a, b, ignore=["vessel.hydrostatics.gm_t"])}


def test_probe_on_boundaries_within_tolerance():
    s = parse_scene(mutated(("probes.0.point", [5.0 + 5e-10, -5e-10, 0.0]),
                            ("probes.1.point", [0.0, 2.5, 4.0])))          # on a wall, above the liquid
    assert s.probes[0].point[0] > 5.0


# --------------------------------------------------------------------------------------------
# Bad input: (edits, key that the message must start with)

BAD = {
    # unknown keys, at every level
    "top-level unknown": ([("effectz", {"buoyancy": True})], "effectz"),
    "effects unknown": ([("effects", {"sloshing": True})], "effects.sloshing"),
    "effects not a bool": ([("effects", {"buoyancy": 1})], "effects.buoyancy"),
    "environment unknown": ([("environment.gravty", 9.81)], "environment.gravty"),
    "simulation unknown": ([("simulation.dtt", 0.01)], "simulation.dtt"),
    "vessel unknown": ([("vessel.masss", 1.0)], "vessel.masss"),
    "hydrostatics unknown": ([("vessel.hydrostatics.gm", 1.0)], "vessel.hydrostatics.gm"),
    "initial unknown": ([("vessel.initial.omega", [0, 0, 0])], "vessel.initial.omega"),
    "tank unknown": ([("tanks.0.depth", 3.0)], "tanks[0].depth"),
    "fluid unknown": ([("tanks.0.fluid.viscosity", 1e-3)], "tanks[0].fluid.viscosity"),
    "walls unknown": ([("tanks.0.walls", dict(ELASTIC_WALLS, colour="red"))], "tanks[0].walls.colour"),
    "walls material unknown": ([("tanks.0.walls", dict(ELASTIC_WALLS, material=dict(
        ELASTIC_WALLS["material"], yield_stress=1.0)))], "tanks[0].walls.material.yield_stress"),
    "structure unknown": ([("structures.0.colour", "red")], "structures[0].colour"),
    "structure material unknown": ([("structures.0.material.e", 1.0)], "structures[0].material.e"),
    "probe unknown": ([("probes.0.owner", "tank")], "probes[0].owner"),
    # missing required keys and tables
    "no simulation": ([("simulation", DELETE)], "simulation"),
    "no vessel": ([("vessel", DELETE)], "vessel"),
    "no duration": ([("simulation.duration", DELETE)], "simulation.duration"),
    "no dt": ([("simulation.dt", DELETE)], "simulation.dt"),
    "no mass": ([("vessel.mass", DELETE)], "vessel.mass"),
    "no inertia": ([("vessel.inertia", DELETE)], "vessel.inertia"),
    "no gm_l": ([("vessel.hydrostatics.gm_l", DELETE)], "vessel.hydrostatics.gm_l"),
    "no waterplane": ([("vessel.hydrostatics.waterplane_area", DELETE)], "vessel.hydrostatics.waterplane_area"),
    "tank no name": ([("tanks.0.name", DELETE)], "tanks[0].name"),
    "tank no size": ([("tanks.0.size", DELETE)], "tanks[0].size"),
    "tank no fill": ([("tanks.0.fill_depth", DELETE)], "tanks[0].fill_depth"),
    "tank no mesh": ([("tanks.0.mesh", DELETE)], "tanks[0].mesh"),
    "walls no thickness": ([("tanks.0.walls", {"material": ELASTIC_WALLS["material"]})], "tanks[0].walls.thickness"),
    "walls no material": ([("tanks.0.walls", {"thickness": 0.01})], "tanks[0].walls.material"),
    "structure no attach": ([("structures.0.attach", DELETE)], "structures[0].attach"),
    "structure no material": ([("structures.0.material", DELETE)], "structures[0].material"),
    "material no poisson": ([("structures.0.material.poisson", DELETE)], "structures[0].material.poisson"),
    "probe no point": ([("probes.0.point", DELETE)], "probes[0].point"),
    "probe no name": ([("probes.1.name", DELETE)], "probes[1].name"),
    # wrong types
    "bool mass": ([("vessel.mass", True)], "vessel.mass"),
    "string dt": ([("simulation.dt", "0.01")], "simulation.dt"),
    "nan duration": ([("simulation.duration", float("nan"))], "simulation.duration"),
    "inf gravity": ([("environment.gravity", float("inf"))], "environment.gravity"),
    "float save_every": ([("simulation.save_every", 2.0)], "simulation.save_every"),
    "bool max_iterations": ([("simulation.max_iterations", True)], "simulation.max_iterations"),
    "vector of 2": ([("tanks.0.origin", [0.0, 0.0])], "tanks[0].origin"),
    "vector of 4": ([("vessel.initial.velocity", [0, 0, 0, 0])], "vessel.initial.velocity"),
    "vector with bool": ([("vessel.initial.angular_velocity", [0.1, False, 0.0])], "vessel.initial.angular_velocity"),
    "vector not a list": ([("probes.0.point", 4.5)], "probes[0].point"),
    "float mesh": ([("tanks.0.mesh", [5.0, 5, 5])], "tanks[0].mesh"),
    "mesh of 2": ([("structures.0.mesh", [2, 2])], "structures[0].mesh"),
    "walls mesh floats": ([("tanks.0.walls", dict(ELASTIC_WALLS, mesh=[1.5, 2, 2]))], "tanks[0].walls.mesh"),
    "scheme not str": ([("simulation.scheme", 1)], "simulation.scheme"),
    "title not str": ([("title", 3)], "title"),
    "name not str": ([("tanks.0.name", 1)], "tanks[0].name"),
    "empty name": ([("tanks.0.name", " ")], "tanks[0].name"),
    "dotted name": ([("probes.0.name", "a.b")], "probes[0].name"),
    "vessel not table": ([("vessel", 5)], "vessel"),
    "fluid not table": ([("tanks.0.fluid", "water")], "tanks[0].fluid"),
    "tanks not array": ([("tanks", {"name": "tank"})], "tanks"),
    "inertia 2x3": ([("vessel.inertia", [[1, 0, 0], [0, 1, 0]])], "vessel.inertia"),
    "inertia strings": ([("vessel.inertia", ["1", "2", "3"])], "vessel.inertia"),
    # impossible values
    "negative mass": ([("vessel.mass", -1.0)], "vessel.mass"),
    "zero mass": ([("vessel.mass", 0)], "vessel.mass"),
    "negative gravity": ([("environment.gravity", -9.81)], "environment.gravity"),
    "zero water density": ([("environment.water_density", 0.0)], "environment.water_density"),
    "zero dt": ([("simulation.dt", 0.0)], "simulation.dt"),
    "negative duration": ([("simulation.duration", -1.0)], "simulation.duration"),
    "dt above duration": ([("simulation.dt", 30.0)], "simulation.dt"),
    "zero fluid density": ([("tanks.0.fluid.density", 0.0)], "tanks[0].fluid.density"),
    "negative sound speed": ([("tanks.0.fluid.sound_speed", -1.0)], "tanks[0].fluid.sound_speed"),
    "zero tank size": ([("tanks.0.size", [5.0, 0.0, 4.0])], "tanks[0].size"),
    "negative structure size": ([("structures.0.size", [0.3, -0.3, 5.0])], "structures[0].size"),
    "zero waterplane": ([("vessel.hydrostatics.waterplane_area", 0.0)], "vessel.hydrostatics.waterplane_area"),
    "negative displacement": ([("vessel.hydrostatics.displaced_volume", -4.0)], "vessel.hydrostatics.displaced_volume"),
    "zero young": ([("structures.0.material.young", 0.0)], "structures[0].material.young"),
    "zero material density": ([("structures.0.material.density", 0.0)], "structures[0].material.density"),
    "zero thickness": ([("tanks.0.walls", dict(ELASTIC_WALLS, thickness=0.0))], "tanks[0].walls.thickness"),
    "walls material young": ([("tanks.0.walls", dict(ELASTIC_WALLS, material=dict(
        ELASTIC_WALLS["material"], young=-1.0)))], "tanks[0].walls.material.young"),
    "mesh zero": ([("tanks.0.mesh", [5, 0, 5])], "tanks[0].mesh"),
    "mesh negative": ([("structures.0.mesh", [2, 2, -1])], "structures[0].mesh"),
    "walls mesh zero": ([("tanks.0.walls", dict(ELASTIC_WALLS, mesh=[0, 2, 2]))], "tanks[0].walls.mesh"),
    "fill above height": ([("tanks.0.fill_depth", 4.5)], "tanks[0].fill_depth"),
    "fill zero": ([("tanks.0.fill_depth", 0.0)], "tanks[0].fill_depth"),
    "fill negative": ([("tanks.0.fill_depth", -1.0)], "tanks[0].fill_depth"),
    "poisson 0.5": ([("structures.0.material.poisson", 0.5)], "structures[0].material.poisson"),
    "poisson -1": ([("structures.0.material.poisson", -1.0)], "structures[0].material.poisson"),
    "inertia negative diagonal": ([("vessel.inertia", [4.9e6, -1.45e7, 1.6e7])], "vessel.inertia"),
    "inertia not symmetric": ([("vessel.inertia", [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]])], "vessel.inertia"),
    "inertia not definite": ([("vessel.inertia", [[1, 2, 0], [2, 1, 0], [0, 0, 1]])], "vessel.inertia"),
    "bad scheme": ([("simulation.scheme", "euler")], "simulation.scheme"),
    "alpha negative": ([("simulation.alpha", -0.1)], "simulation.alpha"),
    "alpha above 1/3": ([("simulation.alpha", 0.34)], "simulation.alpha"),
    "newmark with alpha": ([("simulation.scheme", "newmark")], "simulation.alpha"),
    "rho_inf above 1": ([("simulation.scheme", "generalized-alpha"), ("simulation.alpha", DELETE),
                         ("simulation.rho_inf", 1.5)], "simulation.rho_inf"),
    "rho_inf negative": ([("simulation.rho_inf", -0.1)], "simulation.rho_inf"),
    "save_every zero": ([("simulation.save_every", 0)], "simulation.save_every"),
    "tolerance zero": ([("simulation.tolerance", 0.0)], "simulation.tolerance"),
    "max_iterations zero": ([("simulation.max_iterations", 0)], "simulation.max_iterations"),
    "chunk negative": ([("simulation.chunk", -1)], "simulation.chunk"),
    "projection not bool": ([("simulation.energy_projection", 1)], "simulation.energy_projection"),
    "projection with hht": ([("simulation.energy_projection", True)], "simulation.energy_projection"),
    "projection with structures": ([("simulation.scheme", "newmark"), ("simulation.alpha", DELETE),
                                    ("simulation.energy_projection", True)], "simulation.energy_projection"),
    "bad walls": ([("tanks.0.walls", "glass")], "tanks[0].walls"),
    "elastic without table": ([("tanks.0.walls", "elastic")], "tanks[0].walls"),
    "walls wrong type": ([("tanks.0.walls", 3)], "tanks[0].walls"),
    "bad attach": ([("structures.0.attach", "bottom")], "structures[0].attach"),
    "bad moment": ([("vessel.hydrostatics.moment", "exact")], "vessel.hydrostatics.moment"),
    "bad element": ([("tanks.0.fluid.element", "quadratic")], "tanks[0].fluid.element"),
    # probes
    "probe outside tank": ([("probes.0.point", [5.5, 2.5, 0.0])], "probes[0].point"),
    "probe below tank": ([("probes.0.point", [4.5, 2.5, -1e-6])], "probes[0].point"),
    "probe in the air": ([("probes.1.point", [2.5, 2.5, 3.5])], "probes[1].point"),
    "probe outside structure": ([("probes.2.point", [0.15, 0.15, 5.1])], "probes[2].point"),
    "probe no owner": ([("probes.0.tank", DELETE)], "probes[0]"),
    "probe two owners": ([("probes.0.structure", "mast")], "probes[0]"),
    "probe missing tank": ([("probes.0.tank", "tnk")], "probes[0].tank"),
    "probe missing structure": ([("probes.2.structure", "boom")], "probes[2].structure"),
    # names
    "duplicate tank": ([("tanks", [base()["tanks"][0]] * 2)], "tanks[1].name"),
    "duplicate structure": ([("structures", [base()["structures"][0]] * 2)], "structures[1].name"),
    "duplicate probe": ([("probes.1.name", "A")], "probes[1].name"),
}


@pytest.mark.parametrize("edits, key", list(BAD.values()), ids=list(BAD))
def test_bad_input(edits, key):
    with pytest.raises(SceneError) as info:
        parse_scene(mutated(*edits))
    err = info.value
    assert err.key == key
    assert str(err).startswith(key + ": ")
    assert "\n" not in str(err)


def test_messages_read_well():
    def message(*edits):
        with pytest.raises(SceneError) as info:
            parse_scene(mutated(*edits))
        return str(info.value)

    assert message(("tanks.0.fill_depth", 4.5)) == "tanks[0].fill_depth: 4.5 m is above the tank height 4.0 m"
    assert message(("vessel.mass", -1.0)) == "vessel.mass: must be positive, got -1.0"
    assert message(("simulation.dtt", 0.01)).startswith("simulation.dtt: unknown key (known: duration, dt, ")
    m = message(("simulation.scheme", "newmark"))
    assert "gamma = 1/2" in m and "beta = 1/4" in m and "amplif" in m and 'scheme = "hht"' in m
    assert "boolean true" in message(("vessel.mass", True))


def test_toml_syntax_error_names_line():
    with pytest.raises(SceneError) as info:
        load_scene("title = 'x'\n[simulation\nduration = 1.0\n")
    assert "not valid TOML" in str(info.value) and "line 2" in str(info.value)


def test_spec_elastic_form_gets_a_hint():
    text = SPEC_EXAMPLE.replace('walls = "rigid"', 'walls = "elastic"\n[tanks.walls]\nthickness = 0.01')
    with pytest.raises(SceneError, match="not valid TOML.*remove the line walls"):
        load_scene(text)


def test_missing_file(tmp_path):
    with pytest.raises(SceneError, match="no such file"):
        load_scene(tmp_path / "nope.toml")
    with pytest.raises(SceneError, match="no such file"):
        load_scene(str(tmp_path / "nope.toml"))


# --------------------------------------------------------------------------------------------
# Warnings


def test_warning_unstable_gm():
    s = parse_scene(mutated(("vessel.hydrostatics.gm_t", -0.2), ("vessel.mass", 335000.0)))
    assert s.warnings == ("vessel.hydrostatics.gm_t = -0.2 m <= 0: the vessel is statically unstable in roll; "
                          "it will capsize or loll",)
    s = parse_scene(mutated(("vessel.hydrostatics.gm_l", 0.0), ("vessel.mass", 335000.0)))
    assert len(s.warnings) == 1 and "gm_l" in s.warnings[0] and "pitch" in s.warnings[0]


def test_warning_mass_balance():
    assert parse_scene(mutated(("vessel.mass", 335000.0))).warnings == ()
    assert parse_scene(mutated(("vessel.mass", 335000.0 + 0.009 * 410000))).warnings == ()
    (w,) = parse_scene(mutated(("vessel.mass", 3.0e5))).warnings
    assert w.startswith("vessel.hydrostatics.displaced_volume:")
    assert "as if it were the equilibrium" in w and f"{35000 * 9.81:.4g} N" in w
    # without gravity the imbalance is zero and without hydrostatics there is no buoyancy to compare
    assert parse_scene(mutated(("vessel.mass", 3.0e5), ("environment.gravity", 0.0))).warnings == ()


def test_other_warnings():
    (w,) = parse_scene(mutated(("vessel.mass", 335000.0), ("vessel.inertia", [1.0, 2.0, 4.0]))).warnings
    assert "triangle" in w
    (w,) = parse_scene(mutated(("vessel.mass", 335000.0), ("simulation.duration", 1.005))).warnings
    assert w.startswith("simulation.duration") and "100 steps" in w
    (w,) = parse_scene(mutated(("vessel.mass", 335000.0), ("simulation.rho_inf", 0.5))).warnings
    assert w.startswith("simulation.rho_inf")
    d = tomllib.loads(VESSEL_ONLY)
    del d["vessel"]["hydrostatics"]
    (w,) = parse_scene(d).warnings
    assert "falls" in w


def test_loading_does_not_change_the_mapping():
    d = base()
    before = copy.deepcopy(d)
    parse_scene(d)
    assert d == before


# --------------------------------------------------------------------------------------------
# Values by dotted path, parameter keys, description


def test_scene_values():
    s = parse_scene(mutated(("tanks.0.walls", ELASTIC_WALLS)))
    v = scene_values(s)
    assert v["vessel.mass"] == 3.25e5 and v["vessel.hydrostatics.gm_t"] == 1.67
    assert v["environment.gravity"] == 9.81 and v["simulation.dt"] == 0.01
    assert v["vessel.inertia"] == s.vessel.inertia and v["vessel.initial.angular_velocity"] == (0.1, 0.05, 0.0)
    assert v["tanks.tank.fill_depth"] == v["tanks[0].fill_depth"] == 3.0
    assert v["tanks.tank.fluid.density"] == v["tanks[0].fluid.density"] == 1000.0
    assert v["tanks.tank.walls.material.young"] == 2.1e11
    assert v["structures.mast.material.poisson"] == v["structures[0].material.poisson"] == 0.3
    assert v["probes.B.point"] == (4.5, 2.5, 3.0)
    assert "tanks.tank.mesh" not in v and "simulation.save_every" not in v
    assert "vessel.hydrostatics.gm_t" not in scene_values(load_scene(VESSEL_ONLY.split("[vessel.hydrostatics]")[0]))


def test_check_param_keys():
    s = parse_scene(base())
    assert check_param_keys(s, ["vessel.hydrostatics.gm_t", "tanks[0].fill_depth"]) == (
        "vessel.hydrostatics.gm_t", "tanks.tank.fill_depth")
    assert canonical_key(s, "probes[2].point") == "probes.tip.point"
    with pytest.raises(SceneError) as info:
        check_param_keys(s, ["vessel.gm_t"])
    assert info.value.key == "vessel.gm_t" and "vessel.hydrostatics.gm_t" in str(info.value)
    with pytest.raises(SceneError, match="same value"):
        check_param_keys(s, ["tanks[0].fill_depth", "tanks.tank.fill_depth"])


def test_describe():
    text = describe(parse_scene(base()))
    assert "Rigid ship" in text and "3.25e+05 kg" in text and "75 m^3" in text
    assert "5 x 5 x 5 = 125 hexahedra" in text and "tip" in text and "2000 steps" in text
