"""dentalux: spectral Monte Carlo rendering of teeth and dental restorative materials.

Units everywhere: lengths in mm, coefficients in 1/mm, wavelengths in nm.
"""

from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version

from dentalux.render import RenderResult, render
from dentalux.scene import Scene, SceneError, load_scene, scene_from_dict
from dentalux.slab import Layer, SlabResult

try:  # one home: pyproject.toml's [project] version, read from the installed metadata
    __version__ = _dist_version("dentalux")
except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["Layer", "SlabResult", "__version__"]
__all__ += ["RenderResult", "Scene", "SceneError", "load_scene", "render", "scene_from_dict"]
