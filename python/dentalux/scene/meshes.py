"""Triangle meshes from OBJ and PLY files (read with trimesh), as plain positions and
triangles [mm] for the render contract.

A mesh that bounds a dielectric medium must be closed and consistently oriented; one whose
triangles all face inwards (negative enclosed volume) is flipped so that normals point out of
the ``inside`` medium, which is the orientation the core assumes.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

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

    Closedness is judged on positions merged by coordinate, so vertices duplicated for uv
    seams do not count as holes.
    """
    import trimesh

    merged = trimesh.Trimesh(data.positions, data.triangles, process=True)
    if not merged.is_watertight:
        raise SceneError(
            f"{path}: the mesh is open (not watertight), so it cannot bound a dielectric "
            "medium; close it or give it an opaque surface"
        )
    if not merged.is_winding_consistent:
        raise SceneError(
            f"{path}: the mesh's triangles are inconsistently oriented, so inside and "
            "outside are ambiguous; fix the winding (e.g. trimesh.repair.fix_winding)"
        )
    # signed enclosed volume (divergence theorem), cheaper than trimesh's mass properties
    t = data.positions[data.triangles]
    volume = float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum()) / 6.0
    if volume < 0:
        return MeshData(data.positions, data.triangles[:, ::-1].copy(), data.uvs)
    return data


def is_closed(data: MeshData) -> bool:
    """Whether the mesh is watertight (positions merged by coordinate)."""
    import trimesh

    return bool(trimesh.Trimesh(data.positions, data.triangles, process=True).is_watertight)


def point_inside(data: MeshData, point) -> bool:
    """Whether ``point`` lies inside a closed mesh: the parity of the triangles crossed by a
    ray from it (Moller-Trumbore, vectorised). The ray's direction is skewed so that it
    almost surely misses edges and vertices."""
    p = np.asarray(point, dtype=float)
    lo, hi = data.positions.min(axis=0), data.positions.max(axis=0)
    if np.any(p <= lo) or np.any(p >= hi):
        return False
    d = np.array([0.5377, 0.6151, 0.5767])
    d /= np.linalg.norm(d)
    v0, v1, v2 = (data.positions[data.triangles[:, i]] for i in range(3))
    e1, e2 = v1 - v0, v2 - v0
    pvec = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, pvec)
    ok = np.abs(det) > 1e-300
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    tvec = p - v0
    u = np.einsum("ij,ij->i", tvec, pvec) * inv
    qvec = np.cross(tvec, e1)
    v = (qvec @ d) * inv
    t = np.einsum("ij,ij->i", e2, qvec) * inv
    hits = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return bool(np.count_nonzero(hits) % 2 == 1)
