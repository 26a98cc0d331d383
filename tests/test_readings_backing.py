"""Readings files whose backing is a spectrum (``backing = FILE.csv``), and the ``mc`` fit over
a spectral backing (issue 41)."""

import json
import math

import numpy as np
import pytest
from cli_run import run_main
from dentalux import dental, instrument, readings
from dentalux.color import delta_e00
from dentalux.inverse import readings_fit as rf
from dentalux.reading.layered.stack import ACCURACY

INST = "contact-probe-3mm"
WL = (450, 550, 650)
# a warm white card: its reflectance rises with the wavelength
CARD = "wavelength_nm,reflectance\n400,0.70\n500,0.78\n600,0.84\n700,0.88\n"
CARD_AT = {450: 0.74, 550: 0.81, 650: 0.86}  # linear between the card's rows


def _km_rows(backing_of, mua=(0.3, 0.1, 0.05), mus=(12.0, 10.0, 9.0)):
    """Kubelka-Munk readings at 0.5 and 1.0 mm over black and over the card."""
    inst = instrument.get(INST)
    rows = []
    for t in (0.5, 1.0):
        for b, rg in (("black", inst.backing_black),
                      (backing_of, np.array([CARD_AT[w] for w in WL]))):
            r = rf.km_reflectance(np.asarray(mua), np.asarray(mus), 0.8, 1.5, t, rg,
                                  inst.spec.specular == "excluded")
            rows.append(f"{t},{b}," + ",".join(f"{x:.8f}" for x in r))
    return "thickness_mm,backing," + ",".join(f"r{w}" for w in WL) + "\n" + "\n".join(rows) + "\n"


def test_backing_file_is_read_relative_to_the_readings_file(tmp_path, capsys):
    """A backing spectrum next to the readings file (named relatively) is interpolated at
    the bands: Kubelka-Munk readings over it are fitted back to their coefficients."""
    (tmp_path / "cards").mkdir()
    (tmp_path / "cards" / "warm.csv").write_text("# a comment\n" + CARD)
    f = tmp_path / "r.csv"
    f.write_text(_km_rows("cards/warm.csv"))
    data = readings.load(f)
    card = data.rows[1].backing
    assert isinstance(card, readings.BackingFile) and data.rows[1].backing_label == "cards/warm.csv"
    assert data.rows[3].backing is card  # read once
    out = tmp_path / "m.toml"
    code, stdout, err = run_main(capsys, "fit", "--readings", f, "--instrument", INST, "--g",
                                 0.8, "--n", 1.5, "--model", "km", "--out", out, "--json")
    assert code == 0, err
    doc = json.loads(stdout)
    assert doc["identifiable"] is True
    assert {r["backing"] for r in doc["residuals"]} == {"black", "cards/warm.csv"}
    assert max(r["delta_e00"] for r in doc["residuals"]) < 1e-3
    from dentalux import materials

    m = materials.load(out)["m"]
    assert np.allclose(m.mua, [0.3, 0.1, 0.05], rtol=1e-3)


@pytest.mark.parametrize("card,needle", [
    (None, "backing = 'card.csv': no such file"),
    ("wavelength_nm,r\n400,0.5\n700,0.6\n", "missing column(s) reflectance"),
    ("wavelength_nm,reflectance\n400,0.5\n", "at least two rows"),
    ("wavelength_nm,reflectance\n400,0.5\n700,1.2\n", "line 3: reflectance = 1.2"),
    ("wavelength_nm,reflectance\n400,0.5\n700,x\n", "line 3: reflectance = 'x' is not"),
    ("wavelength_nm,reflectance\n500,0.5\n400,0.6\n", "line 3: wavelength_nm = 400 does not"),
    ("wavelength_nm,reflectance\n500,0.5\n600,0.6\n", "covers 500-600 nm: it must span"),
])
def test_bad_backing_file_exit_2_and_write_nothing(tmp_path, capsys, card, needle):
    if card is not None:
        (tmp_path / "card.csv").write_text(card)
    f = tmp_path / "r.csv"
    f.write_text(_km_rows("card.csv"))
    with pytest.raises(ValueError, match="line 3: backing|card.csv"):
        readings.load(f)
    out = tmp_path / "m.toml"
    code, stdout, err = run_main(capsys, "fit", "--readings", f, "--instrument", INST, "--model",
                                 "km", "--out", out, "--json")
    assert code == 2, err
    assert needle in err and "card.csv" in err, err
    assert not out.exists() and stdout == ""


@pytest.mark.parametrize("where", ["readings file", "instrument"])
def test_mc_fit_over_a_spectral_backing(tmp_path, where):
    """The mc model reads a spectral backing, named in the readings file or the instrument's
    own (the table at the card's lowest and highest reflectance, the verification at the card
    itself): layered readings over black and the card at 0.6 mm are fitted back, and the fit
    reads the card's reading at 1.2 mm within 4 standard errors plus the solver's stated
    accuracy."""
    (tmp_path / "card.csv").write_text(CARD)
    from dentalux.materials import Material

    bands = [float(w) for w in WL]
    comp = Material(name="comp", wavelength_nm=np.array(bands), mua=np.array([0.3, 0.1, 0.05]),
                    mus=np.array([12.0, 10.0, 9.0]), g=np.full(3, 0.8), fd=np.zeros(3),
                    n=np.full(3, 1.5), provenance={"kind": "derived", "source": "test"})
    card = readings.backing_file("card.csv", tmp_path, "test")
    inst = instrument.get(INST)
    name = "card.csv"
    if where == "instrument":
        inst, name = inst.override(backing_white=card.spectrum), "white"
    rows = ["thickness_mm,backing," + ",".join(f"r{w}" for w in WL)]
    m = dental.read([(comp, 0.6)], instrument=inst, bands=bands, photons=4000, seed=3,
                    solver="layered", backing_white=card.spectrum)
    for b, key in (("black", "over_black"), (name, "over_white")):
        rows.append(f"0.6,{b}," + ",".join(f"{x:.6f}" for x in m.spectra[key]))
    f = tmp_path / "r.csv"
    f.write_text("\n".join(rows) + "\n")
    res = rf.fit(readings.load(f), inst, g=0.8, n=1.5, photons=4000, solver="auto")
    assert res.solver == "layered" and res.identifiable
    fitted = Material(name="fit", wavelength_nm=res.wavelength_nm, mua=res.mua, mus=res.mus,
                      g=np.full(3, 0.8), fd=np.zeros(3), n=np.full(3, 1.5),
                      provenance={"kind": "fitted", "source": "test"})
    kw = dict(instrument=INST, bands=bands, photons=4000, seed=7, solver="layered",
              backing_white=card.spectrum)
    a = dental.read([(fitted, 1.2)], **kw)
    b = dental.read([(comp, 1.2)], **kw)
    de = float(delta_e00(a.lab_white, b.lab_white))
    se = math.hypot(dental.reading_precision(a), dental.reading_precision(b))
    spec = np.asarray(b.spectra["over_white"])
    prob = rf.Problem(readings.load(f), instrument.get(INST), 0.8, 1.5, "km", 0, 1, bands)
    acc = float(delta_e00(prob.lab(spec), prob.lab(spec * (1 + ACCURACY))))
    print(f"spectral backing ({where}), 1.2 mm over the card: {de:.3f} ΔE00 (s.e. {se:.3f}, "
          f"accuracy {acc:.3f})")
    assert de < 4 * se + acc, (de, se, acc)
