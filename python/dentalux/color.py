"""Colorimetry: spectra [nm] -> CIE XYZ -> CIELAB, linear sRGB, display sRGB, CIEDE2000.

All colour data (CMFs, illuminant SPDs, sRGB primaries, the sRGB transfer function) come
from colour-science; this module only chooses the conventions. A reading's path does not
import colour-science (about 0.3 s of every command-line reading): the integration weights
of the default systems are kept in ``data/colour_weights.json`` (derived from
colour-science's data by ``data/make_colour_weights.py``), and CIELAB and CIEDE2000 are
written out here; tests/test_color.py holds all three to colour-science's own results.

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

import json
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
    ``tabulated``: take the weights from ``data/colour_weights.json`` where it has this
    system (what colour-science computes, kept so that a reading need not import it);
    otherwise colour-science computes them.
    """

    def __init__(self, illuminant: str = "D65", observer: str = "2", grid=GRID,
                 tabulated: bool = True):
        start, end, step = (float(x) for x in grid)
        if not (step > 0 and end > start):
            raise ValueError(f"grid = {grid!r}: need start < end and step > 0 [nm]")
        self.illuminant = illuminant
        self.observer = _observer_name(observer)
        self.wavelengths = np.arange(round((end - start) / step) + 1) * step + start
        table = _tabulated().get((illuminant, self.observer, (start, end, step))) \
            if tabulated else None
        if table is not None:
            self.weights, self.white_xy = table
        else:
            self.weights, self.white_xy = self._computed(start, end, step)
        self.white_XYZ = self.weights.sum(axis=1)

    def _computed(self, start: float, end: float, step: float):
        """The weights and the white's chromaticity by colour-science: its integration of
        unit spectra, scaled so that rho = 1 gives Y = 1."""
        sd = _illuminant_sd(self.illuminant)
        if start < sd.wavelengths[0] or end > sd.wavelengths[-1]:
            raise ValueError(
                f"grid = {(start, end, step)!r}: illuminant {self.illuminant} covers only "
                f"{sd.wavelengths[0]:.0f}-{sd.wavelengths[-1]:.0f} nm"
            )
        shape = colour.SpectralShape(start, end, step)
        if not np.array_equal(np.asarray(shape.wavelengths, float), self.wavelengths):
            raise ValueError(f"grid = {(start, end, step)!r}: the step does not divide it")
        weights = colour.msds_to_XYZ(
            np.eye(len(self.wavelengths)), cmfs=colour.MSDS_CMFS[self.observer].copy()
            .align(shape), illuminant=sd.align(shape), method="Integration", shape=shape,
        ).T / 100.0  # (3, n)
        return weights, colour.XYZ_to_xy(weights.sum(axis=1))

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
        return xyz_to_lab(XYZ, self.white_xy)

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


def xyz_to_lab(XYZ, white_xy) -> np.ndarray:
    """CIE 1976 L*a*b* (CIE 015:2018, eqs. 8.1-8.3) of XYZ (..., 3) on the Y = 1 scale,
    against the white of chromaticity ``white_xy`` at Y = 1. Written out (as colour-science's
    XYZ_to_Lab computes it, which the tests hold it to) so that a reading need not import
    colour-science."""
    x, y = (float(v) for v in white_xy)
    per_y = 1.0 / y
    t = np.asarray(XYZ, float) / np.array([x * per_y, 1.0, (1.0 - (x + y)) * per_y])
    # the cube root above (6/29)^3, its tangent line through 4/29 below
    f = np.where(t > (24 / 116) ** 3, np.abs(t) ** (1 / 3), (841 / 108) * t + 16 / 116)
    fx, fy, fz = np.moveaxis(f, -1, 0)
    return np.stack([116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)], axis=-1)


def delta_e00(lab1, lab2) -> np.ndarray:
    """CIEDE2000 colour difference (kL = kC = kH = 1; CIE 142:2001, in the notation of
    Sharma, Wu & Dalal 2005, Color Res Appl 30:21, eqs. 1-22) between CIELAB colours
    (..., 3). Written out so that a reading need not import colour-science; the tests hold
    it to Sharma's published pairs and to colour-science's implementation."""
    L1, a1, b1 = np.moveaxis(np.asarray(lab1, float), -1, 0)
    L2, a2, b2 = np.moveaxis(np.asarray(lab2, float), -1, 0)
    # a* stretched by G (eqs. 2-4), so that near-neutral colours weigh hue less
    c7 = ((np.hypot(a1, b1) + np.hypot(a2, b2)) / 2) ** 7
    g = 0.5 * (1 - np.sqrt(c7 / (c7 + 25.0 ** 7)))
    a1, a2 = a1 * (1 + g), a2 * (1 + g)
    c1, c2 = np.hypot(a1, b1), np.hypot(a2, b2)
    h1 = np.degrees(np.arctan2(b1, a1)) % 360
    h2 = np.degrees(np.arctan2(b2, a2)) % 360
    # differences (eqs. 8-11): the hue angle's the short way round, none without chroma
    chromatic = c1 * c2 != 0
    dh = h2 - h1
    dh = np.where(dh > 180, dh - 360, np.where(dh < -180, dh + 360, dh))
    dh = np.where(chromatic, dh, 0.0)
    d_l, d_c = L2 - L1, c2 - c1
    d_h = 2 * np.sqrt(c1 * c2) * np.sin(np.radians(dh / 2))
    # means (eqs. 12-14): the hue's the short way round, the sum without chroma
    l_m, c_m = (L1 + L2) / 2, (c1 + c2) / 2
    h_sum = h1 + h2
    h_m = np.where(np.abs(h1 - h2) <= 180, h_sum / 2,
                   np.where(h_sum < 360, (h_sum + 360) / 2, (h_sum - 360) / 2))
    h_m = np.where(chromatic, h_m, h_sum)
    # weights (eqs. 15-22)
    t = (1 - 0.17 * np.cos(np.radians(h_m - 30)) + 0.24 * np.cos(np.radians(2 * h_m))
         + 0.32 * np.cos(np.radians(3 * h_m + 6)) - 0.20 * np.cos(np.radians(4 * h_m - 63)))
    rotation = 30 * np.exp(-(((h_m - 275) / 25) ** 2))
    r_c = 2 * np.sqrt(c_m ** 7 / (c_m ** 7 + 25.0 ** 7))
    s_l = 1 + 0.015 * (l_m - 50) ** 2 / np.sqrt(20 + (l_m - 50) ** 2)
    s_c = 1 + 0.045 * c_m
    s_h = 1 + 0.015 * c_m * t
    r_t = -np.sin(np.radians(2 * rotation)) * r_c
    dl, dc, dhh = d_l / s_l, d_c / s_c, d_h / s_h
    out = np.sqrt(dl ** 2 + dc ** 2 + dhh ** 2 + r_t * dc * dhh)
    return out[()] if out.ndim == 0 else out


@lru_cache(maxsize=1)
def _tabulated() -> dict:
    """data/colour_weights.json by (illuminant, observer name, grid): (weights, white xy)."""
    doc = json.loads((Path(__file__).parent / "data" / "colour_weights.json").read_text())
    return {(e["illuminant"], e["observer"], tuple(map(float, e["grid"]))):
            (np.array(e["weights"], float), np.array(e["white_xy"], float))
            for e in doc["systems"]}


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
