"""Tank shapes: an abstract shape (geometry/base.py) and its final box, prismatic, cylinder and mesh
file; each reads its keys, checks itself, gives its liquid's volume, mesh, outline, inner surface and
`check`'s words. Below the scene loader, which builds one per tank (`Tank.geometry`)."""
from .base import AXES, AbstractShape, Baffle, Reader
from .box import Box
from .cylinder import Cylinder
from .meshfile import MeshFile
from .prismatic import Prismatic

#: the shapes by the value of a tank's `shape` key, in the order docs/reference/scene.md lists them
SHAPES = {cls.name: cls for cls in (Box, Prismatic, Cylinder, MeshFile)}

__all__ = ["AXES", "AbstractShape", "Baffle", "Box", "Cylinder", "MeshFile", "Prismatic", "Reader", "SHAPES"]
