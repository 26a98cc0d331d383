"""Long inversion validation (``make validate``): every model on every Table 1 row with
Monte Carlo round trips, the synthetic grid with adding-doubling and Monte Carlo, and the
agreement of the ad and mc forward models."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from dentalux.inverse import fit
from dentalux.inverse.models import Sample, get_model
from dentalux.slab import Layer, simulate

pytestmark = pytest.mark.slow

ROWS = [  # tt, tr, n of Table 1 (450, 540, 605 nm, D65); g = 0.75, d = 0.5 mm
    (0.4897, 0.3016, 1.550),
    (0.6016, 0.3243, 1.540),
    (0.6540, 0.3255, 1.537),
    (0.6121, 0.3228, 1.540),
]


@pytest.mark.parametrize("row", ROWS)
def test_table1_every_row_mc_round_trip(row):
    tt, tr, n = row
    r = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="mc")
    chk = simulate([Layer(mua=r.mua, mus=r.mus, g=0.75, n=n, thickness=0.5)],
                   n_photons=2_000_000, seed=31337, estimator="weighted")
    assert abs(chk.total_transmittance - tt) < 0.003
    assert abs(chk.total_reflectance - tr) < 0.003
    for model in ("ad", "telegrapher"):
        other = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model=model)
        assert other.residual < 1e-4
    ad = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="ad")
    assert r.mua_ci[0] <= ad.mua <= r.mua_ci[1] and r.mus_ci[0] <= ad.mus <= r.mus_ci[1]
    km = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="km", km_k2=0.0)
    assert km.residual < 1e-4
    with pytest.raises(ValueError, match="cannot reproduce"):
        fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="km")


FORWARD = [
    (0.1147, 7.44, 0.75, 1.55, 0.5), (0.01, 6.0, 0.96, 1.63, 1.0), (0.1, 6.0, 0.96, 1.63, 1.0),
    (0.35, 28.0, 0.93, 1.54, 1.0), (0.1, 20.0, 0.9, 1.0, 2.0), (0.5, 2.0, 0.0, 1.4, 0.3),
    (0.01, 50.0, 0.75, 1.5, 3.0), (2.0, 0.5, 0.5, 1.33, 0.2),
]


@pytest.mark.parametrize("case", FORWARD)
def test_ad_agrees_with_mc(case):
    mua, mus, g, n, d = case
    res = simulate([Layer(mua=mua, mus=mus, g=g, n=n, thickness=d)], n_photons=500_000,
                   seed=5, estimator="weighted")
    tt, tr = get_model("ad").forward(mua, mus, Sample(g=g, n=n, thickness=d))
    # 4 standard errors plus 5e-4 for the adding-doubling quadrature
    assert abs(tt - res.total_transmittance) < 4 * res.stderr["total_transmittance"] + 5e-4
    assert abs(tr - res.total_reflectance) < 4 * res.stderr["total_reflectance"] + 5e-4


def _coverage(model, generator, cases, rng):
    gen = get_model(generator)
    covered = fitted = 0
    misses = []
    for mua, mus, g, n, d in cases:
        tt, tr = gen.forward(mua, mus, Sample(g=g, n=n, thickness=d))
        e = rng.uniform(-0.005, 0.005, 2)
        try:
            r = fit(tt=float(tt) + e[0], tr=float(tr) + e[1], n=n, g=g, thickness=d,
                    model=model)
        except ValueError as exc:
            assert "bound crossed" in str(exc) or "out of range" in str(exc), str(exc)
            continue
        fitted += 1
        ok = r.mua_ci[0] <= mua <= r.mua_ci[1] and r.mus_ci[0] <= mus <= r.mus_ci[1]
        covered += ok
        if not ok:
            misses.append((mua, mus, g, n, d, r.mua_ci, r.mus_ci))
    return covered, fitted, misses


def test_synthetic_grid_ad(np_rng):
    grid = list(itertools.product([0.001, 0.03, 0.3, 2.0], [0.5, 5.0, 50.0], [0.0, 0.75, 0.96],
                                  [1.0, 1.63], [0.2, 1.0, 3.0]))
    covered, fitted, misses = _coverage("ad", "ad", grid, np_rng)
    assert fitted >= 150
    assert covered >= 0.95 * fitted, misses


def test_synthetic_grid_mc(np_rng):
    # Independent data (adding-doubling) + noise, inverted by Monte Carlo.
    grid = list(itertools.product([0.001, 0.1, 2.0], [0.5, 5.0, 50.0], [0.0, 0.9],
                                  [1.0, 1.63], [0.2, 3.0]))
    grid = grid[::2]
    covered, fitted, misses = _coverage("mc", "ad", grid, np_rng)
    assert fitted >= 0.7 * len(grid)
    assert covered >= 0.95 * fitted, misses


def test_mc_noise_free_round_trip():
    # Data from an independent Monte Carlo run (other seed); the fit recovers the truth
    # within its interval and reproduces the data within 0.003.
    for mua, mus, g, n, d in [(0.05, 5.0, 0.75, 1.54, 0.5), (0.5, 20.0, 0.9, 1.4, 1.0)]:
        res = simulate([Layer(mua=mua, mus=mus, g=g, n=n, thickness=d)], n_photons=2_000_000,
                       seed=99, estimator="weighted")
        r = fit(tt=res.total_transmittance, tr=res.total_reflectance, n=n, g=g, thickness=d,
                model="mc")
        assert r.mua_ci[0] <= mua <= r.mua_ci[1] and r.mus_ci[0] <= mus <= r.mus_ci[1]
        assert np.isclose(r.fit_tt, res.total_transmittance, atol=0.003)
