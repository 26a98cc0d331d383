"""Fresnel numbers of a flat boundary that the analytic slab models need.

All for unpolarised light. ``m = n_outside / n_inside`` is the index ratio seen from inside
the sample. Angular moments are over the inside hemisphere, with mu = cos(theta) inside:

- ``specular(n, n_out)``: normal-incidence reflectance ((n - n_out)/(n + n_out))^2;
- ``moments(n, n_out)``: (R_phi, R_j) = (int_0^1 2 mu R(mu) dmu, int_0^1 3 mu^2 R(mu) dmu), the
  fluence- and current-weighted internal reflectances of the partial-current boundary
  condition (Haskell et al. 1994). R_phi is also the internal reflectance for Lambertian
  light, used as the Saunderson k2.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from dentalux import _core

_GL_X, _GL_W = np.polynomial.legendre.leggauss(64)


def fresnel(cos_i: np.ndarray, m: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance for incidence cosine ``cos_i`` and index ratio m = n_t/n_i.

    Total internal reflection gives 1. The formula is the core's (fresnel.rs), which the
    renderers and the slab simulator use.
    """
    cos_i = np.asarray(cos_i, dtype=float)
    r = _core.fresnel_reflectance(cos_i.ravel().tolist(), 1.0, float(m))
    return np.asarray(r, dtype=float).reshape(cos_i.shape)


def specular(n: float, n_out: float) -> float:
    """Normal-incidence reflectance of the boundary between indices n and n_out."""
    return ((n - n_out) / (n + n_out)) ** 2


@lru_cache(maxsize=256)
def moments(n: float, n_out: float) -> tuple[float, float]:
    """(R_phi, R_j): internal Fresnel reflectance moments of the boundary, inside index n.

    The interval of total internal reflection (mu below the critical cosine) is integrated
    exactly; the rest by 64-point Gauss-Legendre, so the kink at the critical angle costs no
    accuracy.
    """
    m = n_out / n
    mu_c = math.sqrt(1.0 - m * m) if m < 1.0 else 0.0
    half = 0.5 * (1.0 - mu_c)
    mu = mu_c + half * (_GL_X + 1.0)
    r = fresnel(mu, m)
    r_phi = mu_c**2 + half * float(np.sum(_GL_W * 2.0 * mu * r))
    r_j = mu_c**3 + half * float(np.sum(_GL_W * 3.0 * mu**2 * r))
    return r_phi, r_j
