"""A brute-force photon walk for fibre-probe tests, written apart from dentalux's solver and
core: a homogeneous slab in air (smooth Fresnel faces, black below), Henyey-Greenstein
scattering, photons launched along the normal uniformly over the source fibres (each
fibre's share in proportion to its area), counted where they leave the top inside a receiving
fibre within its acceptance half-angle in air."""

from __future__ import annotations

import numpy as np

# a photon's weight below this plays Russian roulette, surviving with ROULETTE_KEEP
ROULETTE_BELOW = 1e-3
ROULETTE_KEEP = 0.1


def fresnel(cos_i: np.ndarray, n1: float, n2: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance from index n1 into n2 (1 past the critical angle)."""
    sin_t = n1 / n2 * np.sqrt(np.clip(1 - cos_i**2, 0, 1))
    tir = sin_t >= 1
    cos_t = np.sqrt(np.clip(1 - sin_t**2, 0, 1))
    rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)
    return np.where(tir, 1.0, 0.5 * (rs**2 + rp**2))


def _scatter(u: np.ndarray, g: float, rng) -> np.ndarray:
    """New directions (N, 3) after Henyey-Greenstein scattering of the directions u."""
    xi = rng.random(len(u))
    if abs(g) < 1e-9:
        cos_t = 2 * xi - 1
    else:
        cos_t = (1 + g * g - ((1 - g * g) / (1 - g + 2 * g * xi)) ** 2) / (2 * g)
    cos_t = np.clip(cos_t, -1, 1)
    sin_t = np.sqrt(1 - cos_t**2)
    phi = 2 * np.pi * rng.random(len(u))
    # any unit vector perpendicular to u, then the second by a cross product
    helper = np.where(np.abs(u[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(u, e1)
    return (cos_t[:, None] * u + sin_t[:, None] * (np.cos(phi)[:, None] * e1
                                                   + np.sin(phi)[:, None] * e2))


def walk(mua: float, mus: float, g: float, n: float, thickness: float, sources, receivers,
         acceptance_deg: float, photons: int, seed: int = 1) -> tuple[float, float]:
    """(reading, its standard error): the power leaving inside the receivers within the
    acceptance, per unit incident power, over the cone's Lambertian fraction sin^2. Fibres
    are (x, y, diameter) [mm]."""
    rng = np.random.default_rng(seed)
    src = np.asarray(sources, float)
    rec = np.asarray(receivers, float)
    area = src[:, 2] ** 2
    pick = rng.choice(len(src), size=photons, p=area / area.sum())
    r = src[pick, 2] / 2 * np.sqrt(rng.random(photons))
    phi = 2 * np.pi * rng.random(photons)
    pos = np.stack([src[pick, 0] + r * np.cos(phi), src[pick, 1] + r * np.sin(phi),
                    np.zeros(photons)], axis=1)
    u = np.tile([0.0, 0.0, 1.0], (photons, 1))  # z points into the slab
    w = np.full(photons, 1.0 - float(fresnel(np.ones(1), 1.0, n)[0]))
    idx = np.arange(photons)
    tally = np.zeros(photons)
    mut = mua + mus
    albedo = mus / mut
    cos_acc = np.cos(np.radians(acceptance_deg))
    while len(idx):
        step = -np.log(rng.random(len(idx))) / mut
        z_new = pos[:, 2] + step * u[:, 2]
        out_top, out_bot = z_new < 0, z_new > thickness
        inside = ~(out_top | out_bot)
        pos[inside] += step[inside, None] * u[inside]
        keep = inside.copy()
        for hit, z_face in ((out_top, 0.0), (out_bot, thickness)):
            if not hit.any():
                continue
            d = (z_face - pos[hit, 2]) / u[hit, 2]
            pos[hit] += d[:, None] * u[hit]
            pos[hit, 2] = z_face
            cos_i = np.abs(u[hit, 2])
            reflect = rng.random(hit.sum()) < fresnel(cos_i, n, 1.0)
            rows = np.flatnonzero(hit)
            u[rows[reflect], 2] *= -1  # back into the slab; a fresh free flight follows
            keep[rows[reflect]] = True
            if z_face == 0.0:
                gone = rows[~reflect]
                sin_t = n * np.sqrt(np.clip(1 - cos_i[~reflect] ** 2, 0, 1))
                in_cone = np.sqrt(np.clip(1 - sin_t**2, 0, 1)) >= cos_acc
                x, y = pos[gone, 0], pos[gone, 1]
                in_fibre = np.zeros(len(gone), bool)
                for fx, fy, fd in rec:
                    in_fibre |= (x - fx) ** 2 + (y - fy) ** 2 <= (fd / 2) ** 2
                counted = gone[in_cone & in_fibre]
                tally[idx[counted]] += w[counted]
        # scatter where the flight ended inside
        if inside.any():
            w[inside] *= albedo
            u[inside] = _scatter(u[inside], g, rng)
        low = keep & (w < ROULETTE_BELOW)
        if low.any():
            live = rng.random(low.sum()) < ROULETTE_KEEP
            rows = np.flatnonzero(low)
            w[rows[live]] /= ROULETTE_KEEP
            keep[rows[~live]] = False
        idx, pos, u, w = idx[keep], pos[keep], u[keep], w[keep]
    lambertian = 1 - cos_acc**2
    values = tally / lambertian
    return float(values.mean()), float(values.std(ddof=1) / np.sqrt(photons))
