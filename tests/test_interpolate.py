"""The reading path's interpolations (dentalux.reading.layered.interpolate) against scipy's
(the cone weights interpolate through the 8 oblique nodes of the medium above):
the not-a-knot cubic spline against CubicSpline, the polynomial against
BarycentricInterpolator, inside and past the nodes."""

import numpy as np
import pytest
from dentalux.reading.layered import interpolate
from dentalux.reading.layered.stack import K_NODES
from dentalux.reading.layered.window import K_SCALE
from scipy.interpolate import BarycentricInterpolator, CubicSpline


@pytest.mark.parametrize("n", [2, 3, 4, 5, 9, 12])
def test_cubic_spline_is_scipys_not_a_knot_spline(n):
    # the nodes the window's reading uses (asinh of the spatial frequencies), and a few
    # uneven ones
    for x in (np.arcsinh(np.asarray(K_NODES[:n]) / K_SCALE),
              np.cumsum(np.random.default_rng(n).uniform(0.1, 2.0, n))):
        at = np.linspace(x[0] - 0.3 * (x[-1] - x[0]), x[-1] * 1.3, 301)
        want = CubicSpline(x, np.eye(n))(at)
        np.testing.assert_allclose(interpolate.cubic_spline(x, at), want, rtol=0,
                                   atol=1e-12 * np.abs(want).max())


@pytest.mark.parametrize("n", [2, 6, 9, 12])
def test_polynomial_is_scipys_barycentric_interpolant(n):
    # direction cosines as the cone weights use them: from the nodes' range to the normal
    # (a cone reaches past the most oblique and the most normal node), and on nodes
    mu = np.cos(np.linspace(0.05, 1.5, n))
    at = np.concatenate([np.linspace(mu.min(), 1.0, 97), mu[:2]])
    want = BarycentricInterpolator(mu, np.eye(n))(at)
    # rounding is amplified by the sum of the weights' magnitudes (the Lebesgue function),
    # large past the nodes: the tolerance scales with it, row by row
    scale = np.abs(want).sum(axis=1, keepdims=True)
    assert np.all(np.abs(interpolate.polynomial(mu, at) - want) <= 1e-12 * scale)


def test_bad_nodes_are_refused():
    with pytest.raises(ValueError, match="strictly increasing"):
        interpolate.cubic_spline(np.array([0.0, 2.0, 1.0, 3.0]), np.array([0.5]))
    with pytest.raises(ValueError, match="at least 2"):
        interpolate.cubic_spline(np.array([0.0]), np.array([0.5]))
    with pytest.raises(ValueError, match="distinct"):
        interpolate.polynomial(np.array([0.0, 1.0, 1.0]), np.array([0.5]))
