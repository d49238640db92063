"""A tank's shape keys (docs/guide/tanks-and-shapes.md: `shape`, `chamfers`, `axis`, `file`, `[[tanks.baffles]]`): the
shape's class (jaxslosh/geometry) reads and checks its own; here what is common to them all."""
from __future__ import annotations


from ..geometry import SHAPES, AbstractShape, Reader
from .fields import one_of, read, show
from .types import SceneError

def _read(table, where, spec, required=()):
    return read(table, where, spec, required)          # this module's `read` when called (the docs' test spies on it)


#: the scene's field reader, handed to the shapes (they sit below the scene)
READER = Reader(read=_read, show=show, one_of=one_of, error=SceneError)


def shape_class(v) -> type[AbstractShape]:
    return SHAPES[v.get("shape", "box")]


def read_shape(table, v, where: str, base_dir: str, elastic: bool = False) -> tuple[dict, AbstractShape]:
    """The tank's shape, checked, and its keys as the Tank holds them: {shape, chamfers, axis, file,
    baffles}."""
    cls = shape_class(v)
    if elastic and (not cls.elastic or "baffles" in table):
        raise SceneError(f"{where}.walls", "elastic walls are built for box tanks without baffles only")
    for other in SHAPES.values():
        for key in other.keys:
            if key in table and other is not cls:
                raise SceneError(f"{where}.{key}", f'belongs to shape = "{other.name}" tanks; this tank is '
                                                   f'shape = "{cls.name}"')
    geo = cls.read(table, v, where, base_dir, READER)
    out = {"shape": cls.name, "chamfers": getattr(geo, "chamfers", ((0.0, 0.0), (0.0, 0.0))),
           "axis": v.get("axis", "x"), "file": getattr(geo, "file", ""), "baffles": geo.baffles}
    return out, geo


def fill_and_mesh(table, v, where: str, base_dir: str) -> None:
    """Set v["fill_depth"] and v["mesh"]: required keys, except where the shape gives them (docs/guide/tank-meshes.md:
    a mesh tank's file gives both)."""
    shape_class(v).read_fill_and_mesh(table, v, where, base_dir, READER)
    for key in ("fill_depth", "mesh"):
        if key not in v:
            raise SceneError(f"{where}.{key}", "a required key is missing")


def read_multimodal_shape(table, where: str) -> None:
    """What the multimodal model refuses in the tank's shape (read before the shape's own keys)."""
    cls = SHAPES.get(table.get("shape", "box"))
    if cls is not None:
        cls.read_multimodal(table, where, READER)


def default_element(geo: AbstractShape, fill_depth, mesh, reduced: bool) -> tuple[str, str]:
    """(element, why) for a tank whose [tanks.fluid] leaves `element` out: the face-normal "rt" where
    the stabilized element locks (a mesh file that is not a box grid, a tank with baffles: issue 30);
    "rt" for prismatic and cylindrical tanks on modes ([tanks.reduction]) and, at full order, where
    their liquid touches a sloping or curved wall (the stabilized element's modes are off there, an
    LNG section's first by +16 % at 30 % fill: docs/guide/liquid-element.md); else "stabilized"
    (boxes keep their fast diagonalization, and a prismatic tank whose liquid touches no chamfer is
    a box)."""
    locks, why = geo.locks(float(fill_depth))
    if not locks:
        if geo.rt_on_modes and reduced:
            return "rt", f"a {geo.name} tank on modes: its higher modes are more accurate with \"rt\""
        if geo.rt_on_modes and geo.sloped(float(fill_depth)):
            return "rt", (f"a {geo.name} tank whose liquid touches sloping or curved walls: the stabilized "
                          "element's modes are off there")
        return "stabilized", why
    return "rt", f"{why}: the stabilized element locks there"
