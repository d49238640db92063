"""jaxslosh: a differentiable JAX simulator of floating vessels carrying sloshing liquid.

The method is Gonzalez & Park, "Coupled analysis of nonlinear structural motion and fluid
sloshing" (2013). Entry points switch on float64 (`jax_enable_x64`); a library user should too:

    import jax; jax.config.update("jax_enable_x64", True)
    import jaxslosh as js
    result = js.simulate(js.load_scene("scenes/paper_ship_tank.toml"))
"""
__version__ = "0.1.0"

from .scene import load_scene  # noqa: E402
from .scene_types import Scene, SceneError  # noqa: E402
from .result import Result, load_result, save_result  # noqa: E402
from .run import NumericalFailure, simulate, simulate_batch  # noqa: E402
from .identify import identify  # noqa: E402


def sloshing_modes(scene, tank=None, n=10):
    """Natural modes of a tank's liquid with the vessel held fixed (see modes.py)."""
    from .analysis import sloshing_modes as _sm
    return _sm(scene, tank=tank, n=n)


def structure_modes(scene, structure, n=10):
    """Natural modes of a flexible structure held at its attachment (see analysis.py)."""
    from .analysis import structure_modes as _sm
    return _sm(scene, structure, n=n)


__all__ = ["structure_modes", "Scene", "SceneError", "Result", "NumericalFailure", "load_scene", "simulate", "save_result",
           "load_result", "sloshing_modes", "identify", "simulate_batch", "__version__"]
