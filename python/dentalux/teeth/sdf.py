"""Signed-distance primitives for procedural teeth, evaluated on regular grids (numpy).

Convention: negative inside, positive outside, values in mm. Lofted cross-sections are not
exact distances; :func:`normalize` divides such a field by its gradient norm, which makes it a
first-order distance near its zero set (what offsets and blends need).

Blends are the polynomial smooth minimum/maximum (blend width ``k`` mm). Both are monotone
non-decreasing in each argument and shift-invariant (smin(a + t, b + t) = smin(a, b) + t), so
an inner field that is pointwise larger than an outer one stays larger after blending: that
is what keeps a dentin core inside its enamel shell.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Grid:
    """A regular grid: ``origin`` [mm] of node (0, 0, 0), node ``spacing`` [mm], ``shape``."""

    origin: tuple[float, float, float]
    spacing: float
    shape: tuple[int, int, int]

    @staticmethod
    def around(lo, hi, spacing: float, pad: int = 2) -> Grid:
        """A grid covering the box [lo, hi] [mm] with ``pad`` extra nodes on each side."""
        if not (isinstance(spacing, int | float) and 0.02 <= spacing <= 1.0):
            raise ValueError(f"resolution = {spacing!r} is out of range: allowed [0.02, 1.0] mm")
        lo = np.asarray(lo, float) - pad * spacing
        hi = np.asarray(hi, float) + pad * spacing
        shape = tuple(int(v) for v in np.ceil((hi - lo) / spacing).astype(int) + 1)
        from dentalux.limits import check_grid

        check_grid(shape, spacing)  # refuse a grid that cannot fit in memory, before it exists
        return Grid(tuple(float(v) for v in lo), float(spacing), shape)

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Node coordinates along x, y, z [mm]."""
        return tuple(o + self.spacing * np.arange(n)
                     for o, n in zip(self.origin, self.shape, strict=True))

    def points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Broadcastable coordinate arrays X (nx,1,1), Y (1,ny,1), Z (1,1,nz) [mm]."""
        x, y, z = self.axes()
        return x[:, None, None], y[None, :, None], z[None, None, :]


def smoothstep(e0: float, e1: float, x):
    """Hermite step: 0 for x <= e0, 1 for x >= e1, C1 in between."""
    t = np.clip((np.asarray(x, float) - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def smin(a, b, k: float):
    """Polynomial smooth minimum with blend width ``k`` [mm] (k = 0: plain min)."""
    if k <= 0:
        return np.minimum(a, b)
    h = np.clip(k - np.abs(a - b), 0.0, None) / k
    return np.minimum(a, b) - h * h * k * 0.25


def smax(a, b, k: float):
    """Polynomial smooth maximum with blend width ``k`` [mm]."""
    return -smin(-np.asarray(a), -np.asarray(b), k)


def superellipse_norm(x, y, a, b, m):
    """((|x|/a)^m + (|y|/b)^m)^(1/m): 1 on the superellipse with half-axes a, b, exponent m."""
    return ((np.abs(x) / a) ** m + (np.abs(y) / b) ** m) ** (1.0 / m)


def section(x, y, a, b_pos, b_neg, m):
    """Superellipse cross-section field with half-width ``a`` along x and half-widths
    ``b_pos`` (y > 0) and ``b_neg`` (y < 0) along y: ``norm - 1`` (negative inside, not yet a
    distance; see :func:`normalize`)."""
    b = np.where(y >= 0, b_pos, b_neg)
    return superellipse_norm(x, y, a, b, m) - 1.0


def round_cone(px, py, pz, p0, p1, r0: float, r1: float):
    """Signed distance [mm] to a cone with spherical caps joining a sphere of radius ``r0`` at
    ``p0`` to one of radius ``r1`` at ``p1`` (all in mm); exact when |r0 - r1| < |p1 - p0|."""
    a = np.asarray(p0, float)
    b = np.asarray(p1, float)
    ba = b - a
    l2 = float(ba @ ba)
    rr = r0 - r1
    a2 = l2 - rr * rr
    il2 = 1.0 / l2
    qx, qy, qz = px - a[0], py - a[1], pz - a[2]
    y = qx * ba[0] + qy * ba[1] + qz * ba[2]
    z = y - l2
    cx, cy, cz = qx * l2 - ba[0] * y, qy * l2 - ba[1] * y, qz * l2 - ba[2] * y
    x2 = cx * cx + cy * cy + cz * cz
    y2 = y * y * l2
    z2 = z * z * l2
    k = np.sign(rr) * rr * rr * x2
    q2 = qx * qx + qy * qy + qz * qz
    d_end1 = np.sqrt(x2 + z2) * il2 - r1
    d_end0 = np.sqrt(q2) - r0
    d_side = (np.sqrt(x2 * a2 * il2) + y * rr) * il2 - r0
    return np.where(np.sign(z) * a2 * z2 > k, d_end1,
                    np.where(np.sign(y) * a2 * y2 < k, d_end0, d_side))


def normalize(field: np.ndarray, spacing: float, floor: float = 0.05) -> np.ndarray:
    """``field / |grad field|`` on a grid with node ``spacing`` [mm]: a first-order signed
    distance near the zero set. ``floor`` keeps the division finite where the gradient
    vanishes (far from the surface, where the value only needs the right sign)."""
    gx, gy, gz = np.gradient(field, spacing)
    norm = np.sqrt(gx * gx + gy * gy + gz * gz)
    return field / np.maximum(norm, floor)
