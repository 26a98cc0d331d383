"""Spectral reconstruction: from a few simulated bands [nm] to a spectrum on a fine grid.

Every Monte Carlo run is one wavelength (a *band*). Three ways to choose bands:

- ``paper``: the paper's measured wavelengths 450, 540, 605 nm only (Jung et al. 2012,
  Table 1). Between them the spectrum is interpolated linearly; outside them it needs an
  extrapolation *basis*, which the paper constrains by the measured D65 totals.
- ``full``: a sweep 380-780 nm every 10 nm (41 bands; ``full_bands(step=...)`` for others),
  material coefficients interpolated from the material spectra (the paper's future work).
- an explicit list of bands.

A :class:`Reconstruction` is a linear operator: spectrum on the grid = ``M @ band values``,
so the same operator serves a single disc and every pixel of an image. Bases outside the
first/last band (``lo``, ``hi``; v_lo, v_hi are the end values, s_lo, s_hi the slopes of the
end segments):

- ``zero``: 0 outside. Linear interpolation alone, the paper's starting point.
- ``hold``: v_lo below, v_hi above (nearest value, no constraint).
- ``constant`` (fitted): gamma * v_lo below and gamma * v_hi above, one gamma for both sides.
- ``linear`` (fitted): v_end + alpha * s_end * (l - l_end), the end segments continued with
  their slope scaled by one alpha (alpha = 1 is plain linear extrapolation, smooth at the
  ends).

For ``constant`` and ``linear`` the parameter is fitted so that the D65-weighted mean of the
reconstructed spectrum, sum D65(l) x(l) / sum D65(l) over the grid, equals a measured D65
total (Table 1's D65 row). The spectrum is linear in the parameter, so the fit is closed
form. See docs/colour.md for the bases' effect on colour.
"""

from __future__ import annotations

import csv
from functools import lru_cache
from pathlib import Path

import numpy as np

from dentalux._lazy import colour

PAPER_BANDS = (450.0, 540.0, 605.0)
BASES = ("zero", "hold", "constant", "linear")
FITTED_BASES = ("constant", "linear")
#: default fine grid [nm] for reconstruction and D65 weighting (D65 in colour-science ends at 780)
FINE_GRID = np.arange(380.0, 781.0, 1.0)
DATA = Path(__file__).parent / "data"


def full_bands(start: float = 380.0, stop: float = 780.0, step: float = 10.0) -> np.ndarray:
    """The ``full`` sweep: start, start + step, ..., stop [nm] (41 bands by default)."""
    if not (step > 0 and stop > start and start > 0):
        raise ValueError(f"bands: need 0 < start < stop and step > 0, got {start}, {stop}, {step}")
    n = int(round((stop - start) / step))
    return start + step * np.arange(n + 1)


def resolve_bands(spec="full", step: float = 10.0) -> np.ndarray:
    """``'paper'`` | ``'full'`` | a list of wavelengths [nm] -> sorted band array."""
    if isinstance(spec, str):
        if spec == "paper":
            return np.array(PAPER_BANDS)
        if spec == "full":
            return full_bands(step=step)
        raise ValueError(f"bands = {spec!r}: allowed 'paper', 'full' or a list of wavelengths")
    try:
        bands = np.asarray(spec, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"bands = {spec!r}: expected numbers [nm]") from None
    from dentalux.limits import check_band_count

    check_band_count(bands.size, "bands")
    if bands.size == 0 or not np.all(np.isfinite(bands)) or np.any(bands <= 0):
        raise ValueError(f"bands = {spec!r}: need at least one positive finite wavelength [nm]")
    if np.any(np.diff(bands) <= 0):
        raise ValueError(f"bands = {spec!r}: must be strictly increasing")
    from dentalux.limits import check_bands_in

    # the colour range, as for render (docs/limits.md); a material's own range is the caller's
    check_bands_in(bands.tolist(), -np.inf, np.inf, "", "bands", extrapolate=True)
    return bands


class Reconstruction:
    """Linear map from band values (..., bands) to a spectrum (..., grid).

    ``bands`` [nm], ``grid`` [nm] (default 380-780 nm every 1 nm), ``basis`` one of
    :data:`BASES`, ``param`` the basis parameter (gamma or alpha; 1 by default).
    """

    def __init__(self, bands, grid=None, basis: str = "hold", param: float = 1.0):
        self.bands = resolve_bands(bands)
        self.grid = np.asarray(FINE_GRID if grid is None else grid, dtype=float).ravel()
        if basis not in BASES:
            raise ValueError(f"basis = {basis!r}: allowed {', '.join(BASES)}")
        if not np.isfinite(param):
            raise ValueError(f"param = {param!r}: must be finite")
        self.basis = basis
        self.param = float(param)
        self.matrix = self._matrix(self.param)

    def _matrix(self, p: float) -> np.ndarray:
        b, g = self.bands, self.grid
        nb = len(b)
        m = np.zeros((len(g), nb))
        eye = np.eye(nb)
        for k in range(nb):  # interpolation inside [b0, b_last], exact at the bands
            m[:, k] = np.interp(g, b, eye[k], left=0.0, right=0.0)
        lo, hi = g < b[0], g > b[-1]
        if self.basis == "zero":
            return m
        gamma = p if self.basis == "constant" else 1.0
        m[lo, 0] = gamma
        m[hi, -1] = gamma
        if self.basis == "linear" and nb > 1:
            t_lo = p * (g[lo] - b[0]) / (b[1] - b[0])  # negative below the first band
            m[lo, 0] -= t_lo
            m[lo, 1] += t_lo
            t_hi = p * (g[hi] - b[-1]) / (b[-1] - b[-2])
            m[hi, -1] += t_hi
            m[hi, -2] -= t_hi
        return m

    def __call__(self, values) -> np.ndarray:
        v = np.asarray(values, dtype=float)
        if v.shape[-1] != len(self.bands):
            raise ValueError(
                f"values have {v.shape[-1]} bands, the reconstruction {len(self.bands)}"
            )
        return v @ self.matrix.T

    def fit(self, values, target: float, illuminant: str = "D65") -> Reconstruction:
        """A copy whose parameter makes the illuminant-weighted mean equal ``target``."""
        if self.basis not in FITTED_BASES:
            raise ValueError(f"basis = {self.basis!r} has no parameter; fit {FITTED_BASES}")
        w = illuminant_weights(illuminant, tuple(self.grid))
        v = np.asarray(values, dtype=float)
        base = w @ (self._matrix(0.0) @ v)
        slope = w @ ((self._matrix(1.0) - self._matrix(0.0)) @ v)
        if abs(slope) < 1e-15:
            raise ValueError("the D65 constraint does not depend on the basis parameter")
        return Reconstruction(self.bands, self.grid, self.basis, (target - base) / slope)


@lru_cache(maxsize=8)
def illuminant_weights(illuminant: str = "D65", grid: tuple = tuple(FINE_GRID)) -> np.ndarray:
    """S(l) / sum S on ``grid`` (colour-science's SPD, interpolated), for weighted means."""
    if illuminant not in colour.SDS_ILLUMINANTS:
        raise ValueError(f"illuminant = {illuminant!r}: not a colour-science illuminant")
    sd = colour.SDS_ILLUMINANTS[illuminant]
    g = np.asarray(grid, dtype=float)
    if g[0] < sd.wavelengths[0] or g[-1] > sd.wavelengths[-1]:
        raise ValueError(
            f"grid {g[0]:.0f}-{g[-1]:.0f} nm exceeds {illuminant}'s "
            f"{sd.wavelengths[0]:.0f}-{sd.wavelengths[-1]:.0f} nm"
        )
    s = np.asarray(sd[g], dtype=float)
    return s / s.sum()


def weighted_mean(spectrum_on_grid, grid=None, illuminant: str = "D65") -> float:
    """Illuminant-weighted mean sum S x / sum S (the 'D65 total' of a spectrum)."""
    g = FINE_GRID if grid is None else np.asarray(grid, dtype=float)
    return float(illuminant_weights(illuminant, tuple(g)) @ np.asarray(spectrum_on_grid, float))


def _read_csv(path: Path) -> list[dict]:
    with path.open() as f:
        rows = [line for line in f if line.strip() and not line.lstrip().startswith("#")]
    return list(csv.DictReader(rows))


def table1() -> dict[str, np.ndarray]:
    """Table 1 of the paper (0.5 mm biomaterial disc): wavelength_nm, tt, tr, n, g, thickness_mm."""
    rows = _read_csv(DATA / "table1.csv")
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def table1_d65() -> dict[str, float]:
    """Table 1's D65 row: D65-weighted tt, tr, ta (fractions), n, g, thickness_mm."""
    row = _read_csv(DATA / "table1_d65.csv")[0]
    return {k: (v if k == "illuminant" else float(v)) for k, v in row.items()}


def paper_reconstruction(quantity: str = "tt", basis: str = "constant",
                         grid=None) -> Reconstruction:
    """The paper-mode reconstruction of Table 1's ``tt`` or ``tr``, fitted to its D65 row."""
    if quantity not in ("tt", "tr"):
        raise ValueError(f"quantity = {quantity!r}: allowed 'tt' or 'tr'")
    t = table1()
    rec = Reconstruction(t["wavelength_nm"], grid, basis)
    if basis in FITTED_BASES:
        rec = rec.fit(t[quantity], table1_d65()[quantity])
    return rec


def linear_only_fraction(grid=None) -> dict[str, float]:
    """The paper's argument: share of D65 power transmitted with linear interpolation only.

    Returns ``interpolated`` (sum D65 x TT_lin / sum D65, TT_lin = 0 outside 450-605 nm),
    ``measured`` (Table 1's D65 tt) and ``accounted`` (their ratio).
    """
    t = table1()
    rec = Reconstruction(t["wavelength_nm"], grid, "zero")
    frac = weighted_mean(rec(t["tt"]), rec.grid)
    measured = table1_d65()["tt"]
    return {"interpolated": frac, "measured": measured, "accounted": frac / measured}
