"""Reading scenes: a TOML file (``load_scene``) or a dict (``scene_from_dict``).

Both return a validated :class:`dentalux.scene.resolve.Scene`. Relative file names in a TOML
scene (meshes, textures) are read from the scene file's folder; in a dict, from ``base_dir``
(default: the current folder).
"""

from __future__ import annotations

import sys
from pathlib import Path

from dentalux.scene.resolve import Scene
from dentalux.scene.schema import SceneError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def read_toml(path: str | Path) -> dict:
    """Parse a TOML scene file into a dict; a syntax error names the file and line."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"scene file not found: {p}")
    from dentalux import inputs
    from dentalux.scene.files import MAX_FILE_BYTES

    try:
        # UTF-8 with a BOM tolerated; another encoding or binary names the file (a scene
        # may carry its meshes inline: as large as the mesh files it may read)
        text = inputs.read_text(p, "scene file", MAX_FILE_BYTES)
    except ValueError as exc:
        raise SceneError(str(exc)) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{p}: not valid TOML ({exc})") from None
    except RecursionError:
        raise SceneError(f"{p}: not valid TOML for a scene (arrays or tables nested too "
                         "deeply)") from None


def load_scene(path: str | Path, allow_outside_paths: bool = False) -> Scene:
    """Load and validate a TOML scene file. The files it names are read relative to its
    folder and must stay inside it unless ``allow_outside_paths`` (dentalux.scene.files)."""
    p = Path(path)
    return Scene(read_toml(p), base_dir=p.resolve().parent, source=str(p),
                 allow_outside_paths=allow_outside_paths)


def scene_from_dict(d: dict, base_dir: str | Path | None = None,
                    allow_outside_paths: bool = False) -> Scene:
    """Validate a scene given as a dict (the same keys as the TOML format); its files are
    read relative to ``base_dir`` (default: the current folder)."""
    return Scene(d, base_dir=base_dir, source=None, allow_outside_paths=allow_outside_paths)


def as_scene(scene) -> Scene:
    """A Scene from a Scene, a dict, or a path to a TOML file."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return scene_from_dict(scene)
    if isinstance(scene, (str, Path)):
        return load_scene(scene)
    raise TypeError(f"scene must be a Scene, a dict or a path, got {type(scene).__name__}")
