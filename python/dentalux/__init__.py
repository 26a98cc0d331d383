"""dentalux: spectral Monte Carlo rendering of teeth and dental restorative materials.

Units everywhere: lengths in mm, coefficients in 1/mm, wavelengths in nm.
"""

from dentalux import _core
from dentalux.render import RenderResult, render
from dentalux.scene import Scene, SceneError, load_scene, scene_from_dict
from dentalux.slab import Layer, SlabResult

__version__ = _core.__version__

__all__ = ["Layer", "SlabResult", "__version__"]
__all__ += ["RenderResult", "Scene", "SceneError", "load_scene", "render", "scene_from_dict"]
