"""The loader's liquid form per tank (scene/liquids.py, docs/design.md "The liquid"): one final
object made from the tank's keys, which the rest of the code asks instead of the keys' strings."""
import dataclasses
import os

import pytest

from jaxslosh.liquid.face.term import FaceLiquid
from jaxslosh.liquid.forms import tank_liquid
from jaxslosh.liquid.modal.term import ModalLiquid
from jaxslosh.liquid.multimodal.liquid import MultimodalLiquid
from jaxslosh.liquid.nodal.term import NodalLiquid
from jaxslosh.scene.liquids import FaceForm, MultimodalForm, NodalForm
from jaxslosh.scene.load import load_scene
from jaxslosh.scene.types import Reduction, Tank

SCENES = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "scenes")


@pytest.mark.parametrize("name, form, liquid", [
    ("sloshing_experiment", MultimodalForm(three_dimensional=False, third_order=False), MultimodalLiquid),
    ("paper_ship_tank", NodalForm(form="stabilized"), NodalLiquid),
    ("paper_ship_elastic_tank", NodalForm(form="stabilized", elastic=True), NodalLiquid),
    ("anti_roll_tank", NodalForm(form="stabilized", reduced=True), ModalLiquid),
    ("lng_carrier", FaceForm(), FaceLiquid),
    ("flng_side_by_side", FaceForm(reduced=True), ModalLiquid),
])
def test_a_shipped_scene_s_tank_has_its_form_and_liquid(name, form, liquid):
    t = load_scene(os.path.join(SCENES, name + ".toml")).tanks[0]
    assert t.form == form
    assert tank_liquid(t) is liquid
    assert (t.multimodal, t.face_normal) == (form.multimodal, form.face_normal)


def test_a_tank_made_by_hand_or_replaced_gets_the_form_of_its_keys():
    t = Tank(name="t", origin=(0.0, 0.0, 0.0), size=(2.0, 1.0, 1.0), fill_depth=0.5, mesh=(2, 2, 2))
    assert t.form == NodalForm(form="stabilized") and t.form.element == "stabilized"
    r = dataclasses.replace(t, reduction=Reduction(modes=4))
    assert r.form.reduced and tank_liquid(r) is ModalLiquid
    m = dataclasses.replace(t, model="multimodal", flow="3d", expansion="third-order")
    assert m.form == MultimodalForm(three_dimensional=True, third_order=True)
    assert m.three_dimensional and m.third_order and not m.form.along_length_only
    assert dataclasses.replace(m, flow="2d").form.along_length_only
