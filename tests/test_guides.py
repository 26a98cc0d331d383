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
