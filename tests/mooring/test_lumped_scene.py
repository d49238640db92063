"""`model = "lumped"` lines read from a scene and run (jaxslosh/mooring/lumped_term.py): the start
at the catenary's tension, the nodes in the result and back from the file, `js.mooring` on them."""
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.mooring.catenary import catenary
from test_statics import SMALL, _lines

LUMPED = 'model = "lumped"\nsegments = 10\nmass = 70.0\n'


def test_scene_reads_lumped_lines():
    scene = js.load_scene(SMALL + _lines(extra=LUMPED))
    assert [m.model for m in scene.mooring] == ["lumped"] * 3
    assert dict(scene.mooring[0].lumped) == {"segments": 10, "mass": 70.0}


@pytest.mark.slow
def test_lumped_lines_run_and_keep_their_nodes(tmp_path):
    scene = js.load_scene(SMALL.replace("duration = 60.0", "duration = 4.0") + _lines(extra=LUMPED))
    result = js.simulate(scene)
    m = result.mooring["l0"]
    n = len(np.asarray(result.time))
    assert np.asarray(m.nodes).shape == (n, 11, 3)
    np.testing.assert_allclose(np.asarray(m.nodes)[:, 0], [[400.0, 0.0, -100.0]] * n, atol=1e-9)
    # at t = 0 the vessel is 0.5 m off its rest position along +X (line l0's anchor is along +X)
    c = catenary((400.0 - 5.0 - 0.5, 100.0), 420.0, 600.0, 3.0e8)
    assert float(np.asarray(m.fairlead_tension)[0]) == pytest.approx(
        float(np.hypot(c.fairlead_horizontal, c.fairlead_vertical)), rel=5e-3)
    path = str(tmp_path / "lumped.h5")
    js.save_result(result, path)
    back = js.load_result(path)
    np.testing.assert_array_equal(np.asarray(back.mooring["l1"].nodes), np.asarray(result.mooring["l1"].nodes))


@pytest.mark.slow
def test_statics_of_lumped_lines_are_the_catenary():
    a = js.mooring(js.load_scene(SMALL + _lines()), offsets=[0.0, 5.0])
    b = js.mooring(js.load_scene(SMALL + _lines(extra=LUMPED)), offsets=[0.0, 5.0])
    np.testing.assert_allclose(np.asarray(b.stiffness), np.asarray(a.stiffness))


@pytest.mark.slow
def test_frequency_domain_takes_lumped_lines_as_their_catenary():
    from jaxslosh.analysis.linear import linearise
    a = linearise(js.load_scene(SMALL + _lines()))
    b = linearise(js.load_scene(SMALL + _lines(extra=LUMPED)))
    np.testing.assert_allclose(np.asarray(b.K), np.asarray(a.K))
