"""The layered solver's special functions (dentalux.reading.layered.special) against
scipy.special's: Bessel J0 and J1 over the arguments the window kernels reach, and the
normalised associated Legendre functions."""

import numpy as np
import pytest
from dentalux import _core
from dentalux.reading.layered import special
from scipy.special import gammaln, j0, j1, lpmv


def test_bessel_functions_are_scipys():
    # the window kernels: k up to about 8 x 32 /mm times radii and distances up to 20 mm
    x = np.concatenate([np.linspace(0.0, 50.0, 20_001), np.geomspace(50.0, 6000.0, 5_000)])
    for ours, theirs in ((special.j0, j0), (special.j1, j1)):
        got = ours(x)
        assert got.shape == x.shape
        # both are approximations good to a few 1e-15 in absolute terms (cephes in scipy, FreeBSD
        # msun in libm): they differ by up to 5e-15 where |J| is about 0.01
        np.testing.assert_allclose(got, theirs(x), rtol=0, atol=1e-14)
    # any shape comes back as given
    grid = x[:24].reshape(2, 3, 4)
    assert special.j0(grid).shape == (2, 3, 4)
    np.testing.assert_array_equal(special.j1(grid.T), special.j1(grid).T)
    with pytest.raises(ValueError, match="order = 2: allowed 0 or 1"):
        _core.bessel_j(2, x)


@pytest.mark.parametrize("modes, order", [(1, 17), (5, 17), (6, 4)])
def test_associated_legendre_functions_are_scipys(modes, order):
    x = np.concatenate([np.linspace(-1.0, 1.0, 401), np.cos(np.linspace(0, np.pi / 2, 9))])
    got = special.associated_legendre(modes, order, x)
    want = np.zeros_like(got)
    for m in range(modes):
        for ell in range(m, order):
            norm = np.exp(0.5 * (gammaln(ell - m + 1) - gammaln(ell + m + 1)))
            want[m, ell] = lpmv(m, ell, x) * norm
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)
