"""dentalux: spectral Monte Carlo rendering of teeth and dental restorative materials.

Units everywhere: lengths in mm, coefficients in 1/mm, wavelengths in nm.
"""

from dentalux import _core, _guard

_guard.install(_core)  # panics -> RuntimeError, overflows -> ValueError (dentalux._guard)

from dentalux.render import RenderResult, render  # noqa: E402
from dentalux.scene import Scene, SceneError, load_scene, scene_from_dict  # noqa: E402
from dentalux.slab import Layer, SlabResult  # noqa: E402


def __getattr__(name: str):
    # __version__ on first use: importlib.metadata takes a twentieth of a second to import,
    # a tenth of a command's start-up, and only `dentalux --version` and reports read it
    if name != "__version__":
        raise AttributeError(f"module 'dentalux' has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:  # one home: pyproject.toml's [project] version, read from the installed metadata
        value = version("dentalux")
    except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
        value = "0+unknown"
    globals()["__version__"] = value
    return value


__all__ = ["Layer", "SlabResult", "__version__"]
__all__ += ["RenderResult", "Scene", "SceneError", "load_scene", "render", "scene_from_dict"]
