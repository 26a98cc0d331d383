"""Scenes: the TOML/dict description format, its validation, transforms, meshes, built-in
scenes, and resolution per wavelength band into the render contract (docs/render-contract.md).
"""

from dentalux.scene.load import as_scene, load_scene, scene_from_dict
from dentalux.scene.resolve import Scene
from dentalux.scene.schema import SceneError

__all__ = ["Scene", "SceneError", "as_scene", "load_scene", "scene_from_dict"]
