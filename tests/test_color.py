"""Colorimetry: colour-science round trips, Sharma's CIEDE2000 pairs, images and files."""

import json
import subprocess
import sys

import colour
import numpy as np
import pytest
from dentalux import color, io
from dentalux.spectra import full_bands

# Sharma, Wu, Dalal 2005 (Color Res Appl 30:21), Table 1: (Lab1, Lab2, ΔE00)
SHARMA = [
    ((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
    ((50.0, 3.1571, -77.2803), (50.0, 0.0, -82.7485), 2.8615),
    ((50.0, 2.8361, -74.0200), (50.0, 0.0, -82.7485), 3.4412),
    ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
    ((50.0, 2.49, -0.001), (50.0, -2.49, 0.0009), 7.1792),
    ((50.0, 2.5, 0.0), (50.0, 0.0, -2.5), 4.3065),
    ((50.0, 2.5, 0.0), (73.0, 25.0, -18.0), 27.1492),
    ((50.0, 2.5, 0.0), (61.0, -5.0, 29.0), 22.8977),
    ((50.0, 2.5, 0.0), (56.0, -27.0, -3.0), 31.9030),
    ((50.0, 2.5, 0.0), (58.0, 24.0, 15.0), 19.4535),
    ((60.2574, -34.0099, 36.2677), (60.4626, -34.1751, 39.4387), 1.2644),
    ((63.0109, -31.0961, -5.8663), (62.8187, -29.7946, -4.0864), 1.2630),
]


@pytest.mark.parametrize("observer", ["2", "10"])
@pytest.mark.parametrize("illuminant", ["D65", "A"])
def test_white_and_grey_round_trip(observer, illuminant):
    bands = full_bands()
    white = color.spectrum_to_Lab(np.ones(len(bands)), bands, illuminant, observer)
    np.testing.assert_allclose(white, [100.0, 0.0, 0.0], atol=1e-9)
    grey = color.spectrum_to_Lab(np.full(len(bands), 0.18), bands, illuminant, observer)
    # CIE L* of Y = 0.18: 116 * 0.18^(1/3) - 16
    assert grey[0] == pytest.approx(116 * 0.18 ** (1 / 3) - 16, abs=0.01)
    assert grey[0] == pytest.approx(49.5, abs=0.01)
    np.testing.assert_allclose(grey[1:], 0.0, atol=0.01)


def test_sharma_pairs():
    lab1 = np.array([p[0] for p in SHARMA])
    lab2 = np.array([p[1] for p in SHARMA])
    expected = np.array([p[2] for p in SHARMA])
    np.testing.assert_allclose(color.delta_e00(lab1, lab2), expected, atol=1e-4)
    np.testing.assert_allclose(color.delta_e00(lab2, lab1), expected, atol=1e-4)


def test_xyz_agrees_with_colour_science_astm_e308():
    """A smooth spectrum: our 10 nm bands + integration vs colour-science's ASTM E308 path."""
    wl = np.arange(360.0, 781.0, 1.0)
    refl = 0.2 + 0.5 * np.exp(-0.5 * ((wl - 600.0) / 60.0) ** 2)
    sd = colour.SpectralDistribution(dict(zip(wl, refl, strict=True)))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    xyz_ref = colour.sd_to_XYZ(sd, cmfs, d65) / 100.0
    white_ref = colour.sd_to_XYZ(colour.sd_ones(), cmfs, d65) / 100.0
    lab_ref = colour.XYZ_to_Lab(xyz_ref, colour.XYZ_to_xy(white_ref))
    bands = full_bands()
    lab = color.spectrum_to_Lab(np.interp(bands, wl, refl), bands)
    assert float(color.delta_e00(lab, lab_ref)) < 0.05


def test_white_maps_to_srgb_white_and_sharma_e76():
    # colour-science uses the IEC 61966-2-1 matrix, rounded to 4 decimals: white within 2e-4
    cs = color.system("D65", "2")
    np.testing.assert_allclose(color.XYZ_to_linear_srgb(cs.white_XYZ, cs.white_xy), 1.0,
                               atol=3e-4)
    cs_a = color.system("A", "2")  # Bradford adaptation: illuminant A's white is sRGB white
    np.testing.assert_allclose(color.XYZ_to_linear_srgb(cs_a.white_XYZ, cs_a.white_xy), 1.0,
                               atol=3e-4)
    assert color.delta_e76([50, 0, 0], [53, 4, 0]) == pytest.approx(5.0)


def test_tone_maps():
    rgb = np.array([[0.5, 0.25, 0.125], [4.0, 2.0, 1.0]])
    np.testing.assert_allclose(color.tone_map(rgb, "clip"), [[0.5, 0.25, 0.125], [1, 1, 1]])
    r = color.tone_map(rgb, "reinhard")
    np.testing.assert_allclose(r[0] / r[0, 0], rgb[0] / rgb[0, 0])  # chromaticity kept
    assert np.all(r <= 1.0)
    with pytest.raises(ValueError, match="tone_map"):
        color.tone_map(rgb, "filmic")
    # sRGB encoding of 0.18: 1.055 * 0.18^(1/2.4) - 0.055 = 0.4613 -> 118
    assert color.display_srgb(np.full((1, 1, 3), 0.18))[0, 0, 0] == 118


def test_bad_inputs():
    with pytest.raises(ValueError, match="observer"):
        color.ColourSystem("D65", "5")
    with pytest.raises(ValueError, match="illuminant"):
        color.ColourSystem("D99")
    with pytest.raises(ValueError, match="covers only"):
        color.ColourSystem("D65", "2", (380, 830, 5))


def test_write_images(tmp_path):
    bands = full_bands()
    cube = np.full((6, 8, len(bands)), 0.18, dtype=np.float32)
    cube[:, :4] = 1.0
    out = color.write_images(cube, bands, tmp_path, regions={"white": [0, 0, 4, 6],
                                                             "grey": [4, 0, 8, 6]}, exposure=0.0)
    saved = json.loads((tmp_path / "colour.json").read_text())
    assert saved["regions"].keys() == {"white", "grey"}
    np.testing.assert_allclose(out["regions"]["white"]["lab"], [100, 0, 0], atol=1e-6)
    np.testing.assert_allclose(out["regions"]["grey"]["lab"], [49.496, 0, 0], atol=0.01)
    rgb = io.read_exr_rgb(tmp_path / "image.exr")
    np.testing.assert_allclose(rgb[0, 0], 1.0, atol=3e-4)
    np.testing.assert_allclose(rgb[0, 7], 0.18, atol=1e-4)
    spec, wl = io.read_exr_spectral(tmp_path / "spectral.exr")
    np.testing.assert_array_equal(wl, bands)
    np.testing.assert_array_equal(spec, cube)
    from PIL import Image

    png = np.asarray(Image.open(tmp_path / "image.png"))
    assert tuple(png[0, 0]) == (255, 255, 255) and tuple(png[0, 7]) == (118, 118, 118)
    with pytest.raises(ValueError, match="regions.bad"):
        color.write_images(cube, bands, tmp_path, regions={"bad": [0, 0, 9, 6]})
    with pytest.raises(ValueError, match="radiance shape"):
        color.write_images(cube[..., :3], bands, tmp_path)


def test_a_reading_imports_neither_colour_science_nor_scipy():
    # a command-line reading paid about 0.3 s for colour-science's import and 0.45 s for
    # scipy's (interpolate, special): the default colour systems' weights are tabulated,
    # CIELAB, CIEDE2000, the two interpolations and the special functions are written out or
    # bound from the core (held to those libraries here, test_interpolate.py and
    # test_special.py). Where
    # colour-science is used, its __init__'s plotting (pyplot, fonts) stays deferred until
    # one of its attributes is read (dentalux._lazy)
    code = ("import sys; from dentalux import dental; "
            "dental.read([('enamel', 1.0)], bands=[450, 550, 650]); "
            "loaded = [m for m in ('colour', 'scipy') if m in sys.modules]; "
            "assert not loaded, loaded; "
            "from dentalux import color; color.XYZ_to_linear_srgb([0.2, 0.3, 0.4]); "
            "assert 'colour' in sys.modules and 'matplotlib.pyplot' not in sys.modules; "
            "import colour; assert callable(colour.plotting.plot_single_colour_swatch); "
            "assert 'matplotlib.pyplot' in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("observer", ["2", "10"])
def test_tabulated_weights_are_colour_sciences(observer):
    """data/colour_weights.json holds what colour-science computes now, to the bit."""
    kept = color.ColourSystem("D65", observer)
    computed = color.ColourSystem("D65", observer, tabulated=False)
    assert np.array_equal(kept.weights, computed.weights)
    assert np.array_equal(kept.white_xy, computed.white_xy)
    assert np.array_equal(kept.wavelengths, computed.wavelengths)


def test_cielab_and_ciede2000_are_colour_sciences():
    rng = np.random.default_rng(5)
    xyz = rng.uniform(-0.01, 1.1, (4000, 3))
    xyz[:1000] *= 0.01  # below (6/29)^3 of the white: the linear part
    for white in (color.system("D65", "2").white_xy, colour.CCS_ILLUMINANTS[
            "CIE 1931 2 Degree Standard Observer"]["A"]):
        np.testing.assert_allclose(color.xyz_to_lab(xyz, white), colour.XYZ_to_Lab(xyz, white),
                                   rtol=0, atol=1e-12)
    lab1 = rng.uniform([0, -120, -120], [100, 120, 120], (4000, 3))
    lab2 = lab1 + rng.normal(0, 5, lab1.shape)
    lab1[:300, 1:] = 0       # neutral against coloured
    lab2[300:600, 1:] = 0
    lab2[600:900] = lab1[600:900]  # identical
    lab2[900:1200, 1:] = -lab1[900:1200, 1:]  # hues 180 degrees apart
    np.testing.assert_allclose(color.delta_e00(lab1, lab2),
                               colour.difference.delta_E_CIE2000(lab1, lab2), rtol=0, atol=1e-12)
    one = color.delta_e00(lab1[0], lab2[0])
    assert np.ndim(one) == 0 and one == pytest.approx(
        float(colour.difference.delta_E_CIE2000(lab1[0], lab2[0])), abs=1e-12)
