"""Interpolation through a few nodes as linear maps: the interpolant's values at given
points are ``basis @ values_at_nodes``. Written here because the reading path needs nothing
else of ``scipy.interpolate``, whose import costs a command-line reading about 0.25 s
(benchmarks/reading_time.py); the tests hold both to scipy's ``CubicSpline`` and
``BarycentricInterpolator``.

- :func:`cubic_spline`: the cubic spline with not-a-knot ends (the third derivative
  continuous at the second and the last-but-one node), as ``CubicSpline`` by default;
- :func:`polynomial`: the polynomial through every node, by the barycentric formula
  (Berrut & Trefethen 2004, SIAM Review 46:501, eq. 4.2), stable for the few nodes here.
"""

from __future__ import annotations

import numpy as np


def cubic_spline(x: np.ndarray, at: np.ndarray) -> np.ndarray:
    """(len(at), len(x)): row i holds the weights of the node values in the spline's value at
    ``at[i]``; ``x`` strictly increasing, at least 2 nodes (3 give the parabola through
    them, 2 the line); points outside [x[0], x[-1]] continue the end pieces."""
    x = np.asarray(x, float)
    at = np.asarray(at, float)
    n = len(x)
    if n < 2 or np.any(np.diff(x) <= 0):
        raise ValueError(f"spline nodes {x.tolist()}: need at least 2, strictly increasing")
    h = np.diff(x)
    # second derivatives m at the nodes from the node values y: a @ m = b @ y
    a = np.zeros((n, n))
    b = np.zeros((n, n))
    for i in range(1, n - 1):
        a[i, i - 1: i + 2] = h[i - 1], 2 * (h[i - 1] + h[i]), h[i]
        b[i, i - 1: i + 2] = 6 / h[i - 1], -6 / h[i - 1] - 6 / h[i], 6 / h[i]
    if n == 2:
        m = np.zeros((2, 2))                                 # the line
    elif n == 3:
        # the parabola: one second derivative throughout
        a[0, :2] = a[2, 1:] = 1, -1
        m = np.linalg.solve(a, b)
    else:
        # not-a-knot: the pieces on either side of x[1] (and of x[n-2]) share their third
        # derivative (m[i+1] - m[i]) / h[i]
        a[0, :3] = 1 / h[0], -1 / h[0] - 1 / h[1], 1 / h[1]
        a[-1, -3:] = 1 / h[-2], -1 / h[-2] - 1 / h[-1], 1 / h[-1]
        m = np.linalg.solve(a, b)                            # (n nodes, n values)
    j = np.clip(np.searchsorted(x, at, side="right") - 1, 0, n - 2)
    hj = h[j]
    lo = (x[j + 1] - at) / hj
    hi = (at - x[j]) / hj
    out = np.zeros((len(at), n))
    rows = np.arange(len(at))
    out[rows, j] += lo
    out[rows, j + 1] += hi
    out += ((lo ** 3 - lo) * hj ** 2 / 6)[:, None] * m[j]
    out += ((hi ** 3 - hi) * hj ** 2 / 6)[:, None] * m[j + 1]
    return out


def polynomial(x: np.ndarray, at: np.ndarray) -> np.ndarray:
    """(len(at), len(x)): the weights of the node values in the value at ``at[i]`` of the
    polynomial through every node (``x`` distinct)."""
    x = np.asarray(x, float)
    at = np.asarray(at, float)
    diff = x[:, None] - x[None, :]
    np.fill_diagonal(diff, 1.0)
    if np.any(diff == 0):
        raise ValueError(f"interpolation nodes {x.tolist()}: need distinct nodes")
    # barycentric weights 1 / prod_{m != j} (x_j - x_m), scaled by the nodes' spread so that
    # the product neither overflows nor underflows (the scale cancels in the quotient)
    scale = 4.0 / (x.max() - x.min()) if len(x) > 1 else 1.0
    w = 1.0 / np.prod(diff * scale, axis=1)
    d = at[:, None] - x[None, :]
    exact = d == 0
    d[exact] = 1.0
    terms = w / d
    out = terms / terms.sum(axis=1, keepdims=True)
    # a point on a node takes that node's value
    hit = exact.any(axis=1)
    out[hit] = exact[hit].astype(float)
    return out
