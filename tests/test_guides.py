"""A lab's own shade guides: import, list, show, --match FILE.csv on shade, --target
FILE.csv:TAB and imported names on design, the instrument note, and bad guides (issue 41)."""

import json

import pytest
from cli_run import run_main
from dentalux import shade_guides
from dentalux.cli import main
from dentalux.design import targets

GUIDE = ("tab,L,a,b,instrument,source,date\n"
         "A1,78.0,0.5,14.0,contact-probe-3mm,our lab,2026-12-01\n"
         "A2,75.0,1.2,17.5,contact-probe-3mm,our lab,2026-12-01\n"
         "A3,71.0,2.0,20.0,contact-probe-3mm,our lab,2026-12-01\n")


run = run_main  # the command line in process: (exit code, stdout, stderr)


@pytest.fixture
def data(tmp_path, monkeypatch):
    monkeypatch.setenv("DENTALUX_DATA", str(tmp_path / "data"))
    f = tmp_path / "ours.csv"
    f.write_text(GUIDE)
    return f


def test_import_list_show_and_use_by_name(data, capsys, tmp_path):
    code, out, err = run(capsys, "guides", "import", data, "--name", "lab-a", "--json")
    assert code == 0, err
    assert (tmp_path / "data" / "guides" / "lab-a.csv").is_file()
    code, out, err = run(capsys, "guides", "list", "--json")
    names = {g["name"]: g for g in json.loads(out)["guides"]}
    assert names["lab-a"]["kind"] == "imported" and names["lab-a"]["tabs"] == 3
    assert "vita-classical" in names
    code, out, err = run(capsys, "guides", "show", "lab-a", "--json")
    assert [t["tab"] for t in json.loads(out)["tabs"]] == ["A1", "A2", "A3"]
    # a second import under the same name needs --replace; a built-in name is refused
    assert run(capsys, "guides", "import", data, "--name", "lab-a")[0] == 2
    assert run(capsys, "guides", "import", data, "--name", "lab-a", "--replace")[0] == 0
    code, _, err = run(capsys, "guides", "import", data, "--name", "vita-classical")
    assert code == 2 and "built-in" in err
    t = targets.parse("lab-a:A2")
    assert t.lab == (75.0, 1.2, 17.5) and t.source["instrument"] == "contact-probe-3mm"
    t = targets.parse(f"{data}:A3")
    assert t.lab == (71.0, 2.0, 20.0)
    with pytest.raises(ValueError, match="'A9' is not in shade guide"):
        targets.parse("lab-a:A9")


def test_duplicate_tab_and_bad_values_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("DENTALUX_DATA", str(tmp_path / "data"))
    for text, needle in ((GUIDE + "A2,70,1,1,x,y,z\n", "line 5: tab 'A2' repeats line 3"),
                         ("tab,L,a,b\nA1,120,0,0\n", "line 2: L = 120"),
                         ("tab,L,a\nA1,70,0\n", "missing column(s) b"),
                         ("tab,L,a,b\n", "empty")):
        f = tmp_path / "bad.csv"
        f.write_text(text)
        code, out, err = run(capsys, "guides", "import", f, "--name", "bad")
        assert code == 2 and needle in err, err
        assert not (tmp_path / "data" / "guides" / "bad.csv").exists()


def test_shade_match_file_nearest_first_with_instrument_note(data, capsys):
    code, out, err = run(capsys, "shade", "enamel", "--bands", "450,550,650", "--photons",
                         2000, "--match", data, "--instrument", "45-0", "--json")
    assert code == 0, err
    doc = json.loads(out)
    des = [m["delta_e00"] for m in doc["shade_match"]]
    assert des == sorted(des) and {m["tab"] for m in doc["shade_match"]} <= {"A1", "A2", "A3"}
    note = doc["shade_match_instrument"]
    assert note["same"] is False and note["guide_instrument"] == ["contact-probe-3mm"]
    assert "45-0" in note["note"]


def test_vita_classical_refusal_names_the_way_forward():
    with pytest.raises(ValueError, match="guides import"):
        shade_guides.lab("vita-classical", "A2")
    with pytest.raises(ValueError, match="guides import"):
        shade_guides.nearest((70, 1, 15), "vita-classical")


def test_design_target_from_a_guide_file_says_its_instrument(data, capsys):
    code, out, err = run(capsys, "design", "--target", f"{data}:A2", "--layer", "enamel:0.5-1.0",
                         "--substrate", "dentin", "--instrument", "45-0", "--photons", 1000,
                         "--bands", "450,550,650", "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["target"]["lab"] == [75.0, 1.2, 17.5]
    assert doc["target_instrument"]["same"] is False
    assert doc["target_instrument"]["guide_instrument"] == ["contact-probe-3mm"]


def test_design_target_from_a_guide_of_another_illuminant_says_so(capsys):
    # the built-in Bioform tabs are D65/2° after a chromatic adaptation from illuminant C:
    # the design (D65/2°) is told the guide's white, and no note is added for it
    code, out, err = run(capsys, "design", "--target", "bioform:B-65", "--layer",
                         "enamel:0.5-1.0", "--substrate", "dentin", "--instrument", "45-0",
                         "--photons", 1000, "--bands", "450,550,650", "--json")
    assert code == 0, err
    note = json.loads(out)["target_instrument"]
    assert note["guide_illuminant"] == ["D65/2"] and "illuminant" not in note["note"]


def test_render_match_takes_a_guide_file(data, tmp_path):
    """render --match FILE.csv: each region's nearest tabs of the lab's guide, with the
    instrument the guide was read with (the render's own geometry is another)."""
    from test_regions import _cornell_with_regions

    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        main(["render", str(_cornell_with_regions(tmp_path)), "--out", str(out), "--spp", "1",
              "--photons", "2000", "--match", str(data), "--json"])
    assert exc.value.code == 0
    colour = json.loads((out / "colour.json").read_text())
    for reg in colour["regions"].values():
        want = shade_guides.nearest(reg["lab"], str(data))
        assert [(m["tab"], m["delta_e00"]) for m in reg["shade_match"]] == want
        assert reg["shade_match_guide_instrument"] == ["contact-probe-3mm"]


# --- the built-in Bioform guide (O'Brien, Groh & Boenke, Dent Mater 1989) -------------------

# Rows copied from the source, munsellinterpol 3.3-2 inst/extdata/dental.txt (tab: Y, x, y
# under illuminant C, 2°): the first, the last and B-83, the one whose published L* is off
BIOFORM_SOURCE = {"B-96": (37.05, 0.3610, 0.3641), "B-83": (43.25, 0.3693, 0.3701),
                  "B-59": (55.72, 0.3407, 0.3502)}
BIOFORM_TABS = 24  # "the 24 teeth in a master Bioform shade guide" (dental.txt has 24 rows)
# Bradford cone matrix and the C white (CIE 15, 1931 2°), written out so the check does not
# lean on colour-science, which data/make_bioform_guide.py uses
BRADFORD = [[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]]
C_WHITE = (0.31006, 0.31616)


def _xyY_to_XYZ(x, y, Y):
    return [x * Y / y, Y, (1 - x - y) * Y / y]


def _c_to_d65_lab(Y, x, y, d65_xy):
    """Published xyY (C) -> Bradford to D65 -> CIELAB, by hand (the stated conversion)."""
    import numpy as np

    m = np.array(BRADFORD)
    w_c = np.array(_xyY_to_XYZ(*C_WHITE, 1.0))
    w_d = np.array(_xyY_to_XYZ(*d65_xy, 1.0))
    xyz = np.linalg.solve(m, (m @ w_d) / (m @ w_c) * (m @ _xyY_to_XYZ(x, y, Y / 100)))
    return _lab(xyz, w_d)


def _lab(xyz, white):
    import numpy as np

    t = np.asarray(xyz) / white
    f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def _published(tab):
    """(Y, x, y) and the published L*a*b* under C, read back from a row's notes."""
    import re

    num = r"(-?\d+\.\d+)"
    m = re.search(rf"published Y {num}, x {num}, y {num}", tab.notes)
    c = re.search(rf"L\* {num}, a\* {num}, b\* {num}; Munsell", tab.notes)
    return tuple(map(float, m.groups())), tuple(map(float, c.groups()))


def test_bioform_is_built_in_with_its_source_and_instrument(capsys):
    tabs = shade_guides.load("bioform")
    assert len(tabs) == BIOFORM_TABS and set(BIOFORM_SOURCE) <= set(tabs)
    for t in tabs.values():
        assert t.lab is not None and t.status == "derived"
        assert (t.illuminant, t.observer) == ("D65", "2")
        assert "Beckman ACTA CIII" in t.instrument and "O'Brien" in t.citation
        assert t.doi == "10.1016/0109-5641(89)90102-4"
    code, out, _ = run(capsys, "guides", "list", "--json")
    row = {g["name"]: g for g in json.loads(out)["guides"]}["bioform"]
    assert row["kind"] == "built-in" and row["tabs_with_values"] == BIOFORM_TABS
    code, _, err = run(capsys, "guides", "import", "-", "--name", "bioform")
    assert code == 2 and "built-in" in err


def test_bioform_values_follow_the_stated_conversion():
    """The derived D65/2° values are the source's xyY under C, Bradford-adapted; the xyY in
    each row's notes are the source's (three rows copied here) and agree with the published
    C values (so no row's numbers were garbled in transcription)."""
    from dentalux.color import delta_e00, system

    d65 = system("D65", "2").white_xy
    tabs = shade_guides.load("bioform")
    for name, xyY in BIOFORM_SOURCE.items():
        assert _published(tabs[name])[0] == xyY
    for t in tabs.values():
        (Y, x, y), lab_c = _published(t)
        want = _c_to_d65_lab(Y, x, y, d65)
        assert max(abs(want - t.lab)) < 0.006, (t.tab, want, t.lab)
        again = _lab(_xyY_to_XYZ(x, y, Y / 100), _xyY_to_XYZ(*C_WHITE, 1.0))
        # B-83's published L* is 0.2 below its own Y (noted in its row); the rest within 0.1
        assert float(delta_e00(again, lab_c)) < (0.2 if t.tab == "B-83" else 0.1), t.tab


def test_shade_match_bioform_names_the_guide_instrument_and_illuminant(capsys):
    base = ("shade", "enamel", "--bands", "450,550,650", "--photons", 2000, "--match",
            "bioform", "--instrument", "45-0", "--json")
    code, out, err = run(capsys, *base)
    assert code == 0, err
    doc = json.loads(out)
    des = [m["delta_e00"] for m in doc["shade_match"]]
    assert des == sorted(des) and {m["tab"] for m in doc["shade_match"]} <= set(
        shade_guides.load("bioform"))
    note = doc["shade_match_instrument"]
    assert note["same"] is False and "Beckman ACTA CIII" in note["guide_instrument"][0]
    assert "45-0" in note["note"] and note["guide_illuminant"] == ["D65/2"]
    assert "illuminant" not in note["note"]  # the reading is D65/2° too
    code, out, err = run(capsys, *base, "--illuminant", "C")
    assert code == 0, err
    assert "for D65/2" in json.loads(out)["shade_match_instrument"]["note"]
    t = targets.parse("bioform:B-65")
    assert t.lab == shade_guides.lab("bioform", "B-65") and t.source["status"] == "derived"
