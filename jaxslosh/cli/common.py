"""What every command shares: exit codes, the one-line input error, the scene loader that prints
its warnings. The library raises (SceneError, NumericalFailure); the commands turn that into
messages and exit codes."""
from __future__ import annotations

import argparse
import math
import os
import sys

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
    """A number argument must be positive and finite (argparse's float takes "nan" and "inf")."""
    if value is not None and not (value > 0 and math.isfinite(value)):
        raise InputError(f"--{name}: must be a positive finite number, got {value}")


def output_folder(flag, path):
    """The file to be written must not be a folder, and its folder must exist (checked before any
    computing)."""
    if path:
        if os.path.isdir(path):
            raise InputError(f"{flag}: {path} is a folder; give a file name")
        d = os.path.dirname(os.path.abspath(path))
        if not os.path.isdir(d):
            raise InputError(f"{flag}: the folder {d} does not exist")


def overridden(scene: Scene, a) -> Scene:
    """The scene with the command line's --duration and --dt folded in (once, here)."""
    try:
        return with_overrides(scene, duration=getattr(a, "duration", None), dt=getattr(a, "dt", None))
    except SceneError as e:
        flag = "--dt" if e.key == "simulation.dt" else "--duration"
        raise InputError(f"{flag}: {str(e).split(': ', 1)[1]}") from None
