"""What every command shares: exit codes, the one-line input error, the scene loader that prints
its warnings. The library raises (SceneError, NumericalFailure); the commands turn that into
messages and exit codes.

This module imports no JAX (nor what imports it): the command line reads and checks a scene before
JAX is imported (jaxslosh/entry.py), and `setup_jax` imports it."""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from importlib import import_module

from ..cache.executables import cache_folder
from ..io.output import OutputError, check_output
from ..scene.keys import with_overrides
from ..scene.load import load_scene
from ..scene.types import Scene, SceneError

#: exit statuses (docs/guide/exit-status-and-warnings.md): done, bad input (one line), numerical
#: failure; interrupted by a signal (128 + SIGINT, the shell's convention); the output could not be
#: written (a full disk)
EXIT_OK, EXIT_INPUT, EXIT_NUMERICAL, EXIT_INTERRUPTED, EXIT_IO = 0, 2, 3, 130, 1


class InputError(Exception):
    """Bad command-line input: one line on stderr, exit status 2."""


#: every command: the module (jaxslosh/cli/<module>.py, whose cmd_<command> runs it) and its help. main.py
#: imports only the module of the command asked for, so `jaxslosh run` loads neither Dask nor SciPy's
#: signal and statistics modules (docs/guide/compilation-cache.md: what a run costs before its first step)
COMMANDS = {
    "run": ("simulate", "simulate a scene, write the result file"),
    "check": ("simulate", "validate a scene; list what it will simulate and what it will cost"),
    "plot": ("plot", "time histories of a result: roll, pitch, heave and every probe "
                     "(of a sweep file: every run overlaid)"),
    "modes": ("modes", "natural frequencies of a tank's liquid, or of a flexible structure, with the vessel held fixed"),
    "identify": ("identify", "fit scene values (dotted keys) to a measured result"),
    "sweep": ("sweep", "run a grid of parameter values as one batch, write one file"),
    "hydro": ("hydro", "hull hydrostatics and hydrodynamic tables from Capytaine, as scene TOML"),
    "rao": ("rao", "response amplitude operators of the vessel and the probes, from the scene linearised about rest"),
    "export": ("export", "write a result for ParaView (XDMF 3 time series over one HDF5 file)"),
    "campaign": ("campaign", "run a scatter of sea states x headings x seeds on Dask, write statistics"),
    "stability": ("stability", "GZ curves (liquids frozen and level), GM0, vanishing angle, IS Code 2008 criteria"),
    "mooring": ("mooring", "mooring lines: static equilibrium, tensions, stiffness matrix, offset curve"),
}


def read(load, path):
    """`load(path)` for a command: a file that is not of the kind asked for, or cannot be read, is
    bad input (one line naming the file and the fault; exit 2)."""
    # imported with the command (it imports JAX), not with this module
    ResultFileError = import_module("..io.result", __package__).ResultFileError
    try:
        return load(path)
    except ResultFileError as e:
        raise InputError(str(e)) from None


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage block
        raise InputError(f"{self.prog}: {message}")


#: the cache folder's size limit, in megabytes (executables.cache_folder: where the folder is)
CACHE_MAX_ENV = "JAXSLOSH_CACHE_MAX_MB"


def setup_jax():
    """float64, JAX's persistent compilation cache and the exported programs beside it (cache/programs.py):
    a second run of a scene skips tracing and XLA."""
    import jax

    programs = import_module("..cache.programs", __package__)
    programs.install()          # the command line is an entry point: its programs go through the cache
    jax.config.update("jax_enable_x64", True)
    d, kept = cache_folder()
    limit = cache_max_bytes() if d is not None else None     # a bad limit changes nothing
    programs.use(kept)
    if d is None:
        return
    jax.config.update("jax_compilation_cache_dir", d)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", -1)
    programs.trim(d, limit)


def cache_max_bytes() -> int:
    """The cache folder's size limit: $JAXSLOSH_CACHE_MAX_MB megabytes, 2048 by default (a few
    hundred scenes' programs and models; one program of the mast scene, with its executable, is
    about 5 MB)."""
    v = os.environ.get(CACHE_MAX_ENV, "")
    try:
        mb = float(v) if v else 2048.0
    except ValueError:
        raise InputError(f"{CACHE_MAX_ENV}: must be a number of megabytes, got {v!r}") from None
    if not mb > 0:
        raise InputError(f"{CACHE_MAX_ENV}: must be a positive number of megabytes, got {v!r}")
    return int(mb * (1 << 20))


#: the scene jaxslosh/entry.py read before JAX was imported (`read_first`): (path, the file's size and
#: time) -> the scene. The command's own `load` takes it from here, once
_READ_FIRST: dict = {}


def _stamp(path):
    try:
        st = os.stat(path)
    except OSError:
        return None                     # load_scene says what is wrong with the path
    return os.path.abspath(path), st.st_size, st.st_mtime_ns


def read_first(path) -> Scene:
    """Read and check a command's scene before JAX is imported (jaxslosh/entry.py): a bad scene is
    answered in a second (SceneError), a good one is kept for the command's `load`."""
    scene = load(path)
    stamp = _stamp(path)
    if stamp is not None:
        _READ_FIRST[stamp] = scene
    return scene


def load(path) -> Scene:
    """The scene, its warnings printed to stderr (once: the scene `read_first` read, from a file
    unchanged since, is that scene)."""
    if _READ_FIRST:
        scene = _READ_FIRST.pop(_stamp(path), None)
        _READ_FIRST.clear()
        if scene is not None:
            return scene
    scene = load_scene(path)
    for w in scene.warnings:
        print(f"warning: {w}", file=sys.stderr)
    return scene


def positive(name, value):
    """A number argument must be positive and finite (argparse's float takes "nan" and "inf")."""
    if value is not None and not (value > 0 and math.isfinite(value)):
        raise InputError(f"--{name}: must be a positive finite number, got {value}")


def output_folder(flag, path, scene=None):
    """The file a command is to write, checked before any computing: not a folder, not the scene
    file (`scene`), in a folder that exists and takes a new file (a file is created there and
    removed: permissions alone do not tell, e.g. for root or on a read-only file system)."""
    if not path:
        return
    if os.path.isdir(path):
        raise InputError(f"{flag}: {path} is a folder; name the file to write")
    if scene and os.path.exists(path) and os.path.exists(scene) and os.path.samefile(path, scene):
        raise InputError(f"{flag}: {path} is the scene file; name another file to write")
    d = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(d):
        raise InputError(f"{flag}: the folder {d} does not exist")
    try:
        with tempfile.TemporaryFile(dir=d):
            pass
    except OSError as e:
        raise InputError(f"{flag}: cannot write in the folder {d} ({e.strerror})") from None
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise InputError(f"{flag}: {path} exists and cannot be written")


#: the image formats a figure is written in (matplotlib's Agg canvas); a name without an extension
#: gets DEFAULT_FIGURE's (and the command says the name it wrote)
FIGURE_FORMATS = ("png", "pdf", "svg", "svgz", "jpg", "jpeg", "tif", "tiff", "webp", "eps", "ps", "pgf", "gif",
                  "avif", "raw", "rgba")
DEFAULT_FIGURE = "png"


def figure_file(flag, path):
    """The figure file a command is to write, checked before any computing (output_folder): its
    extension names one of FIGURE_FORMATS (else exit 2 at once: matplotlib would refuse it only once
    the figure is drawn); a name without one gets ".png", and that is the name returned."""
    if not path:
        return path
    if os.path.isdir(path):
        output_folder(flag, path)           # a folder is refused as such, not given an extension
    ext = os.path.splitext(path)[1]
    if not ext:
        path = path + "." + DEFAULT_FIGURE
    elif ext[1:].lower() not in FIGURE_FORMATS:
        raise InputError(f"{flag}: {path}: {ext!r} is not an image format; name the figure with one of "
                         f".{', .'.join(FIGURE_FORMATS[:9])} (or no extension for .{DEFAULT_FIGURE})")
    output_folder(flag, path)
    return path


def writable_output(flag, path, inputs=()) -> bool:
    """Check an output file before any computing (io.output.check_output); True when an existing
    jaxslosh file will be replaced."""
    output_folder(flag, path, scene=inputs[0] if inputs else None)
    try:
        return check_output(path, inputs) is not None
    except OutputError as e:
        raise InputError(f"{flag}: {e.strerror}") from None


def overridden(scene: Scene, a) -> Scene:
    """The scene with the command line's --duration and --dt folded in (once, here)."""
    try:
        new = with_overrides(scene, duration=getattr(a, "duration", None), dt=getattr(a, "dt", None))
    except SceneError as e:
        flag = "--dt" if e.key == "simulation.dt" else "--duration"
        raise InputError(f"{flag}: {str(e).split(': ', 1)[1]}") from None
    for w in new.warnings:
        if w not in scene.warnings:
            print(f"warning: {w}", file=sys.stderr)
    return new
