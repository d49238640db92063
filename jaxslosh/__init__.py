"""jaxslosh: a differentiable JAX simulator of floating vessels carrying sloshing liquid.

The method is Gonzalez & Park, "Coupled analysis of nonlinear structural motion and fluid
sloshing" (2013). Entry points switch on float64 (`jax_enable_x64`); a library user should too:

    import jax; jax.config.update("jax_enable_x64", True)
    import jaxslosh as js
    result = js.simulate(js.load_scene("scenes/paper_ship_tank.toml"))

The package's layers, lowest first (docs/design.md): _version.py, staging.py; fem/mesh.py,
fem/meshfile.py, fem/slip.py, physics/kinematics.py, solve/schemes.py; fem/shapes.py; hull/;
geometry/; hydro/, io/; scene/; fem/; physics/; mooring/; solve/; liquid/; assemble/; run/; cache/;
analysis/, campaign/, fit/, mooring/statics.py; plot/; cli/; entry.py; __init__.py, __main__.py.

The public names below are imported on first use (PEP 562): `import jaxslosh` stays light, and a
command such as `jaxslosh run` loads neither Dask nor SciPy's signal and statistics modules, which
only campaigns and fits need (a second run of a scene starts in seconds: docs/guide/compilation-cache.md).
"""
from importlib import import_module

# the campaign sub-package (its __init__ imports nothing) is bound now, so that the function
# `campaign` below keeps its name when a module of the sub-package is imported later
from . import campaign as _campaign_package  # noqa: F401
from . import mooring as _mooring_package  # noqa: F401
from ._version import __version__

#: public name -> the module that defines it
_PUBLIC = {
    "sloshing_modes": ".analysis.modes", "structure_modes": ".analysis.modes", "rao": ".analysis.rao",
"identify": ".fit.identify", "Result": ".io.result", "load_result": ".io.result",
    "save_result": ".io.result", "Status": ".io.status", "RunResult": ".io.status", "simulate_batch": ".run.batch",
    "NumericalFailure": ".run.simulate", "simulate": ".run.simulate", "Stepper": ".run.stepper", "Scene": ".scene",
    "SceneError": ".scene", "load_scene": ".scene", "scene_with": ".scene.variant", "stability": ".analysis.stability",
    "catenary": ".mooring.catenary",
}

__all__ = [*_PUBLIC, "campaign", "mooring", "__version__"]


def campaign(*args, **kwargs):
    """`js.campaign`: jaxslosh.campaign.run.campaign (docs/guide/campaigns.md), imported on first call
    (it loads Dask)."""
    _install_cache()
    return import_module(".campaign.run", __name__).campaign(*args, **kwargs)


def mooring(*args, **kwargs):
    """`js.mooring`: jaxslosh.mooring.statics.mooring (docs/guide/moorings.md), imported on first call
    (the name is also the sub-package's, bound above, as for `campaign`)."""
    _install_cache()
    return import_module(".mooring.statics", __name__).mooring(*args, **kwargs)


def _install_cache():
    """The package's functions are an entry point, as the command line is: their programs go
    through the compile cache (jaxslosh/cache, installed here on first use, not on import)."""
    import_module(".cache.programs", __name__).install()


def __getattr__(name):
    if name in _PUBLIC:
        if not _PUBLIC[name].startswith((".scene", ".io")):     # what only reads and writes needs no JAX
            _install_cache()
        value = getattr(import_module(_PUBLIC[name], __name__), name)
        globals()[name] = value           # looked up once
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_PUBLIC))
