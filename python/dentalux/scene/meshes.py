"""Triangle meshes from OBJ and PLY files (read with trimesh), as plain positions and
triangles [mm] for the render contract.

A mesh that bounds a dielectric medium must be closed and consistently oriented (the core's
rule, :func:`check_closed`); one whose triangles all face inwards (negative enclosed volume)
is flipped so that normals point out of the ``inside`` medium, which is the orientation the
core assumes. Whether a point lies inside a mesh is the core's test (:func:`point_inside`).
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dentalux import _core
from dentalux.scene.schema import SceneError

SUFFIXES = (".obj", ".ply")


@dataclass
class MeshData:
    """positions (N, 3) float64 [mm]; triangles (M, 3) int64; uvs (N, 2) or None."""

    positions: np.ndarray
    triangles: np.ndarray
    uvs: np.ndarray | None = None


def load_mesh(f: Path, path: str = "mesh.file", file: str | None = None) -> MeshData:
    """Read the OBJ or PLY file ``f``; ``path`` is the scene key path and ``file`` the name
    as the scene gives it, both for error messages."""
    f = Path(f)
    file = str(f) if file is None else file
    if f.suffix.lower() not in SUFFIXES:
        raise SceneError(f"{path} = '{file}': unsupported mesh format (allowed: .obj, .ply)")
    if not f.is_file():
        raise SceneError(f"{path} = '{file}': file not found")
    import trimesh  # deferred: a 0.2 s import, needed only for mesh files

    try:
        # from the bytes, without a resolver: references inside the file (an OBJ's mtllib,
        # texture maps) are not followed, so a mesh reads no file but itself
        data = io.BytesIO(f.read_bytes())
        mesh = trimesh.load(data, file_type=f.suffix.lower().lstrip("."), force="mesh",
                            process=False)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise SceneError(f"{path} = '{file}': cannot read the mesh ({exc})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise SceneError(f"{path} = '{file}': the file holds no triangles")
    bad = ~np.isfinite(np.asarray(mesh.vertices, dtype=float)).all(axis=1)
    if bad.any():
        raise SceneError(f"{path} = '{file}': vertex {int(np.argmax(bad)) + 1} is not finite "
                         "(NaN or inf); every coordinate must be a finite number [mm]")
    uv = getattr(mesh.visual, "uv", None)
    uvs = None
    if uv is not None and len(uv) == len(mesh.vertices):
        uvs = np.asarray(uv, dtype=float)
    return MeshData(np.asarray(mesh.vertices, dtype=float),
                    np.asarray(mesh.faces, dtype=np.int64), uvs)


def check_closed(data: MeshData, path: str) -> MeshData:
    """Reject an open or inconsistently oriented mesh; flip an inward-facing one.

    The core judges it (``_core.mesh_topology``), by the rule its scene decoder applies to a
    dielectric mesh: on positions merged to 1e-8 mm, so vertices duplicated along uv seams
    do not count as holes; and its signed volume says whether the mesh faces inward.
    """
    kind, edges, inward = _core.mesh_topology(data.positions.tolist(),
                                              data.triangles.tolist())
    if kind == "open":
        raise SceneError(
            f"{path}: the mesh is open (not watertight: {edges} edges are not shared by "
            "exactly two triangles), so it cannot bound a dielectric medium; close it or "
            "give it an opaque surface"
        )
    if kind == "inconsistent":
        raise SceneError(
            f"{path}: the mesh's triangles are inconsistently oriented ({edges} edges are "
            "traversed twice in the same direction), so inside and outside are ambiguous; "
            "fix the winding (e.g. trimesh.repair.fix_winding)"
        )
    if inward:  # the core's signed volume is negative: the normals point in
        return MeshData(data.positions, data.triangles[:, ::-1].copy(), data.uvs)
    return data


def point_inside(data: MeshData, point) -> bool:
    """Whether ``point`` lies strictly inside the mesh (an open one has no inside): the core's
    test, as for a scene's shapes (:func:`dentalux.scene.resolve.shape_contains`)."""
    from dentalux.scene.resolve import shape_contains  # resolve imports this module

    shape = {"type": "mesh", "positions": data.positions, "triangles": data.triangles,
             "boundary": {"kind": "opaque", "surface": 0}}
    return bool(shape_contains(shape, [point])[0])
