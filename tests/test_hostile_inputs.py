"""Issue 43: careless input never gives a silent wrong number, a NaN, or a traceback.

One property-based test per class of input, each feeding a reader malformed values (wrong
types, unsorted, duplicate, non-finite, huge, deep, wrong encoding) and asserting a
``ValueError`` (exit code 2 from the command line) that names the file and the key; a check
that every ``--json`` output is standard JSON (RFC 8259); and the ceilings on work that
are refused before the work starts. Nothing here traces more than a few thousand photons.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import pytest
import tomli_w
from dentalux import dental, inputs, instrument, limits, materials
from dentalux.cli import main
from dentalux.design import substrates
from dentalux.inverse.table import read_table
from dentalux.strict_json import check_finite
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell.toml"
FAST = settings(max_examples=30, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])

# values no number field accepts: wrong types, non-finite, absurd sizes
NOT_A_NUMBER = st.sampled_from([True, False, "4.0", "x", [1.0], {"a": 1.0}])
NON_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])
HUGE = st.sampled_from([1e300, -1e300, 1e-300])


def run(capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return exc.value.code, out, err


def strict_loads(text: str):
    """RFC 8259 JSON: NaN, Infinity and -Infinity are not numbers."""
    def refuse(name):
        raise AssertionError(f"non-standard JSON constant {name}")

    return json.loads(text, parse_constant=refuse)


def deep(n: int) -> str:
    return "[" * n + "]" * n


# ---------------------------------------------------------------------------------------
# instrument TOML


def _instrument(**changes) -> dict:
    table = {"geometry": "0-45", "illuminated_diameter_mm": 4.0, "viewed_diameter_mm": 3.0,
             "backing_black": 0.04,
             "backing_white": {"wavelength_nm": [400.0, 550.0, 700.0],
                               "reflectance": [0.8, 0.85, 0.9]}}
    table.update(changes)
    return table


def _wavelength_mutation():
    """A backing table's wavelengths made unsorted, duplicated, non-finite, huge, negative
    or of the wrong type."""
    return st.one_of(
        st.permutations([400.0, 550.0, 700.0]).filter(lambda w: w != [400.0, 550.0, 700.0]),
        st.sampled_from([[400.0, 400.0, 700.0], [400.0, 550.0, 550.0], [-400.0, 550.0, 700.0],
                         [400.0, 550.0, 1e300], [0.0, 550.0, 700.0], [400.0, True, 700.0],
                         [400.0, "550", 700.0]]),
        NON_FINITE.map(lambda x: [400.0, x, 700.0]))


INSTRUMENT_MUTATIONS = st.one_of(
    st.tuples(st.sampled_from(["illuminated_diameter_mm", "viewed_diameter_mm",
                               "specimen_diameter_mm"]),
              st.one_of(NOT_A_NUMBER, NON_FINITE, HUGE, st.just(-1.0))),
    st.tuples(st.sampled_from(["backing_black", "contact_index"]),
              st.one_of(NOT_A_NUMBER, NON_FINITE, st.sampled_from([1e300, -1e300, -1.0]))),
    st.tuples(st.just("backing_white.wavelength_nm"), _wavelength_mutation()),
    st.tuples(st.just("backing_white.reflectance"),
              st.sampled_from([[0.8, 1.5, 0.9], [0.8, math.nan, 0.9], [0.8, True, 0.9]])),
    st.tuples(st.sampled_from(["bogus", "backing_white.bogus", "provenance"]),
              st.sampled_from(["x", 1.0])),
    st.tuples(st.sampled_from(["geometry", "description"]), st.sampled_from([1.0, True])))


@FAST
@given(INSTRUMENT_MUTATIONS)
def test_instrument_file_refuses_malformed_values_naming_file_and_key(tmp_path, capsys,
                                                                      mutation):
    key, value = mutation
    table = _instrument()
    if key.startswith("backing_white."):
        table["backing_white"] = dict(table["backing_white"], **{key.split(".")[1]: value})
    else:
        table[key] = value
    path = tmp_path / "lab-probe.toml"
    path.write_text(tomli_w.dumps({"instruments": {"probe": table}}), encoding="utf-8")
    with pytest.raises(ValueError) as exc:
        instrument.get(str(path))
    msg = str(exc.value)
    assert "lab-probe.toml" in msg, msg
    assert key.split(".")[-1] in msg or (key == "bogus" and "bogus" in msg), msg
    code, out, err = run(capsys, ["instruments", "show", path, "--json"])
    assert code == 2 and out == "" and err == f"error: {msg}\n", err


def test_instrument_spectral_backing_rules_and_a_good_table_still_reads(tmp_path):
    path = tmp_path / "ok.toml"
    path.write_text(tomli_w.dumps({"instruments": {"probe": _instrument()}}))
    inst = instrument.get(str(path))
    assert inst.backing_white == ((400.0, 550.0, 700.0), (0.8, 0.85, 0.9))
    assert isinstance(inst.illuminated_diameter_mm, float) and not inst.is_infinite
    # the Python API: the same rules, and a string is never compared as a number
    for bad in ("4.0", True, math.nan, 1e-300):
        with pytest.raises(ValueError, match="illuminated_diameter_mm"):
            instrument.Instrument(name="x", illuminated_diameter_mm=bad)


def test_the_name_infinite_means_only_the_builtin(tmp_path, capsys):
    path = tmp_path / "mine.toml"
    path.write_text(tomli_w.dumps({"instruments": {"infinite": _instrument()}}))
    code, _, err = run(capsys, ["instruments", "show", path])
    assert code == 2 and "mine.toml" in err and "reserved" in err, err
    own = instrument.Instrument(name="infinite", geometry="0-45", illuminated_diameter_mm=4.0,
                                viewed_diameter_mm=3.0)
    assert not own.is_infinite  # finite areas: read through its own window
    assert instrument.get("infinite").is_infinite
    with pytest.raises(ValueError, match="illuminated_diameter_mm"):
        instrument.Instrument(name="mine", geometry="0-d", illuminated_diameter_mm=math.inf,
                              viewed_diameter_mm=math.inf)


# ---------------------------------------------------------------------------------------
# material TOML


def _material(**changes) -> dict:
    m = {"wavelength_nm": [400.0, 550.0, 700.0], "mua": [0.1, 0.05, 0.02],
         "mus": [10.0, 8.0, 6.0], "g": [0.6, 0.6, 0.6], "fd": [0.0, 0.0, 0.0],
         "n": [1.5, 1.5, 1.5], "mua_ci": [[0.05, 0.2], [0.0, 0.1], [0.0, 0.05]],
         "provenance": {"kind": "measured", "source": "a test"}}
    m.update(changes)
    return m


MATERIAL_MUTATIONS = st.one_of(
    st.tuples(st.just("wavelength_nm"), _wavelength_mutation()),
    st.tuples(st.sampled_from(["mua", "mus", "g", "fd", "n"]),
              st.one_of(NOT_A_NUMBER, NON_FINITE, st.sampled_from([1e300, -1e300, -1.0]))
              .map(lambda x: [0.5, x, 0.5])),
    st.tuples(st.just("mua_ci"),
              st.sampled_from([[[0.05, 0.2], [math.nan, 0.1], [0.0, 0.05]],
                               [[0.05, 0.2], [0.2, 0.1], [0.0, 0.05]],
                               [[0.05, 0.2], [0.0, math.inf], [0.0, 0.05]],
                               [[0.05, 0.2], [True, 0.1], [0.0, 0.05]],
                               [[0.05, 0.2], [0.1], [0.0, 0.05]]])),
    st.tuples(st.sampled_from(["provenance", "bogus"]), st.sampled_from(["x", 1.0, [1.0]])),
    st.tuples(st.just("description"), st.sampled_from([1.0, True, [1.0]])))


@FAST
@given(MATERIAL_MUTATIONS)
def test_material_file_refuses_malformed_values_naming_file_and_key(tmp_path, capsys,
                                                                    mutation):
    key, value = mutation
    m = _material(**{key: value})
    path = tmp_path / "my-composite.toml"
    path.write_text(tomli_w.dumps({"materials": {"comp": m}}), encoding="utf-8")
    with pytest.raises(ValueError) as exc:
        materials.get(str(path))
    msg = str(exc.value)
    assert "my-composite.toml" in msg and key in msg, msg
    code, out, err = run(capsys, ["materials", "show", path, "--json"])
    assert code == 2 and out == "" and err == f"error: {msg}\n", err


def test_a_material_value_out_of_range_is_printed_as_a_plain_number(tmp_path, capsys):
    path = tmp_path / "my-composite.toml"
    path.write_text(tomli_w.dumps({"materials": {"comp": _material(g=[1.8, 0.6, 0.6])}}))
    code, _, err = run(capsys, ["materials", "show", path])
    assert code == 2 and "g[0] = 1.8 at 400 nm" in err and "np." not in err, err


def test_material_file_deep_or_foreign_encoding_is_a_named_error(tmp_path, capsys):
    good = tmp_path / "good.toml"
    good.write_text(tomli_w.dumps({"materials": {"comp": _material()}}))
    assert materials.get(str(good)).ci["mua"].shape == (3, 2)
    nested = tmp_path / "nested.toml"
    nested.write_text("[materials.comp]\nwavelength_nm = " + deep(5000) + "\n")
    latin = tmp_path / "latin.toml"
    latin.write_bytes(good.read_bytes().replace(b"a test", b"caf\xe9"))
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + good.read_bytes())
    assert materials.get(str(bom)).name == "comp"  # a BOM is tolerated
    for path, why in ((nested, "nested too deeply"), (latin, "not UTF-8")):
        code, _, err = run(capsys, ["materials", "show", path])
        assert code == 2 and path.name in err and why in err, err


# ---------------------------------------------------------------------------------------
# CSV: the measurement table of `dentalux fit` and a substrate's reflectance file

HEADER = "wavelength_nm,tt,tr,n,g,thickness_mm"
ROW = "550,0.5,0.1,1.5,0.9,1.0"
CSV_MUTATIONS = st.one_of(
    st.sampled_from([("550,0.5,0.1", "thickness_mm"), ("550,0.5,0.1,1.5,0.9,1.0,7", "field"),
                     ("550,0.5,x,1.5,0.9,1.0", "tr"), ("550,0.5,nan,1.5,0.9,1.0", "tr"),
                     ("550,inf,0.1,1.5,0.9,1.0", "tt"), ("550,0.5,0.1,,0.9,1.0", "n"),
                     ("550,0.5,0.1,1.5,0.9, ", "thickness_mm")]),
    st.integers(131_073, 140_000).map(lambda n: ("550,0.5,0.1,1.5,0.9," + "1" * n, "131,072")))


@FAST
@given(CSV_MUTATIONS)
def test_measurement_table_refuses_malformed_rows_naming_file_and_column(tmp_path, capsys,
                                                                          mutation):
    row, named = mutation
    path = tmp_path / "discs.csv"
    path.write_text(f"{HEADER}\n{ROW}\n{row}\n", encoding="utf-8")
    with pytest.raises(ValueError) as exc:
        read_table(str(path))
    msg = str(exc.value)
    assert "discs.csv" in msg and named in msg, msg
    code, out, err = run(capsys, ["fit", "--table", path, "--model", "km", "--json"])
    assert code == 2 and out == "" and err == f"error: {msg}\n", err


@FAST
@given(st.sampled_from([b"\xe9", b"\x00", b"\xff\xfe", b"\x80\x81"]))
def test_text_in_another_encoding_is_refused_naming_the_file(tmp_path, raw):
    path = tmp_path / "meas.csv"
    path.write_bytes(raw + f"{HEADER}\n{ROW}\n".encode())
    with pytest.raises(ValueError, match=r"meas\.csv: (not UTF-8|binary|UTF-16)"):
        read_table(str(path))


@FAST
@given(st.binary(max_size=64))
def test_decode_never_raises_anything_but_a_named_valueerror(data):
    try:
        text = inputs.decode(data, "some.csv")
    except ValueError as exc:
        assert str(exc).startswith("some.csv: ")
    else:
        assert isinstance(text, str) and "\x00" not in text


def test_a_bom_csv_reads_like_the_same_file_without_it(tmp_path, capsys):
    plain, bom = tmp_path / "plain.csv", tmp_path / "bom.csv"
    plain.write_text(f"{HEADER}\n{ROW}\n")
    bom.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes())
    assert read_table(str(bom)) == read_table(str(plain)) == [
        {"wavelength_nm": 550.0, "tt": 0.5, "tr": 0.1, "n": 1.5, "g": 0.9, "thickness_mm": 1.0}]
    code, _, err = run(capsys, ["fit", "--table", tmp_path / "missing.csv", "--model", "km"])
    assert code == 2 and "missing.csv" in err


@FAST
@given(st.sampled_from([("700,0.3\n400,0.1\n", "strictly increasing"),
                        ("400,0.1\n400,0.3\n", "strictly increasing"),
                        ("400,0.1\nnan,0.3\n", "wavelength_nm"),
                        ("400,0.1\n1e300,0.3\n", "wavelength_nm"),
                        ("400,0.1\n700\n", "reflectance"),
                        ("400,0.1\n700,1.5\n", "reflectance")]))
def test_substrate_reflectance_file_is_checked_like_every_spectrum(tmp_path, case):
    body, named = case
    path = tmp_path / "stump.csv"
    path.write_text("wavelength_nm,reflectance\n" + body)
    with pytest.raises(ValueError) as exc:
        substrates.backings(f"reflectance:{path}")
    assert "stump.csv" in str(exc.value) and named in str(exc.value), str(exc.value)


# ---------------------------------------------------------------------------------------
# colour.json of a render folder (report --render)


@FAST
@given(st.sampled_from([deep(100_000), '{"regions": NaN}', '{"regions": {"a": {"rect": [1, 2]',
                        "\xe9t\xe9"]))
def test_render_folder_json_is_standard_bounded_and_named(tmp_path, text):
    from dentalux import report

    d = tmp_path / "render"
    d.mkdir(exist_ok=True)
    data = text.encode("latin-1") if "\xe9" in text else text.encode()
    (d / "colour.json").write_bytes(data)
    with pytest.raises(ValueError, match=r"colour\.json"):
        report._render(d)


def test_render_folder_without_image_blames_render_not_figure(tmp_path):
    from dentalux import report

    d = tmp_path / "render"
    d.mkdir()
    (d / "colour.json").write_text('{"regions": {}}')
    with pytest.raises(ValueError, match=r"--render.*image\.png") as exc:
        report._render(d)
    assert "--figure" not in str(exc.value)


# ---------------------------------------------------------------------------------------
# the Python API's counts and names


@FAST
@given(st.one_of(
    st.tuples(st.sampled_from(["photons", "seed", "threads"]),
              st.sampled_from([True, 500.7, "500", math.nan, -1, 2**70])),
    st.tuples(st.sampled_from(["contact"]), st.sampled_from(["x", True, 0.5, math.inf, 1e300]))))
def test_api_counts_are_strict_integers_named_as_the_argument(case):
    name, value = case
    args = {"photons": 1000, name: value}
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=rf"^{name} = "):
        dental.metrics("enamel", 1.0, bands=[550], **args)
    assert time.perf_counter() - t0 < 2  # refused before any photon


def test_api_names_reconstruction_and_design_nodes():
    from dentalux import design

    with pytest.raises(ValueError, match=r"^reconstruction = 'magic'"):
        dental.metrics("enamel", 1.0, bands=[550], reconstruction="magic")
    for nodes in (3.5, True, 100_000, 1):
        with pytest.raises(ValueError, match=r"nodes = "):
            design.optimise("lab:70,0,15", ["enamel:0.3-1.0"], photons=200, bands=[550],
                            nodes=nodes, check=False)


# ---------------------------------------------------------------------------------------
# every printed number finite, every --json strict

JSON_COMMANDS = [
    ["instruments", "list", "--json"],
    ["instruments", "show", "infinite", "--json"],
    ["materials", "list", "--json"],
    ["materials", "show", "enamel", "--json"],
    ["scene", "check", CORNELL, "--json"],
    ["scene", "check", CORNELL, "--dump", "--bands", "540", "--json"],
    ["shade", "enamel", "--bands", "450,550,650", "--photons", "500", "--json"],
    ["shade", "enamel", "--bands", "550", "--photons", "500", "--instrument", "infinite",
     "--json"],
    ["fit", "--tt", "0.4897", "--tr", "0.3016", "--n", "1.55", "--g", "0.75", "--thickness",
     "0.5", "--model", "ad", "--json"],
    ["slab", "--mua", "1", "--mus", "9", "--g", "0.75", "--thickness", "0.2", "--photons",
     "2000", "--json"],
]


@pytest.mark.parametrize("argv", JSON_COMMANDS, ids=lambda a: " ".join(map(str, a[:2])))
def test_json_output_is_strict_rfc8259(capsys, argv):
    try:
        main([str(a) for a in argv])
        code = 0
    except SystemExit as exc:
        code = exc.code or 0
    out, err = capsys.readouterr()
    assert code == 0, err
    strict_loads(out)


def test_cli_prints_json_only_through_strict_json():
    for path in (ROOT / "python" / "dentalux" / "cli").glob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "json.dumps(" not in text, f"{path.name} prints JSON past strict_json"


@FAST
@given(st.sampled_from([math.nan, math.inf, -math.inf]),
       st.sampled_from(["cr", "lab_white", "spectra.over_white"]))
def test_a_non_finite_result_is_an_error_naming_the_key(bad, key):
    out = {"cr": 0.5, "lab_white": [50.0, 1.0, 2.0], "spectra": {"over_white": [0.1, 0.2]},
           "contact_index": None}
    parts = key.split(".")
    target = out
    for p in parts[:-1]:
        target = target[p]
    if isinstance(target[parts[-1]], list):
        target[parts[-1]][1] = bad
    else:
        target[parts[-1]] = bad
    with pytest.raises(ValueError, match=rf"shade: the result's {key}"):
        check_finite(out, "shade")
    check_finite({"contact_index": None, "x": [1.0]}, "shade")  # None is not a number


def test_an_absurd_material_is_an_error_not_null(tmp_path, capsys):
    path = tmp_path / "opaque.toml"
    path.write_text(tomli_w.dumps({"materials": {"x": _material(mua=[1e6] * 3)}}))
    pure = tmp_path / "absorber.toml"
    pure.write_text(tomli_w.dumps({"materials": {"x": _material(mua=[1e6] * 3,
                                                                mus=[0.0] * 3)}}))
    # a pure absorber read 0-45 (specular excluded) by the walks: no photon comes back, Y = 0
    # over both backings and CR = 0/0
    code, out, err = run(capsys, ["shade", pure, "--bands", "450,550", "--photons", "300",
                                  "--solver", "monte-carlo", "--json"])
    assert code == 2 and out == "" and "the result's" in err, (out, err)
    # the layered solver keeps the light scattered once before it is absorbed (albedo about
    # 1e-6): a finite, black, opaque reading, the same over both backings
    code, out, err = run(capsys, ["shade", path, "--bands", "450,550", "--json"])
    assert code == 0, err
    got = json.loads(out)
    assert got["lab_white"][0] < 0.01 and got["cr"] == pytest.approx(1.0, abs=1e-6)


# ---------------------------------------------------------------------------------------
# work bounded before it starts; scene check and render share one validation


@pytest.mark.parametrize("argv, message", [
    (["shade", "enamel", "--bands", "full:0.0001"], "4,000,001 bands"),
    (["shade", "enamel", "--photons", "10000000000"], "about 11.4 h"),
    (["design", "--target", "lab:70,0,15", "--layer", "enamel:0.3-1.0", "--nodes", "100000"],
     "nodes = 100000"),
    (["tooth", "molar", "--resolution", "0.049", "--out", "{tmp}/t"], "about"),
    (["figures", "--only", "", "--out", "{tmp}/f"], "--only = ''"),
    (["scene", "check", CORNELL, "--dump", "--bands", "300"], "bands[0] = 300"),
])
def test_work_is_refused_up_front_with_an_estimate(tmp_path, capsys, argv, message):
    argv = [str(a).replace("{tmp}", str(tmp_path)) for a in argv]
    t0 = time.perf_counter()
    code, _, err = run(capsys, argv)
    assert code == 2 and message in err, err
    assert time.perf_counter() - t0 < 10
    assert not (tmp_path / "t").exists() and not (tmp_path / "f").exists()


def test_ceilings_are_documented():
    text = (ROOT / "docs" / "limits.md").read_text(encoding="utf-8")
    for name in ("MAX_READING_BANDS", "MAX_DESIGN_NODES", "MAX_DESIGN_PHOTONS",
                 "MAX_TOOTH_NODES", "MAX_TEXT_BYTES", "MAX_DEPTH", "MAX_ITEMS",
                 "MAX_CSV_FIELD", "WAVELENGTH_RANGE_NM", "DIAMETER_RANGE_MM",
                 "MAX_FIGURE_BYTES"):
        assert name in text, name
    assert limits.MAX_READING_BANDS == 4_001


# ---------------------------------------------------------------------------------------
# names and paths that mean one thing


def test_a_stack_target_takes_a_material_file_path(tmp_path):
    from dentalux.design.targets import parse_stack

    path = tmp_path / "lab" / "my.toml"
    assert parse_stack(f"{path}:0.5/dentin:2") == [(str(path), 0.5), ("dentin", 2.0)]
    assert parse_stack("enamel:1.0/dentin:2.5") == [("enamel", 1.0), ("dentin", 2.5)]
    with pytest.raises(ValueError, match="MATERIAL:MM"):
        parse_stack("enamel:x")
    # a layer whose thickness is not a number is that layer's error, not a file 'enamel:x/dentin'
    for text, layer in (("enamel:x/dentin:3", "enamel:x"), ("enamel:1,0/dentin:3", "enamel:1,0"),
                        ("enamel:1/dentin:y/enamel:0.5", "dentin:y")):
        with pytest.raises(ValueError, match=f"layer .* = '{layer}': expected MATERIAL:MM"):
            parse_stack(text)


@FAST
@given(st.sampled_from([True, False, 1.5, "1"]))
def test_mesh_indices_refuse_booleans_and_non_integers(index):
    from dentalux.scene.load import read_toml, scene_from_dict

    d = read_toml(CORNELL)
    shape = {k: v for k, v in d["shapes"][0].items() if k not in ("corner", "u", "v")}
    shape.update(type="mesh", name="m", positions=[[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                 triangles=[[0, 2, index]])
    d["shapes"].append(shape)
    with pytest.raises(ValueError, match=r"triangles\[0\]\[2\]"):
        scene_from_dict(d)


def test_scene_file_bom_is_tolerated_and_latin1_named(tmp_path, capsys):
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + CORNELL.read_bytes())
    code, out, _ = run(capsys, ["scene", "check", bom, "--json"])
    assert code in (0, None) and strict_loads(out)["name"] == "cornell"
    latin = tmp_path / "latin.toml"
    latin.write_bytes(CORNELL.read_bytes().replace(b'"cornell"', b'"caf\xe9"', 1))
    code, _, err = run(capsys, ["scene", "check", latin])
    assert code == 2 and "latin.toml" in err and "not UTF-8" in err, err


def test_json_files_in_outputs_name_the_files_where_they_finally_are(tmp_path):
    from dentalux.output_paths import staged_dir

    out = tmp_path / "out"
    with staged_dir(out, "--out") as stage:
        (stage / "image.png").write_bytes(b"x")
        (stage / "colour.json").write_text(json.dumps(
            {"files": {"png": str(stage / "image.png")}}, indent=2))
    files = json.loads((out / "colour.json").read_text())["files"]
    assert files == {"png": str(out / "image.png")} and Path(files["png"]).is_file()


def test_an_output_name_that_is_not_utf8_is_refused_before_writing(tmp_path, capsys):
    import os

    out = os.fsdecode(os.fsencode(str(tmp_path)) + b"/r\xe9")
    code, _, err = run(capsys, ["tooth", "incisor", "--resolution", "0.4", "--out", out])
    assert code == 2 and "not a UTF-8 name" in err, err
    assert list(tmp_path.iterdir()) == []


@FAST
@given(st.sampled_from([math.nan, math.inf, -550.0, 1e300, True, "550"]))
def test_fit_records_only_a_real_wavelength(wl):
    from dentalux.inverse import fit

    with pytest.raises(ValueError, match=r"^wavelength_nm = "):
        fit(tt=0.4897, tr=0.3016, n=1.55, g=0.75, thickness=0.5, model="km",
            wavelength_nm=wl)


def test_a_quoted_field_may_span_lines(tmp_path):
    """CSV as the csv module reads it: a quoted field holding a line break is one field, and
    rows after it keep their line numbers in messages."""
    from dentalux import inputs

    p = tmp_path / "t.csv"
    p.write_text('name,thickness_mm,note\na,1.0,"two\nlines"\nb\n')
    with pytest.raises(ValueError, match=r"line 4 has 1 field\(s\)"):
        inputs.read_csv(p)
    p.write_text('name,thickness_mm,note\na,1.0,"two\nlines"\nb,2.0,x\n')
    _, rows = inputs.read_csv(p)
    assert [r["note"] for r in rows] == ["two\nlines", "x"] and rows[1]["_line"] == 4


def test_a_column_named_twice_is_refused(tmp_path):
    """A header naming a column twice is refused naming the file, the line and the column
    (dict(zip()) kept the last copy and ignored the first)."""
    from dentalux import inputs

    p = tmp_path / "t.csv"
    p.write_text("# note\nname,L,a,b,L\nA1,70,0,10,90\n")
    with pytest.raises(ValueError, match=r"t\.csv: line 2: column 'L' appears twice"):
        inputs.read_csv(p, comments=True)
