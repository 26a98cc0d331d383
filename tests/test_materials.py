"""The material library: data, interpolation rules, provenance, scaling, loading, CLI."""

from __future__ import annotations

import csv
import json
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from dentalux import materials as M
from dentalux.cli import main

REQUIRED = ("air", "enamel", "dentin", "enamel@zoller2018-kienle", "enamel@fried1995-transcribed",
            "enamel@zijp1995", "dentin@zoller2018-kienle", "dentin@fried1995-transcribed")


def test_library_has_the_required_entries_and_documented_defaults():
    names = M.names()
    for name in REQUIRED:
        assert name in names
    assert M.get("enamel").name == "enamel@fitted-yu2009"
    assert M.get("dentin").name == "dentin@fitted-wee2023"
    assert M.get("enamel", variant="fried1995-transcribed") is M.get("enamel@fried1995-transcribed")
    assert M.variants("enamel") == ["enamel@fitted-yu2009", "enamel@fried1995-transcribed",
                                    "enamel@zijp1995", "enamel@zoller2018-kienle"]


def test_fitted_tissues_keep_the_rest_of_their_source():
    for tissue, factor in (("enamel", 20.0), ("dentin", 2.09)):
        fit, src = M.get(f"{tissue}@fitted-yu2009"), M.get(f"{tissue}@zoller2018-kienle")
        np.testing.assert_allclose(fit.mus, factor * src.mus)
        for q in ("g", "fd", "n", "wavelength_nm"):
            np.testing.assert_array_equal(getattr(fit, q), getattr(src, q))
        assert fit.value_provenance("mus").startswith("fitted")
    # the absorption is fitted too: enamel's to thick enamel's colour; the earlier dentin's
    # as a factor on the transcription, the default dentin's as a power law for the tooth's
    # colour, on the same scattering
    assert M.get("enamel").value_provenance("mua").startswith("fitted")
    old = M.get("dentin@fitted-yu2009")
    np.testing.assert_allclose(old.mua, 0.07 * M.get("dentin@zoller2018-kienle").mua)
    dentin = M.get("dentin")
    assert dentin.value_provenance("mua").startswith("fitted")
    for q in ("mus", "g", "fd", "n", "wavelength_nm"):
        np.testing.assert_array_equal(getattr(dentin, q), getattr(old, q))
    # yellow: it absorbs blue far more than red
    assert dentin.at(450.0).mua > 10 * dentin.at(650.0).mua


def test_transcribed_values_match_the_reference_table():
    # docs/explanation/tooth-optics.md §1.1/§1.2 rows, read independently of the TOML file
    rows = {
        ("enamel@zoller2018-kienle", 400): (0.06, 0.8, 0.9, 1.633),
        ("enamel@zoller2018-kienle", 700): (0.02, 0.2, 0.9, 1.633),
        ("enamel@fried1995-transcribed", 632): (0.1, 6.0, 0.96, 1.631),
        ("enamel@fried1995-transcribed", 780): (0.1, 2.867, 0.99, 1.63),
        ("dentin@zoller2018-kienle", 400): (0.2, 7.2, 0.93, 1.54),
        ("dentin@zoller2018-kienle", 700): (0.1, 6.8, 0.964, 1.54),
        ("dentin@fried1995-transcribed", 632): (0.35, 28.0, 0.93, 1.54),
        ("dentin@fried1995-transcribed", 780): (0.35, 22.193, 0.83, 1.49),
        ("enamel@zijp1995", 633): (0.1, 6.6, 0.68, 1.631),
    }
    for (name, lam), (mua, mus, g, n) in rows.items():
        o = M.get(name).at(lam)
        assert (o.mua, o.mus, o.g, o.n) == pytest.approx((mua, mus, g, n), rel=1e-12)


def test_power_law_between_known_points():
    m = M.get("enamel@zoller2018-kienle")  # mus 0.8 -> 0.2, mua 0.06 -> 0.02 (400 -> 700 nm)
    lam = math.sqrt(400 * 700)  # a power law gives the geometric mean here
    o = m.at(lam)
    assert o.mus == pytest.approx(math.sqrt(0.8 * 0.2), rel=1e-12)
    assert o.mua == pytest.approx(math.sqrt(0.06 * 0.02), rel=1e-12)
    d = M.get("dentin@zoller2018-kienle").at(550)  # g linear: 0.93 + (0.964 - 0.93) * 150/300
    assert d.g == pytest.approx(0.947, rel=1e-12)
    # log-log linear: the slope between any two interior points is the exponent b
    b = math.log(0.2 / 0.8) / math.log(700 / 400)
    o1, o2 = m.at(450), m.at(600)
    assert math.log(o2.mus / o1.mus) / math.log(600 / 450) == pytest.approx(b, rel=1e-10)


def test_extrapolation_rules():
    m = M.get("enamel@fried1995-transcribed")  # known 632 and 780 nm only
    b = math.log(2.867 / 6.0) / math.log(780 / 632)
    o = m.at(450.0)
    assert o.mus == pytest.approx(6.0 * (450 / 632) ** b, rel=1e-12)  # power law from 2 nearest
    assert (o.mua, o.g, o.n) == (0.1, 0.96, 1.631)  # nearest value
    hi = m.at(900.0)
    assert hi.mus == pytest.approx(2.867 * (900 / 780) ** b, rel=1e-12)
    assert (hi.g, hi.n) == (0.99, 1.63)
    single = M.get("enamel@zijp1995").at([400.0, 633.0, 700.0])
    assert np.all(single.mus == 6.6) and np.all(single.g == 0.68)


def test_scalar_and_array_evaluation_and_zero_values():
    m = M.get("dentin")
    o = m.at(500)
    assert all(isinstance(getattr(o, q), float) for q in M.QUANTITIES)
    lam = np.array([[400.0, 500.0], [600.0, 700.0]])
    arr = m.at(lam)
    for q in M.QUANTITIES:
        assert getattr(arr, q).shape == (2, 2)
        assert getattr(arr, q)[0, 1] == pytest.approx(getattr(o, q))
    air = M.get("air").at(np.linspace(350, 800, 7))
    assert np.all(air.mua == 0) and np.all(air.mus == 0) and np.all(air.n == 1.0)
    with pytest.raises(ValueError, match="wavelength_nm"):
        m.at(-5.0)
    with pytest.raises(ValueError, match="wavelength_nm"):
        m.at(float("nan"))


def test_every_value_has_provenance():
    for name in M.names():
        m = M.get(name)
        assert m.provenance["kind"] in M.KINDS
        assert m.provenance["source"]
        for q in ("wavelength_nm",) + M.QUANTITIES:
            for lam in m.wavelength_nm:
                text = m.value_provenance(q, lam)
                assert text.split(":")[0].split(" ")[0] in M.VALUE_KINDS, (name, q, text)
        # f_d was not found for any tissue: it must be declared as an assumption
        if name.startswith(("enamel", "dentin")):
            assert m.value_provenance("fd").startswith("assumed")
    fried = M.get("enamel@fried1995-transcribed")
    assert "632 nm" in fried.value_provenance("mus", 640)
    assert "780 nm" in fried.value_provenance("mus", 779)


def test_scaling_is_explicit_and_recorded():
    m = M.get("enamel@zoller2018-kienle")
    s = m.scaled(mus_factor=20.0, mua_factor=2.0, g=0.5, note="limited photon budget")
    assert s.name == "enamel@zoller2018-kienle+scaled" and s.is_scaled and not m.is_scaled
    np.testing.assert_allclose(s.mus, 20.0 * m.mus)
    np.testing.assert_allclose(s.mua, 2.0 * m.mua)
    assert np.all(s.g == 0.5) and np.all(s.n == m.n)
    assert s.provenance["scaling"] == [{"mus_factor": 20.0, "mua_factor": 2.0, "g": 0.5,
                                        "note": "limited photon budget"}]
    assert "x 20" in s.value_provenance("mus")
    assert "limited photon budget" in s.value_provenance("g")
    assert "scaled" not in m.value_provenance("mus")  # the original is untouched
    twice = s.scaled(mus_factor=0.5)
    assert len(twice.provenance["scaling"]) == 2 and twice.name == s.name
    with pytest.raises(ValueError, match="mus_factor"):
        m.scaled(mus_factor=-1)
    with pytest.raises(ValueError, match="g"):
        m.scaled(g=1.0)


def test_similarity_relation_keeps_reduced_scattering_and_is_recorded():
    m = M.get("dentin")
    s = m.similar(0.75, note="fewer photons")
    assert s.is_scaled and s.name.endswith("+scaled") and not m.is_scaled
    np.testing.assert_allclose(s.mus * (1 - s.g), m.mus * (1 - m.g))  # mus' kept
    assert np.all(s.g == 0.75) and np.all(s.mua == m.mua) and np.all(s.n == m.n)
    record = s.provenance["scaling"][-1]
    assert record["similarity_g"] == 0.75 and "fewer photons" in record["note"]
    np.testing.assert_allclose(record["mus_factors"], (1 - m.g) / 0.25, rtol=1e-5)
    assert "similarity relation to g = 0.75" in s.value_provenance("mus")
    # a wavelength already at or below the target g is left as it is
    bio = M.get("biomaterial-table1")
    same = bio.similar(0.8)
    np.testing.assert_array_equal(same.mus, bio.mus)
    np.testing.assert_array_equal(same.g, bio.g)
    with pytest.raises(ValueError, match=r"g = 1.0 is out of range"):
        m.similar(1.0)


VALID = """
[materials.test-medium]
description = "test"
wavelength_nm = [450.0, 650.0]
mua = [0.1, 0.2]
mus = [3.0, 2.0]
g = [0.7, 0.8]
fd = [0.0, 0.1]
n = [1.5, 1.5]
[materials.test-medium.provenance]
kind = "fitted"
source = "unit test"
[materials.test-medium.provenance.values]
mua = ["fitted: at 450", "fitted: at 650"]
"""


def test_load_and_get_from_a_path(tmp_path):
    p = tmp_path / "m.toml"
    p.write_text(VALID)
    mats = M.load(p)
    assert list(mats) == ["test-medium"]
    m = M.get(str(p))
    assert m.at(650).fd == pytest.approx(0.1)
    assert m.value_provenance("mua", 650) == "fitted: at 650"
    assert m.value_provenance("mus").startswith("fitted: unit test")  # inherited


@pytest.mark.parametrize("old,new,field", [
    ("mua = [0.1, 0.2]", "mua = [-0.1, 0.2]", "mua"),
    ("g = [0.7, 0.8]", "g = [0.7, 1.0]", "g"),
    ("n = [1.5, 1.5]", "n = [0.9, 1.5]", "n"),
    ("fd = [0.0, 0.1]", "fd = [0.0, 1.1]", "fd"),
    ("mus = [3.0, 2.0]", "mus = [3.0]", "mus"),
    ("wavelength_nm = [450.0, 650.0]", "wavelength_nm = [650.0, 450.0]", "wavelength_nm"),
    ('kind = "fitted"', 'kind = "guessed"', "provenance.kind"),
    ('mua = ["fitted: at 450", "fitted: at 650"]', 'mua = "made up"', "provenance.values.mua"),
    ('description = "test"', 'description = "test"\ncolour = 1', "colour"),
])
def test_bad_files_name_the_field(tmp_path, old, new, field):
    p = tmp_path / "bad.toml"
    assert old in VALID
    p.write_text(VALID.replace(old, new))
    with pytest.raises(ValueError, match=re.escape(field)):
        M.load(p)


def test_unknown_names_and_missing_files():
    with pytest.raises(ValueError, match="unknown material 'enamle'"):
        M.get("enamle")
    with pytest.raises(ValueError, match="enamel@zoller2018-kienle"):
        M.get("enamel", variant="nope")
    with pytest.raises(FileNotFoundError):
        M.load("/nonexistent/materials.toml")


def test_library_includes_every_data_file_with_materials(tmp_path, monkeypatch):
    for f in M.DATA_DIR.glob("*.toml"):
        shutil.copy(f, tmp_path / f.name)
    (tmp_path / "extra.toml").write_text(VALID)
    (tmp_path / "not-materials.toml").write_text("[scene]\nx = 1\n")
    monkeypatch.setattr(M, "DATA_DIR", tmp_path)
    monkeypatch.setattr(M, "_LIBRARY", None)
    assert "test-medium" in M.names() and "enamel" in M.names()
    (tmp_path / "dup.toml").write_text(VALID)
    with pytest.raises(ValueError, match="defined twice"):
        M.names()


def test_biomaterial_table1_when_present():
    path = M.DATA_DIR / "biomaterial-table1.toml"
    if not path.exists():
        pytest.skip("biomaterial-table1.toml is written by the inversion work (not there yet)")
    m = M.get("biomaterial-table1")
    assert m.provenance["kind"] == "fitted"
    assert 540.0 >= m.wavelength_nm[0] and m.wavelength_nm[-1] >= 540.0


def _read_csv(path: Path):
    lines = path.read_text().splitlines()
    header = [ln for ln in lines if ln.startswith("#")]
    rows = list(csv.DictReader(ln for ln in lines if not ln.startswith("#")))
    return header, rows


def test_example_composite_csv_matches_adding_doubling():
    """The synthetic CSV is what its stated coefficients give: compare with iadpython's
    adding-doubling (independent of the Monte Carlo that made it), within 4 standard errors
    plus the 5e-5 rounding of the file."""
    iad = pytest.importorskip("iadpython")
    header, rows = _read_csv(M.DATA_DIR / "example-composite.csv")
    assert "SYNTHETIC" in header[0]
    assert list(rows[0]) == ["wavelength_nm", "tt", "tr", "n", "g", "thickness_mm"]
    se = float(re.search(r"standard error <= ([0-9.]+e[+-][0-9]+)", " ".join(header)).group(1))
    assert se <= 1e-3
    for row in rows[::4]:
        lam, d = float(row["wavelength_nm"]), float(row["thickness_mm"])
        mus = 4.0 * (lam / 550.0) ** -1.0  # the coefficients stated in the header
        mua = 0.03 + 0.25 * math.exp(-(lam - 400.0) / 50.0)
        s = iad.Sample(a=mus / (mua + mus), b=(mua + mus) * d, g=float(row["g"]), d=d,
                       n=float(row["n"]), n_above=1.0, n_below=1.0, quad_pts=16)
        ur1, ut1, _, _ = s.rt()
        assert abs(float(row["tt"]) - ut1) < 4 * se + 5e-5 + 3e-4, (lam, row["tt"], ut1)
        assert abs(float(row["tr"]) - ur1) < 4 * se + 5e-5 + 3e-4, (lam, row["tr"], ur1)


def _cli(args) -> int:
    try:
        main(args)
    except SystemExit as exc:
        return exc.code or 0
    return 0


def test_cli_list_show_plot(tmp_path, capsys):
    assert _cli(["materials", "list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)["materials"]
    assert {r["name"] for r in listed} >= set(REQUIRED)
    assert _cli(["materials", "show", "enamel", "--json", "-w", "550"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown["name"] == "enamel@fitted-yu2009"
    assert shown["evaluated"]["mus"][0] == pytest.approx(M.get("enamel").at(550).mus)
    out = tmp_path / "enamel.png"
    assert _cli(["materials", "plot", "dentin@fried1995-transcribed", "--out", str(out)]) == 0
    import matplotlib.image as mpimg

    img = mpimg.imread(out)
    assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 600
    assert _cli(["materials", "show", "unobtainium"]) == 2
    assert "unknown material" in capsys.readouterr().err


FITTED = """
[materials.fit-demo]
description = "fitted from table.csv"
wavelength_nm = [450.0, 540.0, 605.0]
mua = [0.5, 0.3, 0.0]
mus = [4.0, 3.5, 3.2]
g = [0.75, 0.75, 0.75]
fd = [0.0, 0.0, 0.0]
n = [1.55, 1.54, 1.537]
mua_ci = [[0.45, 0.55], [0.25, 0.35], [0.0, 0.02]]
mus_ci = [[3.9, 4.1], [3.4, 3.6], [3.1, 3.3]]

[materials.fit-demo.provenance]
kind = "fitted"
source = "table.csv"
model = "slab-mc"
date = "2026-11-22"
notes = "mua is not resolved at [605.0] nm"
"""


def test_fitted_file_with_confidence_intervals(tmp_path):
    """The inversion's output format (extra *_ci keys, extra provenance keys, a zero mua)."""
    p = tmp_path / "fit.toml"
    p.write_text(FITTED)
    m = M.get(str(p))
    assert m.ci["mua"].shape == (3, 2) and m.ci["mus"][1, 1] == 3.6
    assert m.value_provenance("mua").startswith("fitted: table.csv")
    o = m.at([500.0, 580.0, 650.0])
    assert np.all(np.isfinite(o.mua)) and o.mua[2] == 0.0  # zero: linear, then held
    assert o.mua[1] == pytest.approx(0.3 * (1 - 40 / 65))
    s = m.scaled(mus_factor=2.0)
    np.testing.assert_allclose(s.ci["mus"], 2.0 * m.ci["mus"])
    assert s.to_dict()["mus_ci"][0] == [7.8, 8.2]
    p.write_text(FITTED.replace("mus_ci = [[3.9, 4.1], ", "mus_ci = ["))
    with pytest.raises(ValueError, match="mus_ci"):
        M.load(p)


def test_cli_list_reads_at_80_columns(monkeypatch, capsys):
    """`materials list` in an 80-column terminal: one line per name, no line over 80
    characters, every name whole, a default name showing the variant it stands for."""
    monkeypatch.setenv("COLUMNS", "80")
    assert _cli(["materials", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert max(len(line) for line in lines) <= 80
    names = M.names()
    assert len(lines) <= len(names) + 5  # title, header, rule, caption: no wrapped rows
    for name in names:
        rows = [line for line in lines if line.split() and line.split()[0] == name]
        assert len(rows) == 1, f"{name} is not on a line of its own, whole"
        resolved = M.get(name).name
        if resolved != name:
            assert f"= {resolved}" in rows[0]


def test_an_extrapolation_past_the_coefficient_range_is_refused_naming_it(tmp_path):
    """A steep power law carried far from its data is refused with the material, quantity and
    wavelength named, never handed on as inf."""
    import pytest
    from dentalux import materials

    path = tmp_path / "steep.toml"
    path.write_text("""
[materials.steep]
extrapolate = true
wavelength_nm = [400.0, 401.0]
mua = [0.001, 1000000.0]
mus = [1.0, 1000000.0]
g = [0.9, 0.9]
fd = [0.0, 0.0]
n = [1.5, 1.5]
[materials.steep.provenance]
kind = "measured"
source = "a test"
""")
    m = materials.load(path)["steep"]
    assert m.at(400.5).mus < 1e6
    with pytest.raises(ValueError, match=r"'steep': mus at 420 nm .* extrapolated"):
        m.at([420.0, 450.0])
