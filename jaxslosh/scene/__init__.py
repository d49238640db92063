"""The scene: a TOML file (docs/reference/scene.md) read into a validated, immutable `Scene` of plain
Python values (no JAX), and the registry of its keys."""
from .load import load_scene, parse_scene
from .types import Scene, SceneError

__all__ = ["Scene", "SceneError", "load_scene", "parse_scene"]
