"""dentalux: spectral Monte Carlo rendering of teeth and dental restorative materials.

Units everywhere: lengths in mm, coefficients in 1/mm, wavelengths in nm.
"""

from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version

from dentalux import _core, _guard

_guard.install(_core)  # panics -> RuntimeError, overflows -> ValueError (dentalux._guard)

from dentalux.render import RenderResult, render  # noqa: E402
from dentalux.scene import Scene, SceneError, load_scene, scene_from_dict  # noqa: E402
from dentalux.slab import Layer, SlabResult  # noqa: E402

try:  # one home: pyproject.toml's [project] version, read from the installed metadata
    __version__ = _dist_version("dentalux")
except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["Layer", "SlabResult", "__version__"]
__all__ += ["RenderResult", "Scene", "SceneError", "load_scene", "render", "scene_from_dict"]
