"""A multimodal tank of a shape it cannot take (issue 43, item 11): the error names the key and lists
what is allowed (a box, an upright cylinder), never "leave shape out" where shape = "cylinder" works."""
import os

import pytest

from jaxslosh.cli.main import main

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _scene(tmp_path, tank, size="[1.73, 0.2, 1.15]"):
    t = open(os.path.join(ROOT, "scenes", "sloshing_experiment.toml")).read()
    t = t.replace('model = "multimodal"', 'model = "multimodal"\n' + tank).replace("[1.73, 0.2, 1.15]", size)
    path = tmp_path / "scene.toml"
    path.write_text(t)
    return str(path)


@pytest.mark.parametrize("tank", ['shape = "prismatic"\nchamfers = [[0.2, 0.2], [0.0, 0.0]]',
                                  'shape = "mesh"\nfile = "tank.msh"'])
def test_the_shape_error_lists_the_allowed_shapes(tmp_path, capsys, tank):
    assert main(["check", _scene(tmp_path, tank)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: tanks[0].shape: ") and err.count("\n") == 1, err
    assert 'shape = "box"' in err and 'shape = "cylinder" with axis = "z"' in err, err
    assert "leave shape out" not in err, err
    assert f'not shape = "{tank.split(chr(34))[1]}"' in err, err


def test_an_upright_cylinder_and_a_box_are_taken(tmp_path, capsys):
    assert main(["check", _scene(tmp_path, 'shape = "box"')]) == 0
    assert main(["check", _scene(tmp_path, 'shape = "cylinder"\naxis = "z"', "[1.0, 1.0, 1.15]")]) == 0, \
        capsys.readouterr().err
