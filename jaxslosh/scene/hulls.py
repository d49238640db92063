"""The kinds of `[vessel.hull]`: an abstract `Hull` and one final class per value of its `type` key
(`HULLS`, the registry the loader reads). As in Capytaine, a box is the mesh a function makes:
every hull answers the same questions (its closed surface, its wetted mesh for Capytaine, its
still water plane, its words), and the code that uses a hull asks it instead of asking which kind
it is. The fields are one record for both kinds (a kind leaves the other's at their defaults), so
that `dataclasses.replace` and the scene comparison see the same keys as before the kinds.
"""
from __future__ import annotations

import abc
import math
import os
from dataclasses import dataclass, field
from typing import ClassVar, Optional, final

import numpy as np

from ..hull.box import box_hull
from ..hull.surface import hull_mesh_file
from ..hydro.box import box_hydrostatics, froude_krylov_box
from ..hydro.spectra import wavenumber

#: box panels per shortest wave length (the wave pressure's quadrature and tangent planes)
PANELS_PER_WAVELENGTH = 12
#: at most this many cells along a box edge
MAX_DIVISIONS = 48


@dataclass(frozen=True)
class Hull(abc.ABC):
    """The `[vessel.hull]` table: a box (length x beam x draft, centred on the COG in plan, the COG
    `kg` above the keel) or a mesh file (waterline at z = 0, COG at `cog`)."""
    type: str = field(default="", init=False)   # the `type` key's value (each final kind sets its own)
    length: float = 0.0
    beam: float = 0.0
    draft: float = 0.0
    kg: float = 0.0                  # m, COG above the keel (box)
    file: str = ""                   # mesh file (type = "mesh"), relative to the scene's folder
    cog: tuple[float, float, float] = (0.0, 0.0, 0.0)   # the COG in the mesh's coordinates (type = "mesh")
    depth: Optional[float] = None    # m, keel to deck (docs/guide/large-angles.md): large angles immerse the deck edge
    base_dir: str = ""               # the scene's folder (a mesh file is relative to it)

    #: whether the hydrostatics and the Froude-Krylov forces have closed forms (hydro/box.py);
    #: without them a hull is read by Capytaine or by the nonlinear hydrostatics
    closed_form: ClassVar[bool] = False

    def path(self) -> str:
        return self.file if os.path.isabs(self.file) else os.path.join(self.base_dir, self.file)

    @abc.abstractmethod
    def triangles(self, divisions=(1, 1, 1)):
        """The closed surface (n, 3, 3) in the vessel frame; HullMeshError names a bad file."""

    @abc.abstractmethod
    def water_height(self) -> float:
        """The still water plane's height in the vessel frame at rest (the COG at the origin)."""

    @abc.abstractmethod
    def divisions(self, waves) -> tuple:
        """Cells along the surface's edges that the wave pressure of `waves` (None: still water) needs."""

    @abc.abstractmethod
    def capytaine_mesh(self, cpt, panel_size=None, resolution=None, base_dir=""):
        """(Capytaine's mesh of the hull about the COG, the waterline's height above the COG): a box's
        panels of `panel_size` or `resolution` (along, across, down), a mesh file's own (a relative
        file is in `base_dir`, where given)."""

    @abc.abstractmethod
    def closed_hydrostatics(self) -> Optional[dict]:
        """The `[vessel.hydrostatics]` values in closed form (None where there are none)."""

    @abc.abstractmethod
    def froude_krylov(self, omega, heading, rho, g, depth=None):
        """X (N, 6) complex per unit amplitude in closed form (None where there is none)."""

    @abc.abstractmethod
    def cog_key(self) -> tuple[str, object]:
        """(dotted key, value) of the COG against the hull: what `params` may trace."""

    @abc.abstractmethod
    def span(self) -> Optional[float]:
        """The hull's largest horizontal size (None where it is not known without the mesh)."""

    @abc.abstractmethod
    def default_cog_height(self) -> float:
        """The COG's height above the still water when `vessel.cog_height` is not given."""

    def extent(self) -> tuple:
        """((x_min, y_min, z_min), (x_max, y_max)) of the hull in the vessel frame: its plan's bounds
        and its keel (the connection points' check, scene/bodies.py); HullMeshError names a bad file."""
        pts = np.asarray(self.triangles(), dtype=float).reshape(-1, 3)
        return tuple(float(c) for c in pts.min(axis=0)), tuple(float(c) for c in pts.max(axis=0)[:2])

    @abc.abstractmethod
    def describe(self) -> str:
        """The hull in a few words."""


@final
@dataclass(frozen=True)
class BoxHull(Hull):
    """`type = "box"`: the box of `box_hull` (with its deck where `depth` is given)."""
    type: str = field(default="box", init=False)
    closed_form: ClassVar[bool] = True

    def triangles(self, divisions=(1, 1, 1)):
        return box_hull(self.length, self.beam, self.kg, self.depth, divisions)

    def water_height(self) -> float:
        return self.draft - self.kg

    def divisions(self, waves) -> tuple:
        """One cell in still water (the clipping is exact on any box), else panels of a twelfth of
        the shortest wave length of the sea (or finer vertically, where the pressure decays as exp(k z))."""
        if waves is None:
            return (1, 1, 1)
        # the top of an irregular sea's frequency range, not its highest drawn component: the panels
        # then do not depend on the seed, and a campaign's cases share their model (and its compilation)
        lam = 2.0 * math.pi / float(np.max(wavenumber(np.array([waves.band[1]]), 9.81, waves.depth)))
        size = lam / PANELS_PER_WAVELENGTH
        n = [min(MAX_DIVISIONS, max(1, math.ceil(s / size))) for s in (self.length, self.beam, self.depth)]
        n[2] = max(n[2], 4)
        return tuple(n)

    def capytaine_mesh(self, cpt, panel_size=None, resolution=None, base_dir=""):
        L, B, T = self.length, self.beam, self.draft
        size = panel_size or max(min(L, B, T) / 4.0, max(L, B) / 24.0)
        res = resolution or tuple(max(2, int(np.ceil(x / size))) for x in (L, B, 2 * T))
        z_wl = T - self.kg
        return cpt.mesh_parallelepiped(size=(L, B, 2 * T), center=(0.0, 0.0, z_wl), resolution=res,
                                       name="hull"), z_wl

    def closed_hydrostatics(self) -> dict:
        return box_hydrostatics(self.length, self.beam, self.draft, self.kg)

    def froude_krylov(self, omega, heading, rho, g, depth=None):
        return froude_krylov_box(omega, heading, self.length, self.beam, self.draft, self.kg, rho, g, depth)

    def cog_key(self) -> tuple[str, object]:
        return "vessel.hull.kg", self.kg

    def span(self) -> float:
        return max(self.length, self.beam)

    def default_cog_height(self) -> float:
        return self.kg - self.draft

    def extent(self) -> tuple:
        # without the mesh: the box's deck may be absent (no `depth`)
        return (-self.length / 2, -self.beam / 2, -self.kg), (self.length / 2, self.beam / 2)

    def describe(self) -> str:
        return f"box {self.length:g} x {self.beam:g} x {self.depth:g} m (deck included)"


@final
@dataclass(frozen=True)
class MeshHull(Hull):
    """`type = "mesh"`: a mesh file in its own coordinates, the waterline at z = 0, the COG at `cog`."""
    type: str = field(default="mesh", init=False)

    def triangles(self, divisions=(1, 1, 1)):
        return hull_mesh_file(self.path(), self.cog, self.file)

    def water_height(self) -> float:
        return -float(self.cog[2])

    def divisions(self, waves) -> tuple:
        return (1, 1, 1)             # the file's own panels

    def capytaine_mesh(self, cpt, panel_size=None, resolution=None, base_dir=""):
        path = self.file if os.path.isabs(self.file) or not base_dir else os.path.join(base_dir, self.file)
        # the mesh's coordinates: waterline at z = 0; our origin is the COG at `cog`
        mesh = cpt.load_mesh(path).translated(tuple(-np.asarray(self.cog)))
        return mesh, -float(self.cog[2])

    def closed_hydrostatics(self) -> None:
        return None

    def froude_krylov(self, omega, heading, rho, g, depth=None):
        return None

    def cog_key(self) -> tuple[str, object]:
        return "vessel.hull.cog", self.cog

    def span(self) -> None:
        return None

    def default_cog_height(self) -> float:
        return 0.0

    def describe(self) -> str:
        return f"mesh {self.file}"


#: the `type` key's values and their kinds (the loader reads this)
HULLS = {"box": BoxHull, "mesh": MeshHull}
