"""A structure in the vessel's frame beside the vessel's multimodal tank: the multimodal liquid's block
holds its modal coordinates alone, so the loader refuses the pair, naming the structure's `frame`
(exit status 2 on the CLI), instead of a run that leaves the structure out."""
import pytest

import jaxslosh as js
from jaxslosh.cli.main import main

from helpers import mast, multibody_vessel

TANK = ('[[tanks]]\nname = "tank"\nmodel = "multimodal"\norigin = [-1.5, -1.0, -2.0]\nsize = [3.0, 2.0, 2.0]\n'
        'fill_depth = 1.2\n')


def _text(frame: str, model: str = "multimodal") -> str:
    part = mast(mesh=(1, 1, 2)).replace("[structures.material]", f'frame = "{frame}"\n[structures.material]')
    tank = TANK if model == "multimodal" else TANK.replace('model = "multimodal"', 'mesh = [3, 2, 2]')
    return multibody_vessel(duration=0.05) + tank + part


def test_the_loader_names_the_structures_frame():
    with pytest.raises(js.SceneError) as e:
        js.load_scene(_text("vessel"))
    assert e.value.key == "structures[0].frame"
    assert "multimodal" in str(e.value)


def test_the_cli_exits_2_and_writes_nothing(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(_text("vessel"))
    out = tmp_path / "out.h5"
    assert main(["run", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: structures[0].frame: "), err
    assert not out.exists()


@pytest.mark.parametrize("frame, model", [("own", "multimodal"), ("vessel", "fem")])
def test_the_other_pairs_load(frame, model):
    scene = js.load_scene(_text(frame, model))
    assert [s.frame for s in scene.structures] == [frame]
