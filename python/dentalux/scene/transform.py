"""Object-to-world transforms as 4x4 row-major matrices (lengths in mm, angles in degrees).

A shape's ``transform = {scale, rotate, translate}`` applies the scale first, then the
rotations in the order listed, then the translation: M = T · R_n ··· R_1 · S. A raw
``matrix`` (4 rows of 4) is taken as given.
"""

from __future__ import annotations

import numpy as np


def translate(offset) -> np.ndarray:
    """Translation by ``offset`` [mm]."""
    m = np.eye(4)
    m[:3, 3] = np.asarray(offset, dtype=float)
    return m


def rotate(axis, angle_deg: float) -> np.ndarray:
    """Right-handed rotation by ``angle_deg`` [deg] about ``axis`` (any non-zero length)."""
    from scipy.spatial.transform import Rotation  # deferred: a 0.2 s import

    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    m = np.eye(4)
    m[:3, :3] = Rotation.from_rotvec(np.radians(angle_deg) * a).as_matrix()
    return m


def scale(factors) -> np.ndarray:
    """Scale by a number or by per-axis factors (all > 0)."""
    f = np.broadcast_to(np.asarray(factors, dtype=float), (3,))
    return np.diag([*f, 1.0])


def compose(spec: dict | None) -> np.ndarray:
    """The 4x4 matrix of a validated ``transform`` table (identity for ``None``)."""
    if not spec:
        return np.eye(4)
    if "matrix" in spec:
        return np.asarray(spec["matrix"], dtype=float)
    m = np.eye(4)
    if "scale" in spec:
        m = scale(spec["scale"]) @ m
    for r in spec.get("rotate", []):
        m = rotate(r["axis"], r["angle_deg"]) @ m
    if "translate" in spec:
        m = translate(spec["translate"]) @ m
    return m


def apply_point(m: np.ndarray, p) -> np.ndarray:
    """Transform a point (or an array of points, shape (..., 3))."""
    p = np.asarray(p, dtype=float)
    return p @ m[:3, :3].T + m[:3, 3]


def apply_vector(m: np.ndarray, v) -> np.ndarray:
    """Transform a direction (no translation)."""
    return np.asarray(v, dtype=float) @ m[:3, :3].T
