"""An instrument's white calibration tile (issue 40): reading = specimen / tile × the tile's
certified reflectance, with the tile's standard error carried into the reading's.

Checked against closed forms: an ideal Lambertian white at the surface reproduces today's
ideal-white normalisation; a specimen identical to the tile reads exactly the certified
reflectance (the layered solver, no noise) or 1 within its standard error (walks).
"""

import math

import numpy as np
import pytest
from dentalux import dental, instrument, reading
from dentalux.cli import main
from dentalux.spectra import resolve_bands

BANDS = [450, 550, 650]
DISCS = dict(geometry="0-d", illuminated_diameter_mm=3.0, viewed_diameter_mm=3.0,
             backing_black=0.0, backing_white=0.9)
RING = dict(geometry="0-d", illuminated_diameter_mm=3.0, illuminated_inner_diameter_mm=2.0,
            viewed_diameter_mm=1.2, backing_black=0.0, backing_white=0.9)
# a transparent film of index 1 on a perfect Lambertian reflector: an ideal white at the
# surface, whose light leaves where it entered (spread < 1e-6 mm)
IDEAL = {"mua_per_mm": 0.0, "mus_per_mm": 0.0, "g": 0.0, "n": 1.0, "thickness_mm": 1e-6,
         "reflectance": 1.0, "backing": 1.0}
ENAMEL_TILE = {"material": "enamel", "thickness_mm": 1.0,
               "reflectance": {"wavelength_nm": [400, 700], "reflectance": [0.95, 0.99]}}


def spectra(inst, photons=20_000, seed=5, solver="monte-carlo", specimen=(("enamel", 1.0),)):
    wl = resolve_bands(BANDS)
    parts = [(dental._resolve_material(m), t) for m, t in specimen]
    rb = [np.full(len(wl), b) for b in (inst.backing_black, inst.backing_white)]
    return reading.measure(reading.stacks(parts, wl), wl, inst, *rb, photons, seed,
                           solver=solver)


def test_an_ideal_white_tile_reproduces_todays_normalisation():
    """(a) A tile that is an ideal white at reflectance 1, through overlapping discs: the tile
    reads 1 within its standard error, the reading is the specimen's over the tile's exactly,
    and the colour is today's within 4 standard errors; the tile's noise reaches the s.e."""
    plain = instrument.Instrument(name="discs", **DISCS)
    tiled = plain.override(white_reference=IDEAL)
    before, after = spectra(plain), spectra(tiled)
    tile = after.extra["white_reference"]
    t, t_err = np.array(tile["tile_reading"]), np.array(tile["tile_reading_stderr"])
    assert np.all(np.abs(t - 1.0) <= 4 * t_err) and np.all(t_err > 0)
    for c in (0, 1):
        assert after.values[c] == pytest.approx(before.values[c] / t, rel=1e-12)
        # the tile's s.e. adds to the specimen's (independent walks): a^2 se_S^2 + b^2 se_T^2
        expect = np.hypot(before.stderr[c] / t, before.values[c] * t_err / t**2)
        assert np.all(np.abs(after.stderr[c] / expect - 1) < 0.3), (after.stderr[c], expect)
        assert np.all(after.stderr[c] > before.stderr[c] / t)
    assert np.array_equal(after.values[2], before.values[2])  # transmission: its own reference
    kw = dict(bands=BANDS, photons=20_000, seed=5, solver="monte-carlo")
    m0 = dental.read([("enamel", 1.0)], instrument=plain, **kw)
    m1 = dental.read([("enamel", 1.0)], instrument=tiled, **kw)
    err = m1.error("lab_white")
    for j in range(3):
        assert abs(m1.lab_white[j] - m0.lab_white[j]) <= 4 * err[j], (m0.lab_white, m1.lab_white,
                                                                        err)


@pytest.mark.parametrize("inst", [DISCS, RING], ids=["discs", "ring"])
def test_a_specimen_identical_to_the_tile_reads_its_certified_reflectance(inst):
    """(b) Same material, thickness and backing, both unbounded, the layered solver (no
    noise): the reading over black is the certified reflectance exactly (ratio 1)."""
    tiled = instrument.Instrument(name="p", **inst, white_reference=ENAMEL_TILE)
    got = spectra(tiled, solver="layered")
    cert = np.interp(BANDS, [400, 700], [0.95, 0.99])
    assert got.values[0] == pytest.approx(cert, rel=1e-12, abs=0)
    assert np.all(got.stderr[0] <= 1e-12)  # no noise: rounding only


def test_a_specimen_identical_to_the_tile_reads_1_within_se_by_walks():
    """(b) The same by independent walks through a d/8 sphere (the tile has its own seed):
    ratio 1 within 4 standard errors, which include the tile's."""
    d8 = instrument.Instrument(name="d8", geometry="d8-sci", illuminated_diameter_mm=7.0,
                               viewed_diameter_mm=4.0, backing_black=0.0, backing_white=0.9,
                               white_reference={**ENAMEL_TILE, "reflectance": 1.0})
    got = spectra(d8, photons=8000)
    assert np.all(np.abs(got.values[0] - 1.0) <= 4 * got.stderr[0]), (got.values[0],
                                                                       got.stderr[0])
    assert np.all(got.stderr[0] > 0)


def test_a_ring_probe_with_a_tile_is_white_normalised():
    """(c) A probe whose lit ring and read centre do not overlap reads the fraction of the
    incident power without a tile and a reflectance factor with one: finite, positive, over
    white above over black, the instrument JSON saying so."""
    bare = instrument.Instrument(name="ring", **RING)
    tiled = bare.override(white_reference={"mua_per_mm": 0.0005, "mus_per_mm": 20.0,
                                           "g": 0.0, "n": 1.5, "thickness_mm": 6.0,
                                           "reflectance": 0.99})
    assert not bare.white_normalised and tiled.white_normalised
    kw = dict(bands=BANDS, photons=4000, seed=2, solver="auto")
    m0 = dental.read([("enamel", 1.0), ("dentin", 2.0)], instrument=bare, **kw)
    m1 = dental.read([("enamel", 1.0), ("dentin", 2.0)], instrument=tiled, **kw)
    assert m0.instrument["white_normalised"] is False
    assert m1.instrument["white_normalised"] is True
    assert m1.instrument["white_reference"]["mus_per_mm"] == 20.0
    r_b, r_w = (np.array(m1.spectra[f"over_{k}"]) for k in ("black", "white"))
    assert np.all(np.isfinite(r_b)) and np.all(r_b > 0) and np.all(r_w > r_b)
    assert m1.lab_white[0] > m0.lab_white[0]  # the tile loses light too: the ratio is larger
    assert all(math.isfinite(v) for v in m1.stderr.values())


def test_without_a_tile_nothing_changes():
    """An instrument with no tile has no tile key in its JSON; a tile makes one."""
    probe = instrument.get("contact-probe-3mm")
    assert probe.white_reference is None and "white_reference" not in probe.to_json()
    assert probe.override(white_reference=IDEAL).to_json()["white_reference"]["backing"] == 1.0


def _file(tmp_path, tile_lines: str):
    path = tmp_path / "probe.toml"
    path.write_text('[instruments.probe]\ngeometry = "0-d"\nilluminated_diameter_mm = 3.0\n'
                    'viewed_diameter_mm = 3.0\n[instruments.probe.white_reference]\n'
                    + tile_lines)
    return path


GOOD = 'material = "enamel"\nthickness_mm = 5.0\nreflectance = 0.9\n'


@pytest.mark.parametrize("lines, named", [
    ('material = "enamel"\nreflectance = 0.9\n', "thickness_mm"),
    ('material = "enamel"\nthickness_mm = 5.0\n', "reflectance"),
    (GOOD.replace("0.9", "0.0"), "reflectance"),
    (GOOD.replace("0.9", "1.2"), "reflectance"),
    (GOOD.replace("0.9", '"0.9"'), "reflectance"),
    (GOOD.replace("0.9", "true"), "reflectance"),
    (GOOD.replace("0.9", "{ wavelength_nm = [500, 400], reflectance = [0.9, 0.9] }"),
     "reflectance.wavelength_nm"),
    (GOOD.replace("0.9", "{ wavelength_nm = [400, 700], reflectance = [0.9, 0] }"),
     "reflectance"),
    (GOOD.replace("5.0", "0.0"), "thickness_mm"),
    (GOOD.replace("5.0", "nan"), "thickness_mm"),
    (GOOD.replace('"enamel"', '"unobtainium"'), "material"),
    (GOOD.replace('"enamel"', '"missing.toml"'), "material"),
    (GOOD + "mus_per_mm = 20.0\n", "not both"),
    ("mua_per_mm = 0.0\nmus_per_mm = 20.0\nthickness_mm = 5.0\nreflectance = 0.9\n", "g, n"),
    ("mua_per_mm = 0.0\nmus_per_mm = 20.0\ng = 1.0\nn = 1.5\nthickness_mm = 5.0\n"
     "reflectance = 0.9\n", "white_reference.g"),
    ("mua_per_mm = -1.0\nmus_per_mm = 20.0\ng = 0.0\nn = 1.5\nthickness_mm = 5.0\n"
     "reflectance = 0.9\n", "mua_per_mm"),
    ("mua_per_mm = 0.0\nmus_per_mm = 20.0\ng = 0.0\nn = 0.5\nthickness_mm = 5.0\n"
     "reflectance = 0.9\n", "white_reference.n"),
    (GOOD + "backing = 1.5\n", "backing"),
    (GOOD + "diameter_mm = 2.0\n", "diameter_mm"),
    (GOOD + "fd = 0.5\n", "fd"),
    (GOOD + "colour = 1\n", "colour"),
])
def test_bad_tiles_are_refused_with_the_key_named(tmp_path, lines, named):
    """(d) Every bad key is a ValueError naming it and what is allowed."""
    with pytest.raises(ValueError, match=named) as exc:
        instrument.get(str(_file(tmp_path, lines)))
    assert "white_reference" in str(exc.value)


def test_a_bad_tile_exits_2_and_a_good_one_reads(tmp_path, capsys):
    bad = _file(tmp_path, GOOD.replace("0.9", "1.2"))
    with pytest.raises(SystemExit) as exc:
        main(["shade", "enamel", "--instrument", str(bad), "--photons", "100"])
    assert exc.value.code == 2
    assert "white_reference.reflectance" in capsys.readouterr().err
    (tmp_path / "tile.toml").write_text(
        '[materials.tile]\nwavelength_nm = [550]\nmua = [0.001]\nmus = [50.0]\ng = [0.0]\n'
        'fd = [0.0]\nn = [1.5]\nextrapolate = true\n'
        '[materials.tile.provenance]\nkind = "measured"\nsource = "a test"\n')
    good = _file(tmp_path, GOOD.replace('"enamel"', '"tile.toml"'))
    inst = instrument.get(str(good))  # relative to the instrument file
    assert inst.white_reference.resolved.name == "tile"
    assert inst.white_normalised


def test_the_infinite_instrument_takes_no_tile():
    with pytest.raises(ValueError, match="white_reference"):
        instrument.get("infinite").override(white_reference=IDEAL)
