"""The special functions the layered solver needs, without scipy.special (whose import costs a
command-line reading about 0.2 s, benchmarks/reading_time.py); the tests hold each to
scipy's.

- :func:`j0`, :func:`j1`: Bessel functions of the first kind, the core's binding of libm's;
- :func:`associated_legendre`: sqrt((l-m)!/(l+m)!) P_l^m (Condon-Shortley phase, as scipy's
  ``lpmv``) by the recurrences of the normalised functions, which stay within [-1, 1] and
  need no factorials (e.g. Press et al., Numerical Recipes, 3rd ed., section 6.7).
"""

from __future__ import annotations

import numpy as np

from dentalux import _core


def j0(x) -> np.ndarray:
    """J0 elementwise."""
    return _core.bessel_j(0, np.ascontiguousarray(x, dtype=float))


def j1(x) -> np.ndarray:
    """J1 elementwise."""
    return _core.bessel_j(1, np.ascontiguousarray(x, dtype=float))


def associated_legendre(modes: int, order: int, x) -> np.ndarray:
    """(modes, order, *x.shape): sqrt((l-m)!/(l+m)!) P_l^m(x) for m < modes, l < order
    (0 where l < m); x in [-1, 1]."""
    x = np.asarray(x, float)
    out = np.zeros((modes, order, *x.shape))
    sine = np.sqrt(np.maximum(1.0 - x * x, 0.0))
    diagonal = np.ones_like(x)                          # N_m^m, from N_0^0 = 1
    for m in range(min(modes, order)):
        if m > 0:
            diagonal = -np.sqrt((2 * m - 1) / (2 * m)) * sine * diagonal
        out[m, m] = diagonal
        if m + 1 < order:
            out[m, m + 1] = np.sqrt(2 * m + 1) * x * diagonal
        for ell in range(m + 2, order):
            out[m, ell] = ((2 * ell - 1) * x * out[m, ell - 1]
                           - np.sqrt((ell - 1) ** 2 - m * m) * out[m, ell - 2]) \
                / np.sqrt(ell * ell - m * m)
    return out
