"""Instrument classes, `instruments validate` and targets that carry their instrument (issue 40).

The validation is honest: it reports what the presets read, and the clinical contact probe's
failure is kept as a strict expected failure with its measured numbers, so a change that
fixes it (instrument geometry, calibration or tissues) is noticed.
"""

import json

import pytest
from dentalux import instrument, instrument_classes, natural_teeth
from dentalux.cli import main
from dentalux.design import targets

FAST = dict(photons=1500, bands=(450.0, 550.0, 650.0))


def _main(args):
    try:
        main(args)
    except SystemExit as exc:
        return exc.code
    return 0


def test_every_preset_names_a_class(capsys):
    assert _main(["instruments", "list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert listed["infinite"]["class"] == "idealised"
    for name, entry in listed.items():
        assert entry["class"] in instrument.CLASSES, name
    # the presets in the file name their class explicitly (none falls back to custom)
    assert all(entry["class"] != "custom" for entry in listed.values())


def test_user_file_class_default_and_refusals(tmp_path, capsys):
    body = ('[instruments.mine]\ngeometry = "0-45"\nilluminated_diameter_mm = 4.0\n'
            'viewed_diameter_mm = 3.0\n')
    f = tmp_path / "mine.toml"
    f.write_text(body)
    assert instrument.get(str(f)).instrument_class == "custom"
    f.write_text(body + 'class = "clinical-contact-probe"\n')
    assert instrument.get(str(f)).instrument_class == "clinical-contact-probe"
    for bad in ("probe", "idealised"):
        f.write_text(body + f'class = "{bad}"\n')
        assert _main(["instruments", "show", str(f), "--json"]) == 2
        captured = capsys.readouterr()
        assert captured.out == "" and "instruments.mine.class" in captured.err


def test_classes_read_their_published_rows():
    cls = instrument_classes.classes()
    assert set(cls) == set(instrument.CLASSES)
    rows = {r["id"]: r for r in natural_teeth.rows()}
    for name, c in cls.items():
        pub = c["published"]
        if pub is None:
            assert c["no_readings"], name  # the reason is stated
            continue
        assert pub["mean"] == [rows[pub["sources"][0]][k] for k in "Lab"]
        assert pub["sd"] == [rows[pub["sources"][1]][k] for k in "Lab"]
        assert all(s > 0 for s in pub["sd"])


def test_validate_json_contract(capsys):
    code = _main(["instruments", "validate", "--json", "--photons", "1500", "--bands",
                  "450,550,650"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"presets"}
    cls = instrument_classes.classes()
    expected = [n for n, i in instrument.presets().items()
                if cls[i.instrument_class]["published"] is not None]
    assert [p["name"] for p in out["presets"]] == expected
    for p in out["presets"]:
        assert set(p) == {"name", "class", "reading", "published", "inside"}
        assert set(p["reading"]) == {"lab"} and len(p["reading"]["lab"]) == 3
        assert set(p["published"]) == {"mean", "sd", "sources"}
        # inside is the per-coordinate mean ± 2 SD check, all three together
        assert p["inside"] == all(instrument_classes.check(p["reading"]["lab"], p["published"]))
    assert _main(["instruments", "validate"]) == 0
    text = capsys.readouterr().out
    assert "contact-probe-3mm" in text and "not validated" in text


def test_45_0_reads_the_natural_incisor_inside_wee2023():
    res = instrument_classes.validate(presets=["45-0"], **FAST)["presets"]
    assert len(res) == 1 and res[0]["inside"], res


@pytest.mark.xfail(strict=True, reason="measured finding (issue 40): through the 3 mm contact "
                   "window the natural incisor reads L* about 34, b* about -8, against L* 84.0 "
                   "± 2 x 7.6 and b* 24.1 ± 2 x 8.4 of Oh et al. 2022; no concentric window of "
                   "3-15 mm reaches L* 63 with today's tissues (docs/instruments.md)")
def test_clinical_probe_reads_the_natural_incisor_inside_oh2022():
    res = instrument_classes.validate(presets=["contact-probe-3mm"], **FAST)["presets"]
    assert res[0]["inside"], res


def test_target_carries_its_instrument():
    t = targets.parse("lab:72,1.5,16", instrument="45-0")
    assert t.instrument == "45-0" and t.to_json()["instrument"] == "45-0"
    assert targets.parse(t, tp=5.0).instrument == "45-0"  # kept through a re-parse
    assert "different instruments" in targets.differs_note(t, "contact-probe-3mm")
    assert targets.differs_note(t, "45-0") is None
    assert "instrument" not in targets.parse("lab:72,1.5,16").to_json()
    with pytest.raises(ValueError, match="target_instrument"):
        targets.resolve_instrument("no-such-probe", "45-0")


def test_design_target_instrument_cli(capsys, tmp_path):
    other = "contact-probe-3mm"  # a target read by another instrument than the default
    assert other != instrument.DEFAULT
    args = ["design", "--target", "lab:72,1.5,16", "--layer", "enamel:0.3-0.9",
            "--substrate", "none", "--bands", "450,550,650", "--photons", "300",
            "--designs", "1"]
    assert _main([*args, "--target-instrument", other, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["target"]["instrument"] == other
    assert out["instrument"]["name"] == instrument.DEFAULT
    assert _main([*args, "--json"]) == 0  # default: the design's own instrument
    assert json.loads(capsys.readouterr().out)["target"]["instrument"] == instrument.DEFAULT
    assert _main([*args, "--target-instrument", other]) == 0
    assert "different instruments" in " ".join(capsys.readouterr().out.split())
    assert _main([*args, "--target-instrument", "no-such-probe", "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "target_instrument" in captured.err
