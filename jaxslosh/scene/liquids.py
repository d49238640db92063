"""The liquid form of a `[[tanks]]` table: an abstract `LiquidForm` and one final class per liquid
model, made once from the tank's keys (`model`, `fluid.element`, `flow`, `expansion`, the
`[tanks.reduction]` and `[tanks.walls]` tables) by `liquid_form`. The tank keeps it as `Tank.form`;
jaxslosh/liquid asks its flags (`multimodal`, `face_normal`, `reduced`, `elastic`, ...) instead of
comparing the keys' strings, code elsewhere its behaviour (`dense_blocks`, `dampable`, ...) or the
liquid that runs it, and jaxslosh/liquid maps it to the model that runs it
(liquid/forms.py `tank_liquid`). docs/design.md, "The liquid", lists the forms.
"""
from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import ClassVar, final

from ..fem.mesh import FACE_FORMS


@dataclass(frozen=True)
class LiquidForm(abc.ABC):
    """Which liquid model a tank's liquid takes, and how it runs: on its lowest modes (`reduced`,
    [tanks.reduction]) or at full order, in rigid or elastic walls (`elastic`, [tanks.walls])."""
    reduced: bool = False
    elastic: bool = False

    #: the model's name in words (`jaxslosh check`, error messages)
    name: ClassVar[str] = ""
    #: the multimodal liquid (liquid/multimodal), not a finite-element one
    multimodal: ClassVar[bool] = False
    #: the face-normal finite element (liquid/face), not a nodal one
    face_normal: ClassVar[bool] = False
    #: a multimodal tank's flow is three-dimensional (a cylinder's always), not along x alone
    three_dimensional: ClassVar[bool] = False
    #: a multimodal tank runs its third-order system, not the exact integrals
    third_order: ClassVar[bool] = False

    @property
    def along_length_only(self) -> bool:
        """Its liquid sloshes along the tank's length (x) alone: a two-dimensional multimodal tank."""
        return self.multimodal and not self.three_dimensional

    # What code outside the loader and jaxslosh/liquid asks of a form: behaviour, never which model
    # (tests/docs/test_liquid_guards.py keeps the flags above to scene/ and liquid/).
    @property
    def dense_blocks(self) -> bool:
        """Its blocks are dense whatever the mesh's size (elastic walls bring dense blocks of their
        own): `simulation.linear_solver = "auto"` keeps the scene's liquid off the sparse way."""
        return self.elastic

    @property
    def dampable(self) -> bool:
        """`[tanks.damping]` can damp its sloshing modes: they are the liquid's alone (rigid walls),
        not shared with elastic walls."""
        return not self.elastic

    def across_seas_warning(self, headings: str) -> str:
        """What its liquid leaves out at the headings `headings` (degrees, in words) that are not
        along the ship, in a warning's words; "" where it takes such seas whole."""
        if not self.along_length_only:
            return ""
        return (f"a multimodal tank with flow = \"2d\" sloshes only along its length (x); at heading {headings} deg "
                f"the sway, roll and yaw leave its liquid frozen across the tank (no transverse sloshing, no "
                f"free-surface effect in roll): set flow = \"3d\" in [[tanks]] for waves across it too")

    def carried_words(self, tank, text: str, loads: str) -> tuple[str, str]:
        """(the tank's line `text`, its loads on a body that carries it) in the words of the body's
        line (assemble/bodies.py): a finite element's loads are `loads` (its rotation penalty, the
        inertial loads [effects] switches; gravity's the body's, added after), and a reduced
        liquid's line says its modes."""
        return (f"{text}, on {tank.reduction.modes} modes" if self.reduced else text), loads

    @property
    @abc.abstractmethod
    def element(self) -> str:
        """The finite-element form (`fluid.element`: "stabilized", "paper", "rt"), "" for none."""


@final
@dataclass(frozen=True)
class NodalForm(LiquidForm):
    """The nodal finite element (liquid/nodal): the "stabilized" or "paper" form."""
    form: str = "stabilized"
    name: ClassVar[str] = "nodal"

    @property
    def element(self) -> str:
        return self.form


@final
@dataclass(frozen=True)
class FaceForm(LiquidForm):
    """The face-normal finite element "rt" (liquid/face)."""
    name: ClassVar[str] = "face-normal"
    face_normal: ClassVar[bool] = True

    @property
    def element(self) -> str:
        return "rt"


@final
@dataclass(frozen=True)
class MultimodalForm(LiquidForm):
    """The multimodal liquid (liquid/multimodal): free-surface modes in a rigid tank, two-dimensional
    along a box's length or three-dimensional, on exact integrals or its third-order system."""
    three_dimensional: bool = False
    third_order: bool = False
    name: ClassVar[str] = "multimodal"
    multimodal: ClassVar[bool] = True

    @property
    def element(self) -> str:
        return ""

    def carried_words(self, tank, text: str, loads: str) -> tuple[str, str]:
        # its inertial loads are the modal Lagrangian's, not switched by [effects] (its line says so)
        return text.split("; its inertial loads")[0], "the modal Lagrangian's"


def liquid_form(tank) -> LiquidForm:
    """The form a tank's keys choose (the loader has checked that they go together)."""
    if tank.model == "multimodal":
        return MultimodalForm(three_dimensional=tank.flow == "3d", third_order=tank.expansion == "third-order")
    how = dict(reduced=tank.reduction is not None, elastic=tank.wall_spec is not None)
    if tank.fluid.element in FACE_FORMS:
        return FaceForm(**how)
    return NodalForm(form=tank.fluid.element, **how)
