"""Colorimetry: spectra [nm] -> CIE XYZ -> CIELAB, linear sRGB, display sRGB, CIEDE2000.

All colour data (CMFs, illuminant SPDs, sRGB primaries, the sRGB transfer function,
CIEDE2000) come from colour-science; this module only chooses the conventions:

- **Grid.** Spectra are integrated on a regular grid, 380-780 nm every 5 nm by default. CIE
  D65 in colour-science stops at 780 nm, so the grid never goes past 780 nm (the CMFs above
  780 nm carry < 0.01 % of Y).
- **XYZ.** ``XYZ = k * sum S(l) cmf(l) rho(l) dl`` by colour-science's ``'Integration'``
  method on that grid, with ``k`` such that ``rho = 1`` (a perfect diffuser / perfect
  transmitter) gives Y = 1. ``rho`` is a reflectance or transmittance factor, or a radiance
  relative to the light's own spectral radiance (see :func:`write_images`).
- **CIELAB.** The white point is the XYZ of ``rho = 1`` computed by the *same* function, CMFs,
  illuminant and grid, so a perfect white gives exactly L* = 100, a* = b* = 0 (the rounded
  tabulated white point would leave a* and b* off by ~0.01).
- **sRGB.** XYZ -> linear sRGB (IEC 61966-2-1 primaries) with a Bradford adaptation from the
  illuminant's white to D65 when they differ; the display image applies the exposure
  (``2**exposure``), the tone map and the sRGB encoding (see :func:`display_srgb`).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from dentalux._lazy import colour
from dentalux.strict_json import dumps_strict

OBSERVERS = {
    "2": "CIE 1931 2 Degree Standard Observer",
    "1931": "CIE 1931 2 Degree Standard Observer",
    "10": "CIE 1964 10 Degree Standard Observer",
    "1964": "CIE 1964 10 Degree Standard Observer",
}
TONE_MAPS = ("clip", "reinhard")
GRID = (380.0, 780.0, 5.0)


def _observer_name(observer: str) -> str:
    key = str(observer)
    if key in OBSERVERS:
        return OBSERVERS[key]
    if key in OBSERVERS.values():
        return key
    raise ValueError(f"observer = {observer!r}: allowed '2' (CIE 1931) or '10' (CIE 1964)")


def _illuminant_sd(illuminant: str) -> colour.SpectralDistribution:
    if illuminant not in colour.SDS_ILLUMINANTS:
        raise ValueError(
            f"illuminant = {illuminant!r}: allowed a colour-science illuminant such as "
            "'D65', 'D50', 'A', 'FL2'"
        )
    return colour.SDS_ILLUMINANTS[illuminant].copy()


class ColourSystem:
    """Spectra on a fixed grid -> XYZ (Y = 1 for rho = 1) for one illuminant and observer.

    ``grid = (start, end, step)`` in nm; the illuminant must cover it (D65: 300-780 nm).
    """

    def __init__(self, illuminant: str = "D65", observer: str = "2", grid=GRID):
        start, end, step = (float(x) for x in grid)
        if not (step > 0 and end > start):
            raise ValueError(f"grid = {grid!r}: need start < end and step > 0 [nm]")
        self.illuminant = illuminant
        self.observer = _observer_name(observer)
        sd = _illuminant_sd(illuminant)
        if start < sd.wavelengths[0] or end > sd.wavelengths[-1]:
            raise ValueError(
                f"grid = {grid!r}: illuminant {illuminant} covers only "
                f"{sd.wavelengths[0]:.0f}-{sd.wavelengths[-1]:.0f} nm"
            )
        self.shape = colour.SpectralShape(start, end, step)
        self.wavelengths = np.asarray(self.shape.wavelengths, dtype=float)
        self.cmfs = colour.MSDS_CMFS[self.observer].copy().align(self.shape)
        self.illuminant_sd = sd.align(self.shape)
        # the 3 x n weights of the integration, computed by colour-science on unit vectors
        eye = np.eye(len(self.wavelengths))
        self.weights = self._integrate(eye).T / 100.0  # (3, n), rho = 1 -> Y = 1
        self.white_XYZ = self.weights.sum(axis=1)
        self.white_xy = colour.XYZ_to_xy(self.white_XYZ)

    def _integrate(self, values: np.ndarray) -> np.ndarray:
        return colour.msds_to_XYZ(
            values, cmfs=self.cmfs, illuminant=self.illuminant_sd, method="Integration",
            shape=self.shape,
        )

    def grid_to_XYZ(self, values: np.ndarray) -> np.ndarray:
        """Spectra on this grid, shape (..., n) -> XYZ (..., 3) with Y = 1 for rho = 1."""
        values = np.asarray(values, dtype=float)
        if values.shape[-1] != len(self.wavelengths):
            raise ValueError(
                f"spectrum has {values.shape[-1]} samples, the grid {len(self.wavelengths)}"
            )
        return values @ self.weights.T

    def XYZ_to_Lab(self, XYZ: np.ndarray) -> np.ndarray:
        """CIELAB with this system's computed white (L* in [0, 100])."""
        return colour.XYZ_to_Lab(np.asarray(XYZ, dtype=float), self.white_xy)

    def spectrum_to_XYZ(self, values, wavelengths_nm, reconstruction=None) -> np.ndarray:
        """Band values (..., bands) at ``wavelengths_nm`` -> XYZ (..., 3).

        The spectrum between bands is reconstructed by ``reconstruction`` (a
        :class:`dentalux.spectra.Reconstruction`); by default linear interpolation, held
        constant outside the bands.
        """
        from dentalux.spectra import Reconstruction

        rec = reconstruction or Reconstruction(wavelengths_nm, grid=self.wavelengths)
        matrix = rec.matrix
        if len(rec.grid) != len(self.wavelengths) or np.any(rec.grid != self.wavelengths):
            # resample the reconstruction onto this grid (linear between its grid points)
            matrix = np.stack([np.interp(self.wavelengths, rec.grid, col) for col in matrix.T],
                              axis=1)
        values = np.asarray(values, dtype=float)
        if values.shape[-1] != len(rec.bands):
            raise ValueError(f"values have {values.shape[-1]} bands, expected {len(rec.bands)}")
        # fold the (linear) reconstruction into the weights: 3 x bands, no grid-sized arrays
        return values @ (self.weights @ matrix).T

    def spectrum_to_Lab(self, values, wavelengths_nm, reconstruction=None) -> np.ndarray:
        """Band values -> CIELAB (see :meth:`spectrum_to_XYZ`)."""
        return self.XYZ_to_Lab(self.spectrum_to_XYZ(values, wavelengths_nm, reconstruction))


@lru_cache(maxsize=16)
def system(illuminant: str = "D65", observer: str = "2", grid=GRID) -> ColourSystem:
    """A cached :class:`ColourSystem`."""
    return ColourSystem(illuminant, observer, tuple(grid))


def spectrum_to_XYZ(values, wavelengths_nm, illuminant="D65", observer="2",
                    reconstruction=None) -> np.ndarray:
    """Band values (..., bands) -> XYZ (..., 3), Y = 1 for a perfect diffuser."""
    return system(illuminant, str(observer)).spectrum_to_XYZ(values, wavelengths_nm,
                                                             reconstruction)


def spectrum_to_Lab(values, wavelengths_nm, illuminant="D65", observer="2",
                    reconstruction=None) -> np.ndarray:
    """Band values (..., bands) -> CIELAB (..., 3) against the computed white."""
    return system(illuminant, str(observer)).spectrum_to_Lab(values, wavelengths_nm,
                                                             reconstruction)


def delta_e00(lab1, lab2) -> np.ndarray:
    """CIEDE2000 colour difference (kL = kC = kH = 1), colour-science's implementation."""
    return colour.difference.delta_E_CIE2000(np.asarray(lab1, float), np.asarray(lab2, float))


def delta_e00_scale(lab, lab_stderr, step: float = 0.01) -> float:
    """A colour's uncertainty in ΔE00 units: sqrt(Σ_j (s_j ∂ΔE00/∂x_j)²) over x = L*, a*,
    b*, the slope of ΔE00 from ``lab`` along each axis taken over ``step`` (ΔE00 has no
    derivative at zero distance; its slope there is what a small error moves it by). It is
    the ΔE00 that one standard error in every coordinate amounts to at this colour."""
    lab = np.asarray(lab, float)
    err = np.asarray(lab_stderr, float)
    slopes = np.array([float(delta_e00(lab + step * e, lab)) / step for e in np.eye(3)])
    return float(np.sqrt(np.sum((slopes * err) ** 2)))


def delta_e76(lab1, lab2) -> np.ndarray:
    """CIELAB Euclidean colour difference ΔE*ab."""
    d = np.asarray(lab1, float) - np.asarray(lab2, float)
    return np.sqrt((d * d).sum(axis=-1))


def XYZ_to_linear_srgb(XYZ, illuminant_xy=None) -> np.ndarray:
    """XYZ (Y = 1 white) -> linear sRGB; Bradford adaptation from ``illuminant_xy`` to D65."""
    xy = colour.CCS_ILLUMINANTS[OBSERVERS["2"]]["D65"] if illuminant_xy is None else illuminant_xy
    return colour.XYZ_to_RGB(
        np.asarray(XYZ, float), "sRGB", illuminant=np.asarray(xy, float),
        chromatic_adaptation_transform="Bradford", apply_cctf_encoding=False,
    )


def lab_to_display_srgb(lab, illuminant: str = "D65", observer: str = "2") -> dict:
    """A CIELAB colour (relative to the white of ``illuminant``/``observer``, as every reading
    here is) as an 8-bit display sRGB swatch: XYZ with that white, Bradford-adapted to D65,
    out-of-gamut components clipped. Returns ``{"rgb": (r, g, b), "hex": "#rrggbb",
    "clipped": bool}`` (clipped: the colour lies outside the sRGB gamut)."""
    white = system(illuminant, str(observer)).white_xy
    xyz = colour.Lab_to_XYZ(np.asarray(lab, float), white)
    linear = XYZ_to_linear_srgb(xyz, white)
    clipped = bool(np.any(linear < -1e-4) or np.any(linear > 1 + 1e-4))
    rgb = tuple(int(x) for x in display_srgb(linear))
    return {"rgb": rgb, "hex": "#{:02x}{:02x}{:02x}".format(*rgb), "clipped": clipped}


def tone_map(rgb: np.ndarray, method: str = "clip") -> np.ndarray:
    """Linear RGB -> [0, 1].

    ``clip``: negative (out-of-gamut) and > 1 values clipped; colorimetrically exact for
    everything inside the gamut and below white. ``reinhard``: each pixel's RGB is scaled
    by ``Y' / Y`` with ``Y' = Y / (1 + Y)`` (Reinhard's global operator on luminance Y, which
    keeps the chromaticity; mid-tones darken, highlights roll off), then clipped.
    """
    rgb = np.asarray(rgb, dtype=float)
    if method == "clip":
        return np.clip(rgb, 0.0, 1.0)
    if method == "reinhard":
        y = np.maximum(rgb @ np.array([0.2126, 0.7152, 0.0722]), 0.0)
        scale = np.where(y > 0, 1.0 / (1.0 + y), 1.0)
        return np.clip(rgb * scale[..., None], 0.0, 1.0)
    raise ValueError(f"tone_map = {method!r}: allowed {', '.join(TONE_MAPS)}")


def display_srgb(rgb_linear, exposure: float = 0.0, method: str = "clip") -> np.ndarray:
    """Linear sRGB -> 8-bit display sRGB: ``rgb * 2**exposure``, tone map, sRGB encoding."""
    mapped = tone_map(np.asarray(rgb_linear, float) * 2.0 ** float(exposure), method)
    encoded = colour.cctf_encoding(mapped, function="sRGB")
    return np.round(np.clip(encoded, 0.0, 1.0) * 255.0).astype(np.uint8)


def auto_exposure(rgb_linear: np.ndarray, percentile: float = 99.0) -> float:
    """Exposure [stops] that maps the given percentile of luminance to 1 (0 for a black image)."""
    y = np.asarray(rgb_linear, float) @ np.array([0.2126, 0.7152, 0.0722])
    top = float(np.percentile(y, percentile)) if y.size else 0.0
    return float(-np.log2(top)) if top > 0 else 0.0


def _region_slices(name, rect, height, width):
    try:
        x0, y0, x1, y1 = (int(v) for v in rect)
    except (TypeError, ValueError):
        raise ValueError(f"regions.{name} = {rect!r}: expected [x0, y0, x1, y1] pixels") from None
    if not (0 <= x0 < x1 <= width and 0 <= y0 < y1 <= height):
        raise ValueError(
            f"regions.{name} = {rect!r}: need 0 <= x0 < x1 <= {width} and 0 <= y0 < y1 <= {height}"
        )
    return slice(y0, y1), slice(x0, x1)


def write_images(radiance, wavelengths_nm, out_dir, illuminant="D65", regions=None,
                 exposure=None, observer="2", white=1.0, tone="clip",
                 reconstruction=None, region_extra=None) -> dict:
    """Write ``image.png``, ``image.exr``, ``spectral.exr`` and ``colour.json`` to ``out_dir``.

    ``radiance``: H x W x bands, the rendered radiance per band relative to the light's own
    spectral radiance at that band (a light of radiance 1 in every band, i.e. an
    equal-energy light; the colour is then that of the scene lit by ``illuminant``).
    ``white`` is the radiance that counts as the reference white, L* = 100: with the default
    1.0 that is the radiance of the light itself, which is what a perfect white Lambertian
    surface under a uniform hemisphere of radiance 1 sends back. XYZ per pixel =
    ``k sum S(l) cmf(l) L(l)/white dl`` with k giving Y = 1 for L = white everywhere.

    ``regions``: ``{name: [x0, y0, x1, y1]}`` pixel rectangles (x1, y1 exclusive); colour.json
    gives for each the CIELAB of the region's mean spectral radiance (the colour a
    spectrophotometer aperture would read, not a mean of per-pixel L*a*b*).
    ``region_extra(lab)``, when given, returns more keys for a region's entry (the nearest
    shade tabs). ``exposure`` in stops (None: automatic, 99th luminance percentile -> 1).
    Returns the dictionary written to colour.json (with the file paths).
    """
    from dentalux import io as dio

    cube = np.asarray(radiance, dtype=float)
    wl = np.asarray(wavelengths_nm, dtype=float).ravel()
    if cube.ndim != 3 or cube.shape[2] != len(wl):
        raise ValueError(
            f"radiance shape {cube.shape}: expected (height, width, {len(wl)} bands)"
        )
    if not np.all(np.isfinite(cube)):
        raise ValueError("radiance: contains NaN or infinity")
    if not (float(white) > 0):
        raise ValueError(f"white = {white!r}: must be > 0")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cs = system(illuminant, str(observer))
    XYZ = cs.spectrum_to_XYZ(cube / float(white), wl, reconstruction)
    rgb = XYZ_to_linear_srgb(XYZ, cs.white_xy)
    ev = auto_exposure(rgb) if exposure is None else float(exposure)
    paths = {
        "png": str(out / "image.png"),
        "exr": str(out / "image.exr"),
        "spectral_exr": str(out / "spectral.exr"),
        "json": str(out / "colour.json"),
    }
    dio.write_png(paths["png"], display_srgb(rgb, ev, tone))
    dio.write_exr_rgb(paths["exr"], rgb.astype(np.float32))
    dio.write_exr_spectral(paths["spectral_exr"], cube.astype(np.float32), wl)
    summary = {
        "illuminant": illuminant,
        "observer": cs.observer,
        "white": float(white),
        "white_XYZ": cs.white_XYZ.tolist(),
        "exposure": ev,
        "tone_map": tone,
        "wavelengths_nm": wl.tolist(),
        "regions": {},
        "files": paths,
    }
    h, w = cube.shape[:2]
    for name, rect in (regions or {}).items():
        rows, cols = _region_slices(name, rect, h, w)
        mean = cube[rows, cols].reshape(-1, len(wl)).mean(axis=0) / float(white)
        lab = cs.spectrum_to_Lab(mean, wl, reconstruction)
        summary["regions"][name] = {"rect": [int(v) for v in rect], "lab": lab.tolist(),
                                    "mean_radiance": mean.tolist(),
                                    **(region_extra(lab) if region_extra else {})}
    Path(paths["json"]).write_text(dumps_strict(summary, indent=2))
    return summary
