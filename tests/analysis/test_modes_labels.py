"""`jaxslosh modes` keeps the sloshing band clean (issue 30): a mode that is not sloshing (a nodal
element's spurious or circulation mode) among the sloshing modes is printed apart, labelled, and
listed in the JSON's `others_in_sloshing_band`; a tank with elastic walls lists its modes too."""
import json
import os

import numpy as np
import pytest

from jaxslosh.cli.main import main
from jaxslosh.liquid.modes import others_in_band

HEAD = """
title = "labels"
[simulation]
duration = 1.0
dt = 0.05
[vessel]
mass = 4.1e5
inertia = [6.0e6, 1.6e7, 2.0e7]
"""

# a standing baffle with slender elements beside it: the stabilized element's 12th mode is a
# spurious one between sloshing modes (the element pinned: "rt", the default with baffles, has none)
BAFFLED = HEAD + """
[[tanks]]
name = "baffled"
origin = [0.0, 0.0, 0.0]
size = [0.2, 1.0, 1.0]
fill_depth = 0.5
mesh = [2, 20, 10]
[tanks.fluid]
element = "stabilized"
[[tanks.baffles]]
normal = "y"
position = 0.5
from = "bottom"
height = 0.3
"""


def test_others_in_band():
    assert others_in_band(["sloshing", "spurious", "sloshing", "circulation"]) == [1]
    assert others_in_band(["spurious", "sloshing"]) == [0]
    assert others_in_band(["sloshing", "sloshing", "acoustic"]) == []
    assert others_in_band(["spurious"]) == []


def test_a_spurious_mode_among_the_sloshing_ones_is_printed_apart(tmp_path, capsys):
    scene = tmp_path / "b.toml"
    scene.write_text(BAFFLED)
    assert main(["modes", str(scene), "-n", "14", "--json"]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    kinds = out["kind"]
    band = out["others_in_sloshing_band"]
    assert band and all(kinds[i] != "sloshing" for i in band)
    assert all(k == "sloshing" for i, k in enumerate(kinds[:max(band)]) if i not in band)
    assert any(k == "sloshing" for k in kinds[max(band) + 1:])           # they lie among sloshing modes
    assert np.all(np.diff(out["omega"]) >= 0)                             # SPEC's form unchanged: ascending
    assert main(["modes", str(scene), "-n", "14"]) == 0
    text = capsys.readouterr().out
    main_table, apart = text.split("not sloshing, among the sloshing modes above")
    rows = [ln.split() for ln in main_table.splitlines() if ln[:3].strip().isdigit()]
    assert [r[-1] for r in rows] == ["sloshing"] * (len(kinds) - len(band)) + \
        [kinds[i] for i in range(len(kinds)) if i not in band and kinds[i] != "sloshing"]
    apart_rows = [ln.split() for ln in apart.splitlines() if ln[:3].strip().isdigit()]
    assert [int(r[0]) - 1 for r in apart_rows] == band                   # '#': the place in frequency order
    assert all(kinds[i] in apart for i in band) and "numerical mode" in apart


@pytest.mark.slow
def test_a_tank_with_elastic_walls_lists_its_modes(capsys):
    """scenes/paper_ship_elastic_tank.toml: its modes are the liquid's and the walls' together
    (`jaxslosh modes --json` failed on them: no circulation count)."""
    path = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "scenes",
                        "paper_ship_elastic_tank.toml")
    assert main(["modes", path, "-n", "3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert len(out["omega"]) == 3 and out["circulation_modes_left_out"] == 0
