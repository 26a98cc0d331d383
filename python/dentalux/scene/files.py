"""What a scene may read: mesh and image files, checked before any parser sees them.

A file named by a scene (``shapes[i].file``, ``surfaces.NAME.file``, a tooth's
``enamel_file``) is resolved relative to the scene file's folder (a dict scene: its
``base_dir``). It is read only when

- it stays inside that folder once ``..`` and symbolic links are resolved, unless the
  caller allows outside paths (``--allow-outside-paths``, ``allow_outside_paths=True``);
  absolute paths count as outside;
- it is a regular file (not a device, FIFO or folder) of at most MAX_FILE_BYTES;
- its name and the name it resolves to end in an allowed suffix, and its first bytes are
  those of that format (PNG, JPEG, TIFF, BMP signatures; ``ply``; an OBJ must be UTF-8
  text without NUL bytes).

Errors name the scene key and the file as the scene gives it, never the resolved absolute
path (which would tell whether a file exists elsewhere). docs/scene-format.md and
docs/limits.md document the rules.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from dentalux.scene.schema import SceneError

MESH_SUFFIXES = (".obj", ".ply")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")
#: the largest mesh or image file a scene may read [bytes]
MAX_FILE_BYTES = 1 << 30

_MAGIC = {
    ".png": (b"\x89PNG\r\n\x1a\n",),
    ".jpg": (b"\xff\xd8\xff",),
    ".jpeg": (b"\xff\xd8\xff",),
    ".tif": (b"II*\x00", b"MM\x00*"),
    ".tiff": (b"II*\x00", b"MM\x00*"),
    ".bmp": (b"BM",),
    ".ply": (b"ply\n", b"ply\r\n"),
}


def _refuse(key: str, name: str, why: str) -> SceneError:
    return SceneError(f"{key} = '{name}': {why}")


def _looks_like(real: Path, suffix: str, key: str, name: str) -> None:
    with open(real, "rb") as f:
        head = f.read(1 << 16)
    if suffix == ".obj":
        if b"\x00" in head:
            raise _refuse(key, name, "not an OBJ file (binary data, OBJ is text)")
        try:
            head.decode("utf-8")
        except UnicodeDecodeError as exc:
            if exc.start < len(head) - 4:  # not just a character cut at the 64 kB mark
                raise _refuse(key, name, "not an OBJ file (not UTF-8 text)") from None
        return
    if not any(head.startswith(m) for m in _MAGIC[suffix]):
        kind = suffix.lstrip(".").upper()
        raise _refuse(key, name, f"not a {kind} file (its first bytes are not a {kind} "
                                 "signature)")


def scene_file(name: str, base_dir: Path, key: str, kind: str,
               allow_outside: bool = False) -> Path:
    """The checked path of the ``kind`` ('mesh' or 'image') file ``name`` that scene key
    ``key`` names; raises SceneError otherwise."""
    suffixes = MESH_SUFFIXES if kind == "mesh" else IMAGE_SUFFIXES
    if not isinstance(name, str) or not name.strip():
        raise _refuse(key, str(name), "an empty file name")
    given = Path(name)
    suffix = given.suffix.lower()
    if suffix not in suffixes:
        raise _refuse(key, name, f"unsupported {kind} file (allowed: {', '.join(suffixes)})")
    base = Path(base_dir).resolve()
    full = given if given.is_absolute() else base / given
    try:
        real = full.resolve(strict=False)
    except (OSError, RuntimeError):  # a symlink loop
        raise _refuse(key, name, "cannot be resolved (a symbolic link loop?)") from None
    if not allow_outside:
        if given.is_absolute():
            raise _refuse(key, name, "an absolute path; scene files are read relative to "
                                     "the scene's folder (pass --allow-outside-paths, or "
                                     "allow_outside_paths=True, to read it anyway)")
        if not real.is_relative_to(base):
            raise _refuse(key, name, "leaves the scene's folder (through '..' or a symbolic "
                                     "link); pass --allow-outside-paths (or "
                                     "allow_outside_paths=True) to read it anyway")
    try:
        st = os.stat(real)
    except OSError:
        raise _refuse(key, name, "file not found (relative to the scene's folder)") from None
    if not stat.S_ISREG(st.st_mode):
        raise _refuse(key, name, "not a regular file")
    if real.suffix.lower() not in suffixes:
        raise _refuse(key, name, f"is a link to a file without a {kind} suffix "
                                 f"(allowed: {', '.join(suffixes)})")
    if st.st_size > MAX_FILE_BYTES:
        raise _refuse(key, name, f"{st.st_size:,} bytes is out of range: allowed at most "
                                 f"{MAX_FILE_BYTES:,} bytes")
    try:
        _looks_like(real, real.suffix.lower(), key, name)
    except OSError as exc:
        raise _refuse(key, name, f"cannot be read ({exc.strerror or 'error'})") from None
    return real
