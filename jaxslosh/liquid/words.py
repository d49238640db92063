"""A tank's liquid in words (`TankWords`), as the model that runs its form says it (liquid/base.py
`AbstractLiquid.describe_tank`, asked of liquid/forms.py `tank_liquid(tank)`): assemble/about.py,
effects.py and run/validity.py list them without asking which model a tank takes. Here the
pieces the models share: the tank's shape, a finite-element tank's mesh, element and walls."""
from __future__ import annotations

from typing import NamedTuple

from .walls import shell_mesh


class TankWords(NamedTuple):
    """A tank's liquid in `jaxslosh check`'s words and the run's validity warnings."""
    line: tuple          # (effect, text): the tank's liquid as the liquid term holds it
    walls: tuple         # (effect, text) lines of its elastic walls in the deformable block (none: rigid)
    mesh: str            # what the liquid is discretized into: its mesh, or a multimodal tank's modes
    damped: str          # the modes `[tanks.damping]` damps
    model: str           # the model's name in the validity warnings ("the linear liquid")


def shape_words(t) -> str:
    """"prismatic (chamfers ...) " and the like for a tank that is not a plain box, else ""."""
    if t.geometry.plain_box:
        return ""
    return t.geometry.describe() + ", "


def grid_words(t, short: bool = False) -> str:
    """"mesh 5 x 5 x 5 = 125 hexahedra" (a grid, of any shape, or a mesh file that is one), or
    "mesh file of 12 hexahedra on 30 nodes" (a mesh tank's file that is not a grid: its counts
    along x, y, z mean nothing): a finite-element tank's mesh."""
    nx, ny, nz = t.mesh
    words = t.geometry.mesh_words()
    if words is not None:
        return words
    return f"{nx}x{ny}x{nz} hexahedra" if short else f"mesh {nx} x {ny} x {nz} = {nx * ny * nz} hexahedra"


def element_line(t, runs: str = "") -> tuple[str, str]:
    """A finite-element tank's liquid line: its mesh, mass, element (with `runs`, how the model runs
    it, and the loader's note where the scene left the element out: scene/shape.py default_element)
    and its slip walls."""
    why = runs + (f" (by default: {t.fluid.element_default})" if t.fluid.element_default else "")
    return (f"liquid in tank {t.name!r}", f"{shape_words(t)}{grid_words(t, short=True)}, {t.liquid_mass:.6g} kg, "
                                          f"element {t.fluid.element!r}{why}, {t.walls} walls (slip)")


def element_words(t, runs: str = "", flux: bool = False) -> TankWords:
    """A finite-element tank's words: `runs`, how its model runs the element (" at full order", " on
    8 modes"); `flux`, its wall faces follow elastic walls by their flux (the face-normal element)."""
    return TankWords(element_line(t, runs), elastic_walls_lines(t, flux), grid_words(t), "the sloshing modes",
                     "the linear liquid")


def elastic_walls_lines(t, flux: bool = False) -> tuple:
    """A finite-element tank's elastic walls ([tanks.walls]), as the deformable block holds them
    (none with rigid walls); `flux`: the face-normal element's wall faces follow them by their flux."""
    if not t.form.elastic:
        return ()
    return ((f"elastic walls of tank {t.name!r}",
             f"{t.wall_spec.thickness:g} m thick, {t.wall_mass:.6g} kg of elastic hexahedra built into the hull (the "
             "vessel's frame), the liquid tied to them in the normal direction only"
             + (": each wall face's flux is the volume the wall sweeps there" if flux else "")),)


def walls_words(t) -> str:
    """The tank's walls in `check`'s tank line: "slip", "no-slip", or elastic and how thick."""
    return f"elastic, {t.wall_spec.thickness:g} m thick" if t.form.elastic else t.walls


def wall_unknowns(t) -> int:
    """The free nodal dofs of a tank's elastic walls (none with rigid walls): the liquid's
    wall-normal dofs, or its wall faces' fluxes, follow theirs."""
    if not t.form.elastic:
        return 0
    _, _, _, held = shell_mesh(t.size, t.fill_depth, t.mesh, t.wall_spec.thickness, t.wall_spec.mesh)
    return 3 * int((~held).sum())
