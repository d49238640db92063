"""The box tank (`shape = "box"`, the default), with or without baffles."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, final

from ..fem.shapes import TankMesh
from ..hull.box import box_surface
from .base import AbstractShape
from .section import NO_CHAMFERS, section_mesh, section_outline


@final
@dataclass(frozen=True)
class Box(AbstractShape):
    """A box of inner size (a, b, H) from its min corner; baffles across x or y."""
    name: ClassVar[str] = "box"
    elastic: ClassVar[bool] = True
    modal: ClassVar[bool] = True
    baffle_normals: ClassVar[tuple] = ("x", "y")

    size: tuple = (1.0, 1.0, 1.0)
    baffles: tuple = ()

    @property
    def plain_box(self) -> bool:
        return not self.baffles

    def volume(self, fill_depth: float) -> float:
        a, b, _ = self.size
        return a * b * fill_depth                     # traced fill depths pass through

    def _mesh(self, h: float, counts: tuple, graded: bool = True) -> TankMesh:
        return section_mesh(self.size, NO_CHAMFERS, self.baffles, h, counts, graded)

    def _outline(self, fill_depth: float, mesh) -> list:
        return section_outline(self.size, NO_CHAMFERS)

    def modal_base(self, rectangle, disk):
        return rectangle(float(self.size[0]), float(self.size[1]))

    def surface(self):
        return box_surface([0, 0, 0], list(self.size))
