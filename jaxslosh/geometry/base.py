"""The tank-shape interface: `AbstractShape`, which every final shape (geometry/box.py, prismatic.py,
cylinder.py, meshfile.py) implements, and the thin rigid plates (`Baffle`) that box and prismatic
tanks hold.

A shape is placed by its bounding box (`size`, tank-local coordinates from its inner min corner) and
owns everything that differs from one shape to another: reading its keys from the scene's tank
table, its checks, the liquid's volume at rest, its mesh (fem/shapes.TankMesh), its outline to draw,
its closed inner surface (stability), and the words `check` prints for it. Code elsewhere calls these
methods; it never asks which shape it holds. Shapes are frozen and hashable: meshes are cached by them.

The geometry sits below the scene loader: the loader hands it its field reader (`Reader`), so a
bad key raises the scene's error naming it, as every other key does.
"""
from __future__ import annotations

import abc
import functools
from dataclasses import dataclass
from typing import Callable, ClassVar, NamedTuple, Optional

import numpy as np

from ..fem.shapes import TankMesh

AXES = ("x", "y", "z")


class Reader(NamedTuple):
    """The scene's field reader (scene/fields.py), passed in by the loader."""
    read: Callable            # read(table, where, spec, required=()) -> {key: value}
    show: Callable            # a value as it reads in TOML
    one_of: Callable          # the check of a string among options
    error: type               # SceneError(key, message)


@dataclass(frozen=True)
class Baffle:
    normal: str            # "x" | "y": the plate is the plane normal to this axis
    at: float              # its position along that axis, tank-local, m
    mount: str             # "bottom" (standing) | "top" (hanging from the roof)
    height: float          # the plate's extent from the bottom up, or from the roof down, m


class AbstractShape(abc.ABC):
    """A tank's shape. Finals hold `size` (the bounding box, m) and `baffles` (a tuple of Baffle),
    and the fields of their own keys."""

    #: the value of the tank's `shape` key
    name: ClassVar[str]
    #: the tank-table keys only this shape reads (another shape's tank refuses them)
    keys: ClassVar[tuple] = ()
    #: whether elastic walls can be built round it
    elastic: ClassVar[bool] = False
    #: the baffle normals the shape takes (none: baffles are refused)
    baffle_normals: ClassVar[tuple] = ()
    #: whether the multimodal model (liquid/multimodal/) takes the shape, and its waves there
    #: when the tank leaves `flow` out
    modal: ClassVar[bool] = False
    modal_flow: ClassVar[str] = "2d"
    # the loader's default element on modes is "rt" (its higher modes at sloping and curved walls),
    # and at full order where the liquid touches such a wall (`sloped`)
    rt_on_modes: ClassVar[bool] = False

    size: tuple
    baffles: tuple

    # ------------------------------------------------------------------------------ reading
    @classmethod
    def read_fill_and_mesh(cls, table, v, where: str, base_dir: str, reader: Reader) -> None:
        """Set v["fill_depth"] and v["mesh"] where the shape gives them (a mesh file does)."""

    @classmethod
    def read(cls, table, v, where: str, base_dir: str, reader: Reader) -> "AbstractShape":
        """The shape of a tank table (`v`: its keys read so far, `fill_depth` and `mesh` among
        them), its own keys and its baffles read and the whole checked."""
        own = cls.read_own(table, v, where, base_dir, reader)
        shape = cls(size=tuple(v["size"]), baffles=read_baffles(table, v, where, reader), **own)
        shape.check_read(v, where, reader)
        bad = shape.check(v["fill_depth"], v["mesh"])
        if bad:
            raise reader.error(f"{where}.{bad[0]}", bad[1])
        return shape

    @classmethod
    def read_own(cls, table, v, where: str, base_dir: str, reader: Reader) -> dict:
        """The fields of the shape's own keys (`keys`)."""
        return {}

    def check_read(self, v, where: str, reader: Reader) -> None:
        """Refuse, naming the key, what the shape's reading finds wrong beyond `check`."""

    @classmethod
    def sketch(cls, table) -> "AbstractShape":
        """The shape from a tank table without checks, enough to draw its outline (a result whose
        scene no longer loads)."""
        return cls(size=tuple(table["size"]))

    def modal_base(self, rectangle, disk):
        """The base the multimodal model's waves run on, built by `rectangle(L, B)` or `disk(R)`
        (liquid/multimodal/modes.py: the geometry sits below it)."""
        raise ValueError(f'the multimodal model takes box and upright cylinder tanks, not shape = "{self.name}"')

    @classmethod
    def read_multimodal(cls, table, where: str, reader: Reader) -> None:
        """Refuse what the multimodal model cannot take in this shape."""

    # ------------------------------------------------------------------------------ checks
    def check(self, fill_depth: float, counts) -> Optional[tuple]:
        """(key, message) where the numbers cannot describe the shape, else None."""
        return self._check(fill_depth, counts) or self._check_baffles(fill_depth)

    def _check(self, fill_depth: float, counts) -> Optional[tuple]:
        return None

    def _check_baffles(self, h: float) -> Optional[tuple]:
        a, b, H = self.size
        for i, bf in enumerate(self.baffles):
            where = f"baffles[{i}]"
            if not self.baffle_normals:
                return where, f"baffles go into box and prismatic tanks; give a {self.name} tank with baffles as a mesh"
            if bf.normal not in ("x", "y"):
                return f"{where}.normal", f'must be "x" or "y" (the plate stands across that axis), got {bf.normal!r}'
            if bf.mount not in ("bottom", "top"):
                return f"{where}.from", f'must be "bottom" or "top", got {bf.mount!r}'
            ext = a if bf.normal == "x" else b
            if not 0 < bf.at < ext:
                return (f"{where}.position", f"must lie inside the tank (0 < position < {ext:g} m along "
                                             f"{bf.normal}), got {bf.at:g}")
            if bf.normal not in self.baffle_normals:
                return f"{where}.normal", f"a {self.name} tank's baffles stand across its length (normal = \"x\")"
            if not 0 < bf.height <= H:
                return f"{where}.height", f"must be in (0, {H:g}] m, got {bf.height:g}"
            if bf.mount == "top" and H - bf.height >= h:
                return f"{where}.height", "this hanging baffle does not reach the liquid"
        return None

    # ------------------------------------------------------------------------------ the liquid
    @property
    def plain_box(self) -> bool:
        """A box without baffles: the grid the fast paths (boxsolve, the traced fill depth) take."""
        return False

    @abc.abstractmethod
    def volume(self, fill_depth: float) -> float:
        """The liquid's volume at rest, exactly for the shape (a mesh file: its elements' volume)."""

    def mesh(self, fill_depth: float, counts, graded: bool = True) -> TankMesh:
        """The liquid at rest filled to `fill_depth` on `counts` = (nx, ny, nz) elements mapped onto
        the shape. Built once per shape, fill, counts and `graded` (`jaxslosh check` counts its
        unknowns, the build uses it); its arrays are shared: read them, do not write them. `graded`:
        the layers of a tank whose section has kinks (prismatic, baffles) thinner toward the surface,
        the face-normal element's mesh (fem/shapes.py `surface_layers`); False: spread in proportion
        to the bands between the kinks, the nodal elements' mesh (their one-point curl locks on thin
        layers at a top chamfer's kink). Other shapes have one mesh."""
        return _mesh(self, float(fill_depth), tuple(int(m) for m in counts), bool(graded))

    @abc.abstractmethod
    def _mesh(self, h: float, counts: tuple, graded: bool = True) -> TankMesh:
        """`mesh`, uncached."""

    def free_count(self, fill_depth: float, counts) -> int:
        """The liquid's unknowns in a tank of this shape."""
        return int(self.mesh(fill_depth, counts).free.sum())

    def box_counts(self, fill_depth: float):
        """The counts of the box grid this shape's liquid is, meshed as the box (a mesh file that is
        one), else None."""
        return None

    def sloped(self, fill_depth: float) -> bool:
        """Whether the liquid at rest touches a wall that is not along the tank's axes (the nodal
        elements then work in node frames, and the stabilized element's modes are off there)."""
        return False

    def locks(self, fill_depth: float) -> tuple[bool, str]:
        """(whether the stabilized element locks in this shape, why): the loader's default element."""
        if self.baffles:
            return True, "a tank with baffles"
        return False, ""

    def reentrant(self, fill_depth: float) -> tuple[bool, str]:
        """(whether the liquid at rest has re-entrant edges, what they are): there the nodal elements
        lose whole modes (docs/guide/liquid-element.md, "Why rt"), which the loader warns of. The
        shapes drawn from numbers are convex but for their baffles (each reaches into the liquid)."""
        n = len(self.baffles)
        return (True, f"{n} baffle{'s' if n > 1 else ''} in the liquid") if n else (False, "")

    # ------------------------------------------------------------------------------ drawing, words
    def outline(self, fill_depth: float, mesh=None) -> list:
        """The outline to draw: polylines (k, 3) in tank-local coordinates, each baffle's plate
        among them. `mesh` = (nodes, elements) of the liquid where a result keeps them (a mesh
        file's shape draws its feature edges from them; the others draw from their numbers)."""
        a, b, H = self.size
        lines = self._outline(fill_depth, mesh)
        for bf in self.baffles:
            z0, z1 = (0.0, bf.height) if bf.mount == "bottom" else (H - bf.height, H)
            if bf.normal == "x":
                lines.append(np.array([[bf.at, 0, z0], [bf.at, b, z0], [bf.at, b, z1], [bf.at, 0, z1],
                                       [bf.at, 0, z0]]))
            else:
                lines.append(np.array([[0, bf.at, z0], [a, bf.at, z0], [a, bf.at, z1], [0, bf.at, z1],
                                       [0, bf.at, z0]]))
        return [np.asarray(line, dtype=float) for line in lines]

    @abc.abstractmethod
    def _outline(self, fill_depth: float, mesh) -> list:
        """The shape's own polylines (the baffles apart)."""

    @abc.abstractmethod
    def surface(self) -> np.ndarray:
        """The closed inner surface (n, 3, 3), outward, tank-local: the container a level liquid
        fills at any heel (hull/tanks.py; baffles left out)."""

    def describe(self) -> str:
        """`check`'s words for the shape: "prismatic (chamfers ...) with 2 baffles" and the like."""
        words = self._describe()
        n = len(self.baffles)
        if n:
            words += f" with {n} baffle{'s' if n > 1 else ''}"
        return words

    def _describe(self) -> str:
        return self.name

    def notes(self, fill_depth: float, counts) -> list[str]:
        """`check`'s indented lines under the tank: each baffle as the model reads it (its plane,
        side and edge), then what the shape has to say (a nearly full horizontal cylinder, a mesh
        file's re-oriented hexahedra)."""
        out = []
        H = self.size[2]
        for i, b in enumerate(self.baffles):
            edge = b.height if b.mount == "bottom" else H - b.height
            side = ("standing on the bottom, its upper edge" if b.mount == "bottom"
                    else "hanging from the roof, its lower edge")
            out.append(f"  baffle {i}: the plane {b.normal} = {b.at:g} m from the tank's origin, {side} {edge:g} m "
                       f"above the tank bottom ({b.height:g} m of plate)")
        return out + self._notes(fill_depth, counts)

    def _notes(self, fill_depth: float, counts) -> list[str]:
        return []

    def mesh_words(self) -> Optional[str]:
        """`check`'s words for a mesh whose counts along x, y, z mean nothing, else None."""
        return None


@functools.lru_cache(maxsize=16)
def _mesh(shape: AbstractShape, h: float, counts: tuple, graded: bool) -> TankMesh:
    return shape._mesh(h, counts, graded)


def read_baffles(table, v, where: str, reader: Reader) -> tuple:
    """The tank's [[tanks.baffles]], each as a Baffle (its extent from the bottom up or from the roof
    down); the shape's `check` then says whether it takes them."""
    show = reader.show
    H = v["size"][2]
    baffles = []
    for i, b in enumerate(table.get("baffles", [])):
        bw = f"{where}.baffles[{i}]"
        _old_baffle_keys(b, bw, H, reader)
        bv = reader.read(b, bw, {"normal": ("str", reader.one_of(("x", "y"))), "position": ("float", None),
                                 "from": ("str", reader.one_of(("bottom", "top"))), "height": ("float", None)},
                         required=("position", "height"))
        mount, edge = bv.get("from", "bottom"), bv["height"]
        if mount == "bottom" and not 0 < edge <= H:
            raise reader.error(f"{bw}.height", f"a standing plate's upper edge must be in (0, {show(H)}] m above "
                                               f"the tank bottom, got {show(edge)}")
        if mount == "top" and not 0 <= edge < v["fill_depth"]:
            raise reader.error(f"{bw}.height", f"a hanging plate's lower edge must be below the free surface "
                                               f"({show(v['fill_depth'])} m above the bottom) and >= 0, got {show(edge)}")
        baffles.append(Baffle(normal=bv.get("normal", "x"), at=bv["position"], mount=mount,
                              height=edge if mount == "bottom" else H - edge))
    return tuple(baffles)


def _old_baffle_keys(b, bw: str, H: float, reader: Reader) -> None:
    """An earlier form (`at`, `mount`, `height` as the plate's extent from the bottom or the roof) is
    refused with its translation to the keys of docs/guide/baffles.md: its `height` means another length, so reading it
    silently either way would put the edge where the user did not mean it."""
    if not isinstance(b, dict) or not ({"at", "mount"} & set(b)):
        return
    show = reader.show
    key = "at" if "at" in b else "mount"
    mount = b.get("mount", b.get("from", "bottom"))
    parts = []
    if "at" in b:
        parts.append(f"position = {show(b['at'])} (for at)")
    if "mount" in b:
        parts.append(f'from = "{mount}" (for mount)')
    extent = b.get("height")
    if isinstance(extent, (int, float)) and not isinstance(extent, bool) and mount in ("bottom", "top"):
        edge = extent if mount == "bottom" else H - extent
        which = "upper" if mount == "bottom" else "lower"
        parts.append(f"height = {edge:g} (the plate's {which} edge above the tank bottom; the old height "
                     f"{show(extent)} was the plate's extent from the {'bottom' if mount == 'bottom' else 'roof'})")
    else:
        parts.append("height = the edge's height above the tank bottom (the old height was the plate's extent)")
    raise reader.error(f"{bw}.{key}", "an old form of the baffle keys; write " + ", ".join(parts))
