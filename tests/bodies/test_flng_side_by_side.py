"""scenes/flng_side_by_side.toml (docs/guide/flng-side-by-side.md): it loads without a warning, its
masses balance their buoyancy, the hulls' footprints are the overlap check's rectangles, and it runs.
The overlap check's separations are held to closed forms."""
import math
from pathlib import Path

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.scene.placement import apart as _apart, outline as _outline
from jaxslosh.scene.types import SceneError

ROOT = Path(__file__).resolve().parents[2]
FLNG = ROOT / "scenes" / "flng_side_by_side.toml"


@pytest.fixture(scope="module")
def scene():
    return js.load_scene(str(FLNG))


def test_the_scene_loads_without_warnings_and_floats_at_rest(scene):
    assert scene.warnings == ()
    rho = scene.environment.water_density
    liquid = sum(t.fluid.density * v for t, v in zip(scene.tanks, (7208.0, 15416.0, 23624.0, 31812.8)))
    # the four tanks' LNG from their sections (hopper 5 x 5 m, top chamfer 8 x 6 m) by hand
    assert liquid == pytest.approx(35.127e6, rel=1e-4)
    assert scene.vessel.mass + liquid == pytest.approx(rho * scene.vessel.hydrostatics.displaced_volume, rel=1e-6)
    # the carrier's four half-full tanks (36 x 22 m section, 4 x 4 m hoppers): (36 x 11 - 16) x 40 m^3 each
    carrier = scene.bodies[0]
    assert [t.liquid_mass for t in carrier.tanks] == pytest.approx([450.0 * 380.0 * 40.0] * 4, rel=1e-9)
    assert carrier.mass + sum(t.liquid_mass for t in carrier.tanks) == pytest.approx(
        rho * carrier.hydrostatics.displaced_volume, rel=1e-6)
    # the fenders touch at rest: the FLNG's side (32.5 m) and the carrier's (60 - 23 m) 4.5 m apart
    for c in scene.connections:
        if c.kind == "fender":
            assert c.length == pytest.approx(60.0 - 23.0 - 32.5)


def test_the_overlap_check_takes_the_footprints(scene):
    text = FLNG.read_text().replace('file = "flng_side', f'file = "{FLNG.parent}/flng_side')   # read from text
    # 0.5 m of overlap between the sides is refused, naming the key
    with pytest.raises(SceneError) as e:
        js.load_scene(text.replace("position = [0.0, 60.0]", "position = [0.0, 55.0]"))
    assert e.value.key == "bodies[0].position" and "overlap at rest by 0.5 m" in str(e.value)
    # without footprints the waterplanes are circles of their areas (radii 91.0 and 65.2 m): refused
    bare = "\n".join(line for line in text.splitlines() if not line.startswith("footprint"))
    with pytest.raises(SceneError, match="as circles of their areas"):
        js.load_scene(bare)


def test_the_separations_of_rectangles_and_circles():
    a = _outline((0.0, 0.0), 0.0, (400.0, 65.0), 1.0)
    b = _outline((0.0, 60.0), 0.0, (290.0, 46.0), 1.0)
    assert _apart(a, b) == pytest.approx(4.5)
    # end to end along x: 10 m between them; turned by 90 deg the second one's length lies across
    assert _apart(a, _outline((255.0, 0.0), 0.0, (90.0, 10.0), 1.0)) == pytest.approx(10.0)
    assert _apart(a, _outline((250.0, 0.0), math.pi / 2, (90.0, 10.0), 1.0)) == pytest.approx(45.0)
    # a square turned by 45 deg beside a rectangle: its corner reaches sqrt(2) / 2 of its side
    sq = _outline((0.0, 32.5 + 3.0 + 10.0 / math.sqrt(2)), math.pi / 4, (10.0, 10.0), 1.0)
    assert _apart(a, sq) == pytest.approx(3.0)
    # a circle of area pi r^2 beside a rectangle's side, and beyond its corner
    c = _outline((0.0, 32.5 + 2.0 + 5.0), 0.0, None, math.pi * 25.0)
    assert _apart(a, c) == pytest.approx(2.0)
    corner = _outline((200.0 + 3.0, 32.5 + 4.0), 0.0, None, math.pi * 1.0)
    assert _apart(corner, a) == pytest.approx(5.0 - 1.0)
    inside = _outline((0.0, 30.0), 0.0, None, math.pi * 1.0)
    assert _apart(a, inside) == pytest.approx(-2.5 - 1.0)
    # two circles: the old check, centre distance less the radii
    assert _apart(_outline((0, 0), 0, None, math.pi * 4), _outline((0, 5), 0, None, math.pi)) == pytest.approx(2.0)


@pytest.mark.slow
def test_the_scene_runs(scene):
    """A few seconds of the sea state: the connections start at rest (taut hawsers, touching fenders,
    no force), the run is ok and the carrier stays alongside."""
    r = js.simulate(scene, duration=5.0)
    assert r.status == "ok"
    for name, c in r.connections.items():
        f = np.asarray(c.force)
        assert abs(f[0]) < 1.0e3, (name, f[0])          # 1 kN of the lines' 1.8-3.1 MN/m stiffness: 0.3 mm
        assert np.all(np.isfinite(f))
    gap_change = np.asarray(r.bodies["carrier"].position)[:, 1] - np.asarray(r.vessel.position)[:, 1]
    assert np.max(np.abs(gap_change)) < 1.0
