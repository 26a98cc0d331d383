"""The instrument model: finite lit spot and window, backings inside the walk, edge loss.

Checked against independent estimates: the adding formula of the infinite geometry (large
areas), reciprocity (the two diameters swapped), a brute-force launch over the lit disc
against both the run that lights the smaller disc and the pencil-beam profile convolved
with the discs' overlap, and Yu et al.'s finding that TP rises with the window.
"""

import math
from dataclasses import replace

import numpy as np
import pytest
from dentalux import dental, instrument
from dentalux.cli import main
from dentalux.slab import Layer, simulate


class Flat:
    """A wavelength-independent material."""

    def __init__(self, mua, mus, g=0.9, n=1.55, name="flat"):
        self.mua, self.mus, self.g, self.n, self.fd, self.name = mua, mus, g, n, 0.0, name

    def at(self, lam):
        return self


SCATTERING = Flat(0.03, 5.0)  # mus' 0.5 /mm: edge loss separates the two backings
BANDS = [450, 550, 650]


def close(a, b, sa, sb, k=4.0):
    return abs(a - b) <= k * math.hypot(sa, sb)


def test_large_areas_reproduce_the_infinite_geometry():
    big = instrument.Instrument(name="big", geometry="0-d", illuminated_diameter_mm=4000.0,
                                viewed_diameter_mm=4000.0, backing_black=0.0,
                                backing_white=0.9)
    walks = dict(bands=BANDS, photons=40_000, solver="monte-carlo")
    inf = dental.metrics(SCATTERING, 1.0, instrument="infinite", **walks)
    fin = dental.metrics(SCATTERING, 1.0, instrument=big, **walks)
    for key in ("tp", "cr"):
        assert close(fin.__dict__[key], inf.__dict__[key], fin.stderr[key], inf.stderr[key]), key
    for j, c in enumerate("Lab"):
        for side in ("lab_black", "lab_white"):
            a, b = getattr(fin, side)[j], getattr(inf, side)[j]
            assert close(a, b, fin.stderr[f"{side}.{c}"], inf.stderr[f"{side}.{c}"]), (side, c)
    assert fin.edge_loss["white"] < 0.01
    assert inf.instrument["name"] == "infinite" and inf.edge_loss == {"black": 0.0, "white": 0.0}


def _brute(inst, backing, photons=200_000, band=0):
    layer = [Layer(mua=0.03, mus=5.0, g=0.9, n=1.55, thickness=1.0)]
    res = simulate(layer, n_photons=photons, seed=3, band=band, estimator="weighted",
                   window=inst.window(backing, brute_force=True))
    return inst.reading(res.window, res.window_stderr, brute_force=True), res


def test_reciprocity_brute_force_and_pencil_profile_agree():
    wide = instrument.Instrument(name="w", geometry="0-d", illuminated_diameter_mm=8.0,
                                 viewed_diameter_mm=3.0)
    narrow = instrument.Instrument(name="n", geometry="0-d", illuminated_diameter_mm=3.0,
                                   viewed_diameter_mm=8.0)
    (x, sx), _ = _brute(wide, 0.5, band=0)
    (y, sy), _ = _brute(narrow, 0.5, band=1)
    assert close(x, y, sx, sy), (x, sx, y, sy)
    # the run dentalux makes (lighting the smaller disc) reads the same
    layer = [Layer(mua=0.03, mus=5.0, g=0.9, n=1.55, thickness=1.0)]
    res = simulate(layer, n_photons=200_000, seed=3, band=2, estimator="weighted",
                   window=wide.window(0.5))
    z, sz = wide.reading(res.window, res.window_stderr)
    assert close(x, z, sx, sz)
    # a pencil beam's exit profile convolved with the discs' overlap (backing inside)
    pencil = instrument.Instrument(name="p", geometry="0-d", illuminated_diameter_mm=1e-9,
                                   viewed_diameter_mm=1e6)
    prof = simulate(layer, n_photons=400_000, seed=3, band=3, estimator="weighted",
                    window=pencil.window(0.5), radial=(2000, 40.0))
    spec = prof.window["viewed_specular"]
    v = instrument.reading_from_profile(prof.radial_reflectance, 40.0, 4.0, 1.5) + spec
    assert abs(v - x) <= 4 * sx + 0.002, (v, x, sx)  # + the profile's binning error
    # edge loss is real: the infinite slab reads far more
    assert prof.window["viewed_reflectance"] - x > 20 * sx


def test_overlap_area_closed_forms():
    assert instrument.overlap_area(0.0, 1.0, 2.0) == pytest.approx(math.pi)
    assert instrument.overlap_area(3.5, 1.0, 2.0) == 0.0
    # two unit discs one radius apart: 2π/3 − √3/2
    assert instrument.overlap_area(1.0, 1.0, 1.0) == pytest.approx(2 * math.pi / 3 - 3**0.5 / 2)


def test_energy_ledger_closes():
    inst = instrument.Instrument(name="x", geometry="0-45", illuminated_diameter_mm=3.0,
                                 viewed_diameter_mm=3.0, specimen_diameter_mm=6.0)
    (_, _), res = _brute(inst, 0.9, photons=20_000)
    w = res.window
    total = (w["viewed_reflectance"] + w["outside_reflectance"] + w["rim_loss"]
             + res.total_transmittance + res.absorbed)
    assert total == pytest.approx(1.0, abs=1e-9)
    assert w["rim_loss"] > 0


def test_tp_rises_with_the_window():
    tps = []
    for d in (3.0, 10.0):
        inst = instrument.get("contact-probe-3mm").override(illuminated_diameter_mm=d,
                                                             viewed_diameter_mm=d,
                                                             specimen_diameter_mm=20.0)
        m = dental.metrics(SCATTERING, 1.0, bands=BANDS, photons=40_000, instrument=inst)
        tps.append((m.tp, m.stderr["tp"]))
    (a, sa), (b, sb) = tps
    assert b - a > 4 * math.hypot(sa, sb), tps


def test_presets_carry_provenance_for_every_number():
    for name, inst in instrument.presets().items():
        if inst.is_infinite:
            continue
        for key in ("geometry", "illuminated_diameter_mm", "viewed_diameter_mm",
                    "backing_black", "backing_white"):
            entry = inst.provenance.get(key, "")
            assert entry.split(":")[0] in ("measured", "transcribed", "derived", "assumed",
                                           "fitted"), (name, key, entry)


@pytest.mark.parametrize("change, field", [
    (dict(viewed_diameter_mm=0.0), "viewed_diameter_mm"),
    (dict(illuminated_diameter_mm=float("nan")), "illuminated_diameter_mm"),
    (dict(geometry="d8-sci", viewed_diameter_mm=9.0), "viewed_diameter_mm"),
    (dict(contact_index=0.9), "contact_index"),
    (dict(backing_white=1.2), "backing_white"),
    (dict(geometry="d9"), "geometry"),
])
def test_bad_instruments_name_the_field(change, field):
    base = dict(name="t", geometry="0-45", illuminated_diameter_mm=3.0, viewed_diameter_mm=3.0)
    with pytest.raises(ValueError, match=field):
        instrument.Instrument(**{**base, **change})


def test_unknown_instrument_suggests_a_preset(capsys):
    with pytest.raises(ValueError, match="did you mean 'contact-probe-3mm'"):
        instrument.get("contact-probe-3m")
    with pytest.raises(SystemExit) as exc:
        main(["shade", "enamel", "--instrument", "nope", "--json", "--bands", "550"])
    assert exc.value.code == 2
    assert "instrument" in capsys.readouterr().err
    assert np.isfinite(instrument.get("infinite").white_fraction())


def _shade_json(capsys, args):
    with pytest.raises(SystemExit) as exc:
        main(["shade", *args, "--json"])
    out = capsys.readouterr()
    return exc.value.code, out.out, out.err


def test_shade_contract_instrument_keys_and_infinite_as_before(capsys):
    import json

    common = ["enamel", "--bands", "450,550,650", "--photons", "2000"]
    code, out, _ = _shade_json(capsys, [*common, "--instrument", "infinite"])
    assert code in (0, None)
    got = json.loads(out)
    before = dental.metrics("enamel", 1.0, bands=BANDS, photons=2000,
                            instrument="infinite").to_json()
    got.pop("cpu_seconds"), before.pop("cpu_seconds")  # the cost is the run's own
    assert got == before  # exactly the infinite-geometry numbers
    assert got["instrument"]["name"] == "infinite" and got["edge_loss"]["white"] == 0.0
    with pytest.raises(SystemExit):  # the table names the unbounded areas, not None
        main(["shade", *common, "--instrument", "infinite"])
    table = capsys.readouterr().out
    assert "lit unbounded" in table and "None" not in table, table
    code, out, _ = _shade_json(capsys, [*common, "--viewed-diameter", "2.5"])
    got = json.loads(out)
    ins = got["instrument"]
    assert ins["name"] == f"{instrument.DEFAULT}+custom" and ins["viewed_diameter_mm"] == 2.5
    assert set(ins) >= {"name", "geometry", "illuminated_diameter_mm", "viewed_diameter_mm",
                        "specular", "contact_index", "backing_black", "backing_white"}
    assert set(got["edge_loss"]) == {"black", "white"} and got["edge_loss"]["white"] > 0
    code, _, err = _shade_json(capsys, [*common, "--instrument", "infinite",
                                        "--viewed-diameter", "3"])
    assert code == 2 and "viewed_diameter_mm" in err and "infinite" in err, err
    for bad, field in ((["--viewed-diameter", "-1"], "viewed_diameter_mm"),
                       (["--contact", "0.5"], "contact"),
                       (["--backing-white", "1.5"], "backing_white"),
                       (["--geometry", "d7"], "geometry"),
                       (["--match", "vita-nope"], "shade guide")):
        code, _, err = _shade_json(capsys, [*common, *bad])
        assert code == 2 and field in err, (bad, err)


def test_shade_layered_specimen_has_the_same_keys_and_reads_like_dental_read(capsys):
    import json

    code, out, _ = _shade_json(capsys, ["--layer", "biomaterial-table1:0.5", "--layer",
                                        "dentin:1.0", "--bands", "450,550,650", "--photons",
                                        "2000"])
    got = json.loads(out)
    assert set(got) >= set(dental.JSON_KEYS) and [x["thickness_mm"] for x in got["layers"]] \
        == [0.5, 1.0]
    direct = dental.read([("biomaterial-table1", 0.5), ("dentin", 1.0)], bands=BANDS,
                         photons=2000, instrument=instrument.DEFAULT)
    assert got["tp"] == direct.tp and got["lab_white"] == list(direct.lab_white)
    for bad in (["--layer", "dentin:0"], ["enamel", "--layer", "dentin:1"],
                ["--layer", "a:1", "--layer", "b:1", "--layer", "c:1", "--layer", "d:1"]):
        code, _, err = _shade_json(capsys, bad)
        assert code == 2 and ("layer" in err or "MATERIAL" in err), (bad, err)


def test_bands_outside_a_materials_data_need_its_consent(tmp_path, capsys):
    """One band rule (issue 18, item 8): the colour range and the material's data range;
    extrapolation only where the material says so (every library entry does)."""
    text = """[materials.narrow]
wavelength_nm = [450.0, 600.0]
mua = [0.1, 0.1]
mus = [5.0, 5.0]
g = [0.9, 0.9]
fd = [0.0, 0.0]
n = [1.5, 1.5]
[materials.narrow.provenance]
kind = "measured"
source = "a test disc"
"""
    narrow = tmp_path / "narrow.toml"
    narrow.write_text(text)
    code, _, err = _shade_json(capsys, [str(narrow), "--bands", "500,700", "--photons", "500"])
    assert code == 2 and "[450, 600] nm" in err and "extrapolate = true" in err, err
    code, _, err = _shade_json(capsys, [str(narrow), "--bands", "300,500", "--photons", "500"])
    assert code == 2 and "360" in err, err
    narrow.write_text(text.replace("[materials.narrow]", "[materials.narrow]\nextrapolate = true"))
    code, out, _ = _shade_json(capsys, [str(narrow), "--bands", "500,700", "--photons", "500"])
    assert code in (0, None) and "tp" in out
    code, out, _ = _shade_json(capsys, ["enamel", "--bands", "380,780", "--photons", "500"])
    assert code in (0, None)


# a fibre-optic contact probe: an illuminating ring of fibres around a central receiving
# bundle (diameters in mm), and the reverse (a central source, a receiving ring)
RING_LIT = dict(illuminated_diameter_mm=3.0, illuminated_inner_diameter_mm=2.0,
                viewed_diameter_mm=1.2)
CENTRE_LIT = dict(illuminated_diameter_mm=1.2, viewed_diameter_mm=3.0,
                  viewed_inner_diameter_mm=2.0)


@pytest.mark.parametrize("rings, walks", [(RING_LIT, "per-band"), (CENTRE_LIT, "per-band"),
                                          (RING_LIT, "shared")],
                         ids=["ring-lit", "centre-lit", "ring-lit-shared"])
def test_fibre_probe_reading_matches_brute_force(rings, walks):
    """The reading engine (one walk per band, backing orders, entry point integrated out
    over the lit ring by inclusion-exclusion of disc lenses; or shared walks, entry sampled)
    against the plain slab walk sampling the entry over the lit region and counting exits
    inside the window."""
    from dentalux import reading
    from dentalux.spectra import resolve_bands

    inst = instrument.Instrument(name="probe", geometry="0-d", **rings)
    assert not inst.is_discs and not inst.white_normalised
    wl = resolve_bands(BANDS)
    stacks = reading.stacks([(SCATTERING, 1.0)], wl)
    got = reading.measure(stacks, wl, inst, np.zeros(len(wl)), np.full(len(wl), 0.9),
                          40_000, seed=4, walks=walks)
    for k, stack in enumerate(stacks):
        for j, rb in ((0, 0.0), (1, 0.9)):
            res = simulate(stack, n_photons=200_000, seed=9, band=k, estimator="weighted",
                           window=inst.window(rb, brute_force=True))
            ref, ref_err = inst.reading(res.window, res.window_stderr, brute_force=True)
            value, err = got.values[j, k], got.stderr[j, k]
            assert value > 0.002 and ref > 0.002, (rings, rb, value, ref)
            assert close(value, ref, err, ref_err), (rings, rb, BANDS[k], value, err, ref,
                                                     ref_err)


def test_a_ring_probe_is_read_through_dental_read():
    inst = instrument.Instrument(name="probe", geometry="0-d", **RING_LIT)
    m = dental.read([(SCATTERING, 1.0)], bands=BANDS, instrument=inst, photons=4000, seed=2,
                    threads=2)
    assert m.instrument["illuminated_inner_diameter_mm"] == 2.0
    assert m.instrument["white_normalised"] is False
    assert all(np.isfinite(m.lab_white)) and m.lab_white[0] > 0


def test_rings_of_inner_diameter_zero_read_exactly_as_discs():
    """Inner diameters 0 are today's discs: the same window tuple, the same reading to the
    bit, and the same JSON (no ring keys)."""
    disc = instrument.get("contact-probe-3mm")
    zero = replace(disc, illuminated_inner_diameter_mm=0, viewed_inner_diameter_mm=0.0)
    assert zero == disc and zero.window(0.9) == disc.window(0.9)
    kw = dict(bands=BANDS, photons=2000, seed=3, threads=2)
    a = dental.read([(SCATTERING, 1.0)], instrument=disc, **kw).to_json()
    b = dental.read([(SCATTERING, 1.0)], instrument=zero, **kw).to_json()
    for m in (a, b):
        m.pop("cpu_seconds", None)
    assert a == b


def test_a_ring_is_lit_as_the_instrument_lights_it():
    """Reciprocity's swap (light the smaller disc) is for discs only."""
    inst = instrument.Instrument(name="p", geometry="0-d", **RING_LIT)
    assert inst.window(0.5) == (1.0, 1.5, 0.0, 0.6, math.inf, 0.5, None)
    assert inst.window(0.5) == inst.window(0.5, brute_force=True)
    wide = instrument.Instrument(name="w", geometry="0-d", illuminated_diameter_mm=8.0,
                                 viewed_diameter_mm=3.0)
    assert wide.window(0.5)[:4] == (0.0, 1.5, 0.0, 4.0)
    assert wide.window(0.5, brute_force=True)[:4] == (0.0, 4.0, 0.0, 1.5)
    # overlapping rings are normalised by the lit area inside the window
    over = instrument.Instrument(name="o", geometry="0-d", illuminated_diameter_mm=4.0,
                                 illuminated_inner_diameter_mm=2.0, viewed_diameter_mm=3.0)
    assert over.white_normalised
    assert over.white_fraction() == pytest.approx((9 - 4) / (16 - 4))


@pytest.mark.parametrize("field, value", [
    ("illuminated_inner_diameter_mm", -0.5), ("illuminated_inner_diameter_mm", math.nan),
    ("illuminated_inner_diameter_mm", 3.0), ("illuminated_inner_diameter_mm", 4.0),
    ("viewed_inner_diameter_mm", -1.0), ("viewed_inner_diameter_mm", math.inf),
    ("viewed_inner_diameter_mm", 1.2), ("viewed_inner_diameter_mm", "0.5"),
])
def test_bad_inner_diameters_are_refused_with_the_field_named(field, value):
    with pytest.raises(ValueError, match=field):
        instrument.Instrument(name="p", geometry="0-d", **{**RING_LIT, field: value})


def test_bad_inner_diameter_in_a_toml_file_exits_2(tmp_path, capsys):
    path = tmp_path / "probe.toml"
    path.write_text('[instruments.probe]\ngeometry = "0-d"\nilluminated_diameter_mm = 3.0\n'
                    'illuminated_inner_diameter_mm = 3.5\nviewed_diameter_mm = 1.2\n')
    with pytest.raises(SystemExit) as exc:
        main(["shade", "enamel", "--instrument", str(path), "--photons", "100"])
    assert exc.value.code == 2
    assert "illuminated_inner_diameter_mm" in capsys.readouterr().err
    good = tmp_path / "ok.toml"
    good.write_text('[instruments.probe]\ngeometry = "0-d"\nilluminated_diameter_mm = 3.0\n'
                    'illuminated_inner_diameter_mm = 2.0\nviewed_diameter_mm = 1.2\n')
    assert instrument.get(str(good)).illuminated_inner_diameter_mm == 2.0


def test_a_ring_probe_and_its_reverse_are_reciprocal():
    """Lighting the ring and reading the centre moves as much power per unit lit area as
    lighting the centre and reading the ring (reciprocity: power A->B times area(A) is
    symmetric for a laterally uniform specimen under uniform light)."""
    from dentalux import reading
    from dentalux.spectra import resolve_bands

    wl = resolve_bands([550])
    stacks = reading.stacks([(SCATTERING, 1.0)], wl)
    out = []
    for rings in (RING_LIT, CENTRE_LIT):
        inst = instrument.Instrument(name="probe", geometry="0-d", **rings)
        got = reading.measure(stacks, wl, inst, np.zeros(1), np.full(1, 0.9), 40_000, seed=6,
                              solver="monte-carlo")
        a, a0 = inst.illuminated_diameter_mm / 2, inst.illuminated_inner_diameter_mm / 2
        area = math.pi * (a * a - a0 * a0)
        out.append((got.values[1, 0] * area, got.stderr[1, 0] * area))
    (x, sx), (y, sy) = out
    assert close(x, y, sx, sy), out
