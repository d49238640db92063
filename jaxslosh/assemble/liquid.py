"""The stacked liquid block of a scene's tanks (jaxslosh/liquid LiquidBlock): each tank's model and
the one form of their block are the liquid's to decide (liquid/forms.py), each form's builder its
model's sub-package; here the scene's switches and the structures the vessel's frame carries."""
from __future__ import annotations

from typing import Optional

from ..liquid.base import NoLiquid
from ..liquid.block import LiquidBlock, TankBlock, VesselFrameStructure, rigid_part  # noqa: F401 (the assembly's names)
from ..liquid.face.stack import wall_node_count  # noqa: F401
from ..liquid.forms import block_form, outline_block, tank_models
from ..liquid.nodal.sparse import SPARSE_AUTO
from ..scene.types import Scene
from .effects import liquid_unknowns
from .structures import held_spin_stiffness, held_structure


def build_liquid_block(scene: Scene, params: Optional[dict] = None, gravity=None, include_liquid=True):
    """The stacked liquid block of all tanks. `params` (canonical keys) may replace each tank's
    fill depth, density and sound speed, and `gravity` the scene's, by traced values: then the
    matrices are JAX values (the integer mesh, the free dofs and the probes' host-side geometry
    stay NumPy). The probes' tank blocks hold the mesh at the scene's fill depth whatever the params
    say (liquid/block.py host_block), so their weights do not depend on a traced fill depth."""
    tanks = list(scene.tanks) if include_liquid else []
    in_vessel_frame = [s for s in scene.structures if s.frame == "vessel"]
    if not tanks and not in_vessel_frame:
        return LiquidBlock(NoLiquid())
    params = params or {}
    g = scene.environment.gravity if gravity is None else gravity
    sparse = wants_sparse(scene)
    models = tank_models(scene, tanks, params, g, sparse)
    build = block_form(tanks, models, bool(in_vessel_frame), sparse)
    held = [held_structure(st) for st in in_vessel_frame]
    return build(scene, tanks, models, params, g, sparse, held, held_spin_stiffness(held))


def wants_sparse(scene) -> bool:
    """Whether the scene's liquid goes the sparse way (`simulation.linear_solver`)."""
    choice = scene.simulation.linear_solver
    if choice != "auto":
        return choice in ("sparse", "sparse-host")
    if any(t.form.dense_blocks for t in scene.tanks):
        return False
    return liquid_unknowns(scene) > SPARSE_AUTO


def outline_liquid_block(scene: Scene, gravity, include_liquid: bool = True) -> LiquidBlock:
    """`build_liquid_block`'s terms without their arrays (liquid/forms.py outline_block), for
    `jaxslosh check`."""
    tanks = list(scene.tanks) if include_liquid else []
    return outline_block(tanks, [s for s in scene.structures if s.frame == "vessel"], gravity)
