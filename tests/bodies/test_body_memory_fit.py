"""The radiation memory of a [[bodies]] body and of the vessel take one path (hydro/radiation.py
fit_tables, assemble/seakeeping.py memory_of): the same tables give the same fit with the same
`memory_order` (a body's was ignored: always automatic), and the same memory."""
import numpy as np

import jaxslosh as js
from jaxslosh.assemble.bodyhydro import source_fit, sources, time_terms
from jaxslosh.assemble.seakeeping import memory_module
from jaxslosh.hydro.source import radiation_fit
from two_boxes_scene import box

HEAD = "[simulation]\nduration = 1.0\ndt = 0.05\n"


def _same(a, b):
    return (np.array_equal(a.p, b.p) and np.array_equal(a.inp, b.inp) and np.array_equal(a.c, b.c)
            and np.array_equal(a.added_mass_infinite, b.added_mass_infinite))


def test_a_bodys_memory_order_gives_the_vessels_fit_of_the_same_tables():
    """The barge's tables as the vessel's and as a body's (heading 0, far from a tender vessel), with
    memory_order = 2: the body's fit is the vessel's, array for array (two pole pairs per fitted
    entry, fewer poles than the automatic fit's), and its memory over the 12 rigid dofs is the
    vessel's own memory on the body's six."""
    order = "memory_order = 2\n"
    alone = js.load_scene(HEAD + box("vessel", "barge", 0, "barge.nc") + order)
    pair = js.load_scene(HEAD + box("vessel", "tender", 1, "tender.nc")
                         + box("bodies", "barge", 0, "barge.nc", "position = [0.0, 300.0]") + order)
    fv = radiation_fit(alone)
    src = next(s for s in sources(pair) if s.index[0] == 6)
    fb = source_fit(src)
    assert _same(fv, fb)
    automatic = js.load_scene(HEAD + box("vessel", "barge", 0, "barge.nc"))
    assert 0 < fv.p.size < radiation_fit(automatic).p.size
    # the memory over the vessel's and the body's dofs: the body's block is the vessel's own memory
    mine = memory_module(fv)
    _, memory, _ = time_terms(pair, {})
    rows = np.asarray(memory.select)[:, 6:].any(axis=1)
    assert np.array_equal(np.asarray(memory.select)[rows][:, 6:], np.asarray(mine.select))
    assert np.array_equal(np.asarray(memory.c_re)[6:][:, rows], np.asarray(mine.c_re))
