"""What every command shares: exit codes, the one-line input error, the scene loader that prints
its warnings. The library raises (SceneError, NumericalFailure); the commands turn that into
messages and exit codes."""
from __future__ import annotations

import argparse
import os
import sys
import tempfile

import jax

from ..scene.keys import with_overrides
from ..scene.load import load_scene
from ..scene.types import Scene, SceneError

EXIT_OK, EXIT_INPUT, EXIT_NUMERICAL = 0, 2, 3


class InputError(Exception):
    """Bad command-line input: one line on stderr, exit status 2."""


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage block
        raise InputError(f"{self.prog}: {message}")


def enable_x64():
    jax.config.update("jax_enable_x64", True)


def load(path) -> Scene:
    """The scene, its warnings printed to stderr."""
    scene = load_scene(path)
    for w in scene.warnings:
        print(f"warning: {w}", file=sys.stderr)
    return scene


def positive(name, value):
    if value is not None and not (value > 0):
        raise InputError(f"--{name}: must be positive, got {value}")


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


def overridden(scene: Scene, a) -> Scene:
    """The scene with the command line's --duration and --dt folded in (once, here)."""
    try:
        return with_overrides(scene, duration=getattr(a, "duration", None), dt=getattr(a, "dt", None))
    except SceneError as e:
        flag = "--dt" if e.key == "simulation.dt" else "--duration"
        raise InputError(f"{flag}: {str(e).split(': ', 1)[1]}") from None
