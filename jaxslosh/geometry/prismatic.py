"""The prismatic tank (`shape = "prismatic"`): a box whose y-z section has its bottom and top corners
cut by chamfers (width along y, height along z): membrane LNG tanks' hopper and top-side tanks."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, final

import numpy as np

from ..fem.shapes import TankMesh
from ..hull.tanks import prism_surface, prismatic_section
from .base import AbstractShape, Reader
from .section import NO_CHAMFERS, section_mesh, section_outline, section_walls


@final
@dataclass(frozen=True)
class Prismatic(AbstractShape):
    """`chamfers` = ((width, height) of the bottom cuts, (width, height) of the top cuts), m, both
    sides; baffles across x."""
    name: ClassVar[str] = "prismatic"
    rt_on_modes: ClassVar[bool] = True
    keys: ClassVar[tuple] = ("chamfers",)
    baffle_normals: ClassVar[tuple] = ("x",)

    size: tuple = (1.0, 1.0, 1.0)
    chamfers: tuple = NO_CHAMFERS
    baffles: tuple = ()

    @classmethod
    def read_own(cls, table, v, where: str, base_dir: str, reader: Reader) -> dict:
        if "chamfers" not in table:
            return {}
        return {"chamfers": _chamfers(table["chamfers"], f"{where}.chamfers", reader)}

    def _check(self, h: float, counts):
        a, b, H = self.size
        (cw, ch), (tw, th) = self.chamfers
        if min(cw, ch, tw, th) < 0:
            return "chamfers", "chamfer widths and heights must be >= 0"
        if (cw > 0) != (ch > 0) or (tw > 0) != (th > 0):
            return "chamfers", "a chamfer needs both its width and its height > 0 (or both 0)"
        if cw > b / 2 + 1e-12 * b or tw > b / 2 + 1e-12 * b:
            return "chamfers", f"a chamfer is wider than half the breadth {b:g} m"
        if ch + th > H + 1e-12 * H:
            return "chamfers", f"the bottom and top chamfers ({ch:g} + {th:g} m) are taller than the tank ({H:g} m)"
        if abs(tw - b / 2) <= 1e-12 * b and h > H - th:
            return "fill_depth", "the liquid reaches the ridge where the top chamfers meet"
        return None

    def sloped(self, fill_depth: float) -> bool:
        (_, ch), (_, th) = self.chamfers
        H = self.size[2]
        return ch > 0 or (th > 0 and fill_depth > H - th + 1e-12 * H)

    def volume(self, fill_depth: float) -> float:
        a, b, H = self.size
        h = fill_depth
        zs = np.unique(np.clip(np.array([0.0, self.chamfers[0][1], H - self.chamfers[1][1], h]), 0, h))
        w = [section_walls(self.size, self.chamfers, z) for z in zs]
        return float(a * sum(0.5 * ((w[i][1] - w[i][0]) + (w[i + 1][1] - w[i + 1][0])) * (zs[i + 1] - zs[i])
                             for i in range(len(zs) - 1)))

    def _mesh(self, h: float, counts: tuple, graded: bool = True) -> TankMesh:
        return section_mesh(self.size, self.chamfers, self.baffles, h, counts, graded)

    def _outline(self, fill_depth: float, mesh) -> list:
        return section_outline(self.size, self.chamfers)

    def surface(self):
        return prism_surface(prismatic_section(self.size, self.chamfers), self.size[0])

    def _describe(self) -> str:
        (cw, ch), (tw, th) = self.chamfers
        return f"prismatic (chamfers bottom {cw:g} x {ch:g} m, top {tw:g} x {th:g} m)"


def _chamfers(value, where, reader: Reader):
    """[[bottom width, height], [top width, height]], or {bottom = [w, h], top = [w, h]}."""
    show = reader.show
    if isinstance(value, dict):
        c = reader.read(value, where, {"bottom": ("numbers", None), "top": ("numbers", None)})
        pairs = [(f"{where}.{k}", c.get(k, [0.0, 0.0])) for k in ("bottom", "top")]
    elif isinstance(value, list) and len(value) == 2:
        pairs = [(f"{where}[{i}]", w) for i, w in enumerate(value)]
    else:
        raise reader.error(where, f"must be [[bottom width, height], [top width, height]] in m, got {show(value)}")
    out = []
    for key, w in pairs:
        ok = isinstance(w, list) and len(w) == 2 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                          for x in w)
        if not ok or min(w) < 0:
            raise reader.error(key, f"must be [width, height] in m (>= 0), got {show(w)}")
        out.append((float(w[0]), float(w[1])))
    return tuple(out)
