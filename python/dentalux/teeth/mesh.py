"""Triangle meshes from fields, and the checks a dielectric boundary needs.

- :func:`extract`: marching cubes (scikit-image, Lewiner) of a field's zero set, faces wound
  so that normals point outward (towards increasing field), vertices welded.
- :func:`edge_check`: closed (every edge in exactly two faces) and consistently oriented
  (each directed edge once, its reverse once).
- :func:`signed_volume` [mm^3] (> 0 for outward normals), :func:`winding_number` (1 inside a
  closed outward mesh, 0 outside), :func:`intersects` (does any edge of one mesh cross a
  triangle of the other).
- :func:`vertex_normals`: area-weighted unit normals for smooth shading.
- :func:`write_obj` / :func:`read_obj`: Wavefront OBJ (``v``, ``f`` and optional ``vn``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skimage.measure import marching_cubes

from dentalux.teeth.sdf import Grid

Mesh = tuple[np.ndarray, np.ndarray]
"""(vertices float64 (N, 3) [mm], faces int64 (M, 3) indices into vertices)."""


def extract(field: np.ndarray, grid: Grid) -> Mesh:
    """The zero set of ``field`` (negative inside) on ``grid`` as a closed outward mesh.

    The field must be positive on the grid's border (the pad of :meth:`Grid.around`), which
    makes the surface closed. Nodes exactly at 0 are nudged outward so that no triangle is
    degenerate."""
    f = np.where(field == 0.0, 1e-9, field).astype(np.float64)
    border = np.concatenate([f[[0, -1]].ravel(), f[:, [0, -1]].ravel(), f[:, :, [0, -1]].ravel()])
    if np.any(border <= 0):
        raise ValueError("the shape touches the grid border: enlarge the grid bounds")
    h = grid.spacing
    verts, faces, _, _ = marching_cubes(f, level=0.0, spacing=(h, h, h),
                                        gradient_direction="ascent", allow_degenerate=False)
    verts = verts.astype(np.float64) + np.asarray(grid.origin)
    verts, faces = weld(verts, faces.astype(np.int64))
    if signed_volume(verts, faces) < 0:
        faces = faces[:, ::-1].copy()
    return verts, faces


def weld(verts: np.ndarray, faces: np.ndarray, tol: float = 1e-9) -> Mesh:
    """Merge vertices closer than ``tol`` [mm] (on a lattice of that size), drop unused ones
    and faces that collapsed."""
    key = np.round(verts / tol).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    faces = inverse[faces]
    ok = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    faces = faces[ok]
    used = np.unique(faces)
    remap = np.full(len(first), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return verts[first][used], remap[faces]


def edge_check(faces: np.ndarray) -> dict:
    """Edge statistics: ``closed`` (every undirected edge in exactly two faces),
    ``oriented`` (every directed edge exactly once and its reverse present), counts."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    und = np.sort(e, axis=1)
    _, und_counts = np.unique(und, axis=0, return_counts=True)
    directed, dir_counts = np.unique(e, axis=0, return_counts=True)
    closed = bool(np.all(und_counts == 2))
    # with every undirected edge used twice, orientation is consistent iff no directed edge
    # repeats (then the two uses run in opposite directions)
    oriented = closed and bool(np.all(dir_counts == 1))
    return {"closed": closed, "oriented": oriented, "edges": int(len(und_counts)),
            "boundary_edges": int(np.sum(und_counts == 1)),
            "nonmanifold_edges": int(np.sum(und_counts > 2)),
            "repeated_directed_edges": int(np.sum(dir_counts > 1))}


def euler_characteristic(verts: np.ndarray, faces: np.ndarray) -> int:
    """V - E + F (2 for a closed surface of genus 0)."""
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return int(len(verts) - len(np.unique(e, axis=0)) + len(faces))


def signed_volume(verts: np.ndarray, faces: np.ndarray) -> float:
    """Enclosed volume [mm^3] by the divergence theorem; positive for outward normals."""
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def area(verts: np.ndarray, faces: np.ndarray) -> float:
    """Surface area [mm^2]."""
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def winding_number(points: np.ndarray, verts: np.ndarray, faces: np.ndarray,
                   chunk: int = 8) -> np.ndarray:
    """Generalised winding number of each point [-] (solid angles of all triangles / 4π,
    Van Oosterom and Strackee's formula): 1 inside a closed outward mesh, 0 outside."""
    points = np.atleast_2d(np.asarray(points, float))
    tri = verts[faces]  # (M, 3, 3)
    out = np.empty(len(points))
    for s in range(0, len(points), chunk):
        p = points[s:s + chunk, None, None, :]
        r = tri[None] - p  # (P, M, 3, 3)
        a, b, c = r[:, :, 0], r[:, :, 1], r[:, :, 2]
        la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
        det = np.einsum("pmi,pmi->pm", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("pmi,pmi->pm", a, b) * lc
               + np.einsum("pmi,pmi->pm", b, c) * la + np.einsum("pmi,pmi->pm", c, a) * lb)
        out[s:s + chunk] = 2.0 * np.arctan2(det, den).sum(axis=1) / (4.0 * np.pi)
    return out


def _cells(lo: np.ndarray, hi: np.ndarray, cell: float):
    """(item index, cell key) pairs for every grid cell that a box [lo, hi] overlaps."""
    i0 = np.floor(lo / cell).astype(np.int64)
    i1 = np.floor(hi / cell).astype(np.int64)
    span = i1 - i0 + 1
    items, keys = [], []
    for dx in range(int(span[:, 0].max())):
        for dy in range(int(span[:, 1].max())):
            for dz in range(int(span[:, 2].max())):
                d = np.array([dx, dy, dz])
                ok = np.all(d < span, axis=1)
                idx = np.nonzero(ok)[0]
                c = i0[idx] + d
                items.append(idx)
                keys.append((c[:, 0] * 1_000_003 + c[:, 1]) * 1_000_033 + c[:, 2])
    return np.concatenate(items), np.concatenate(keys)


def intersects(mesh_a: Mesh, mesh_b: Mesh, cell: float | None = None) -> int:
    """Number of (edge of A, triangle of B) pairs that cross; 0 for disjoint surfaces.
    Candidates come from a uniform grid of ``cell`` mm; each is tested with the
    Möller-Trumbore segment-triangle test."""
    va, fa = mesh_a
    vb, fb = mesh_b
    edges = np.unique(np.sort(np.concatenate([fa[:, [0, 1]], fa[:, [1, 2]], fa[:, [2, 0]]]),
                              axis=1), axis=0)
    p, q = va[edges[:, 0]], va[edges[:, 1]]
    tri = vb[fb]
    if cell is None:
        cell = 2.0 * float(np.median(np.linalg.norm(q - p, axis=1)))
    ei, ek = _cells(np.minimum(p, q), np.maximum(p, q), cell)
    ti, tk = _cells(tri.min(axis=1), tri.max(axis=1), cell)
    order = np.argsort(tk, kind="stable")
    tk, ti = tk[order], ti[order]
    left = np.searchsorted(tk, ek, side="left")
    right = np.searchsorted(tk, ek, side="right")
    counts = right - left
    e_idx = np.repeat(ei, counts)
    starts = np.repeat(left, counts)
    offs = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    t_idx = ti[starts + offs]
    pairs = np.unique(np.stack([e_idx, t_idx], axis=1), axis=0)
    hits = 0
    for s in range(0, len(pairs), 1_000_000):
        e, t = pairs[s:s + 1_000_000, 0], pairs[s:s + 1_000_000, 1]
        o, d = p[e], q[e] - p[e]
        v0, v1, v2 = tri[t, 0], tri[t, 1], tri[t, 2]
        e1, e2 = v1 - v0, v2 - v0
        pv = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, pv)
        ok = np.abs(det) > 1e-14
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tv = o - v0
        u = np.einsum("ij,ij->i", tv, pv) * inv
        qv = np.cross(tv, e1)
        v = np.einsum("ij,ij->i", d, qv) * inv
        tt = np.einsum("ij,ij->i", e2, qv) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (tt >= 0) & (tt <= 1)
        hits += int(hit.sum())
    return hits


def vertex_normals(verts: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit vertex normals: the area-weighted mean of the adjacent faces' normals (outward
    for an outward mesh); for smooth shading, not for the geometry."""
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    fn = np.cross(b - a, c - a)  # length = 2 x area: area weighting for free
    vn = np.zeros_like(verts)
    for k in range(3):
        np.add.at(vn, faces[:, k], fn)
    return vn / np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)


def write_obj(path, verts: np.ndarray, faces: np.ndarray, comment: str = "",
              normals: np.ndarray | None = None) -> Path:
    """Write a Wavefront OBJ (``v x y z`` in mm, 1-based ``f i j k``, counter-clockwise seen
    from outside); with ``normals`` (one per vertex) also ``vn`` records and ``f i//i ...``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", encoding="ascii") as fh:
        for line in comment.splitlines():
            fh.write(f"# {line}\n")
        np.savetxt(fh, verts, fmt="v %.6f %.6f %.6f")
        if normals is None:
            np.savetxt(fh, faces + 1, fmt="f %d %d %d")
        else:
            np.savetxt(fh, normals, fmt="vn %.6f %.6f %.6f")
            np.savetxt(fh, np.repeat(faces + 1, 2, axis=1), fmt="f %d//%d %d//%d %d//%d")
    return path


def read_obj(path) -> Mesh:
    """Read the ``v`` and ``f`` records of an OBJ file (polygons are fanned into
    triangles; ``v/vt/vn`` index forms and negative indices are accepted)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"mesh file {str(path)!r} not found")
    verts, faces = [], []
    for lineno, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        try:
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(tok.split("/")[0]) for tok in parts[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                faces.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
        except (ValueError, IndexError):
            raise ValueError(f"{path}:{lineno}: malformed OBJ record {line!r}") from None
    v = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(f) and (f.min() < 0 or f.max() >= len(v)):
        raise ValueError(f"{path}: a face index is out of range (1..{len(v)})")
    return v, f
