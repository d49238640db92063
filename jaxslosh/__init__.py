"""jaxslosh: a differentiable JAX simulator of floating vessels carrying sloshing liquid.

The method is Gonzalez & Park, "Coupled analysis of nonlinear structural motion and fluid
sloshing" (2013). Entry points switch on float64 (`jax_enable_x64`); a library user should too:

    import jax; jax.config.update("jax_enable_x64", True)
    import jaxslosh as js
    result = js.simulate(js.load_scene("scenes/paper_ship_tank.toml"))

The package's layers, lowest first (README "Design"): scene/ (TOML to a Scene), fem/ and hydro/
(host-side models), physics/ (traced terms), solve/ (schemes, Newton, linear solvers), build/
(scene to System), run/ (time loop), io/ (files), analysis/, campaign/, fit/, plot/, cli/.
"""
from ._version import __version__
from .analysis.modes import sloshing_modes, structure_modes
from .analysis.rao import rao
from .campaign.run import campaign
from .fit.identify import identify
from .io.result import Result, load_result, save_result
from .io.status import Status
from .run.batch import simulate_batch
from .run.simulate import NumericalFailure, simulate
from .run.stepper import Stepper
from .scene import Scene, SceneError, load_scene

__all__ = ["structure_modes", "Scene", "SceneError", "Result", "NumericalFailure", "load_scene", "simulate", "save_result",
           "load_result", "sloshing_modes", "identify", "simulate_batch", "Stepper", "Status", "rao", "campaign",
           "__version__"]
