"""``dentalux report``: one self-contained HTML file whose numbers are ``shade --json``'s (or a
design result's, ``--design``), opening with a summary in plain words and colour swatches,
opened in a real browser (headless Chromium through playwright; skipped with the reason when
no browser is installed: ``make browser`` installs Debian's ``chromium``); the screenshot's
pixels must show the swatches' sRGB."""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest
from dentalux import report

TOML = """
[materials.toy]
description = "a toy composite for the report test"
wavelength_nm = [400.0, 700.0]
mua = [0.3, 0.05]
mus = [8.0, 5.0]
g = [0.6, 0.6]
fd = [0.1, 0.1]
n = [1.52, 1.52]

[materials.toy.provenance]
kind = "derived"
source = "report test material"
"""
# few photons, three bands: a report in a few seconds
COMMON = ["--thickness", "0.8", "--bands", "paper", "--photons", "1500", "--seed", "7",
          "--tp-thicknesses", "0.5,1.5"]


def _main(args) -> tuple[int, str, str]:
    from dentalux.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            pytest.raises(SystemExit) as exc:
        main(args)
    return exc.value.code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A report of a TOML material and a library material against dentin, and the JSON
    ``dentalux shade`` prints for each with the same arguments."""
    tmp = tmp_path_factory.mktemp("report")
    toy = tmp / "toy.toml"
    toy.write_text(TOML)
    materials = [str(toy), "enamel"]
    html = tmp / "shade report.html"
    rc, out, err = _main(["report", *materials, "--against", "dentin", *COMMON,
                          "--out", str(html)])
    assert rc == 0, err
    assert str(html) in out
    shade = {}
    for m in materials:
        rc, out, err = _main(["shade", m, "--against", "dentin", "--json",
                              *COMMON[:COMMON.index("--tp-thicknesses")]])
        assert rc == 0, err
        shade[m] = json.loads(out)
    return {"html": html, "shade": shade, "tmp": tmp}


def _expected_cells(shade_json: dict, only=None) -> dict[str, tuple[object, str]]:
    """JSON path -> (value, text the page shows) for every leaf of a shade JSON object (the
    instrument's are in the instrument section; ``only``: the top keys to take)."""
    cells = {}
    for key, value in report._leaves(shade_json):
        top = key.split(".", 1)[0]
        if top in report.SPECTRUM_KEYS or top in report.RUN_COST_KEYS:
            continue  # spectra are charted; a run's cost differs between runs
        if (top == report.INSTRUMENT_KEY) != (only == report.INSTRUMENT_KEY):
            continue  # stated once for all materials
        if top in report.PAIRED_KEYS:  # a standard error: the digits of its value
            top = key.split(".")[1]
        if top == "verdict_probability":
            text = report._percent(key, value)["text"]
        elif isinstance(value, float) and top in report.DIGITS:
            text = f"{value:.{report.DIGITS[top]}f}"
        elif isinstance(value, float):
            text = f"{value:.4g}"
        elif value is None:
            text = "—"
        else:
            text = str(value)
        cells[key] = (value, text)
    return cells


class _Cells(HTMLParser):
    """The data-key cells of each material section of a report."""

    def __init__(self):
        super().__init__()
        self.sections: dict[str, dict[str, tuple[str, str]]] = {}
        self._section = self._cell = None
        self._text = ""

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "section" and "data-material" in a:
            self._section = self.sections.setdefault(a["data-material"], {})
        elif tag == "section" and a.get("id") in ("instrument", "designs"):
            self._section = self.sections.setdefault("#" + a["id"], {})
        elif self._section is not None and "data-key" in a:
            self._cell, self._value, self._text = a["data-key"], a["data-value"], ""
            self._tag = tag

    def handle_data(self, data):
        if self._cell is not None:
            self._text += data

    def handle_endtag(self, tag):
        if self._cell is not None and tag == self._tag:
            self._section.setdefault(self._cell, (self._value, self._text.strip()))
            self._cell = None
        if tag == "section":
            self._section = None


def _check_cells(found: dict[str, tuple[str, str]], shade_json: dict, only=None) -> None:
    expected = _expected_cells(shade_json, only)
    assert set(expected) <= set(found), f"not in the page: {sorted(set(expected) - set(found))}"
    for key, (value, text) in expected.items():
        raw, shown = found[key]
        assert (raw if isinstance(value, str) else json.loads(raw)) == value, key
        assert shown == text, (key, shown, text)


def test_page_carries_the_shade_json_numbers(made):
    parser = _Cells()
    parser.feed(made["html"].read_text(encoding="utf-8"))
    assert set(parser.sections) == set(made["shade"]) | {"#instrument"}
    for material, out in made["shade"].items():
        assert {"lab_white", "tp00", "delta_e00", "verdict", "stderr"} <= set(out)
        _check_cells(parser.sections[material], out)
        # every value the tables show carries its standard error
        for key in ("lab_white.L", "lab_black.b", "tp", "tp00", "cr", "op"):
            assert f"stderr.{key}" in parser.sections[material], key
    # the instrument, stated once, with every leaf of its JSON
    for out in made["shade"].values():
        _check_cells(parser.sections["#instrument"], out, only=report.INSTRUMENT_KEY)


def test_page_is_self_contained_and_complete(made):
    from dentalux import __version__

    text = made["html"].read_text(encoding="utf-8")
    # no network: nothing fetched from elsewhere, images inline
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text)
    assert "<script" not in text and "<link" not in text
    assert len(re.findall(r'<img src="data:image/png;base64,', text)) == 3
    for out in made["shade"].values():  # the geometry the numbers were read in is stated
        assert report._geometry(out)["short"] in text
    assert f"dentalux {__version__}" in text and 'id="seed">7<' in text
    for needle in ("report test material", "Zoller", "PT 0.8", "AT 1.8", "toy", "dentin"):
        assert needle in text, needle


def test_infinite_geometry_is_stated_and_a_figure_and_render_embedded(tmp_path):
    from PIL import Image

    png = tmp_path / "render.png"
    Image.new("RGB", (8, 6), (200, 180, 150)).save(png)
    run = tmp_path / "run"  # what `dentalux render --out run` leaves (the parts read)
    run.mkdir()
    Image.new("RGB", (8, 6), (90, 90, 90)).save(run / "image.png")
    (run / "colour.json").write_text(json.dumps({
        "illuminant": "D65", "observer": "2",
        "regions": {"incisal": {"rect": [0, 0, 4, 3], "lab": [71.234, 1.5, 12.25]}}}))
    (run / "render.json").write_text(json.dumps({"scene_name": "crown"}))
    html = report.render_html(report.build("enamel", 1.0, instrument="infinite", bands="paper",
                                           photons=300, tp_thicknesses=[1.0], figure=png,
                                           render=run))
    assert 'id="infinite-geometry">infinite geometry: a laterally infinite disc' in html
    assert html.count('<img src="data:image/png;base64,') == 5 and "render.png" in html
    assert "crown (run/image.png)" in html and "incisal" in html and ">71.23<" in html
    (run / "colour.json").write_text("{")
    with pytest.raises(ValueError, match="--render"):
        report._render(run)
    with pytest.raises(ValueError, match="--render"):
        report._render(tmp_path)
    fake = tmp_path / "fake.png"
    fake.write_text("not an image")
    for bad, why in ((fake, "not a png"), (tmp_path / "r.gif", ".png or .jpg"),
                     (tmp_path / "none.png", "not found")):
        with pytest.raises((ValueError, FileNotFoundError), match=why):
            report._figure(bad)


def test_instrument_sections_are_rendered_from_the_json(monkeypatch, tmp_path):
    """Whatever instrument / edge_loss / shade_match keys `shade --json` gives appear."""
    real = report.shade_json

    def with_instrument(*args, **kw):
        out = real(*args, **{k: v for k, v in kw.items() if k != "instrument"})
        out.update({"instrument": {"name": "spectro-x", "aperture_mm": 3.0},
                    "edge_loss": {"tp00_drop": 1.25},
                    "shade_match": [{"tab": "A2", "delta_e00": 1.5}]})
        return out

    monkeypatch.setattr(report, "shade_json", with_instrument)
    ctx = report.build(["enamel"], 0.8, bands="paper", photons=500,
                       tp_thicknesses=[1.0])
    html = report.render_html(ctx)
    parser = _Cells()
    parser.feed(html)
    _check_cells(parser.sections["enamel"], with_instrument("enamel", 0.8, bands="paper",
                                                            photons=500))
    _check_cells(parser.sections["#instrument"], with_instrument("enamel", 0.8, bands="paper",
                                                                  photons=500),
                 only=report.INSTRUMENT_KEY)
    assert "infinite geometry:" not in html and "spectro-x" in html
    assert parser.sections["enamel"]["shade_match.0.tab"] == ("A2", "A2")


def test_bad_arguments_are_refused_before_any_work(tmp_path):
    for out, why in ((tmp_path / "r.txt", ".html"), (tmp_path, "folder"),
                     (Path("/proc/r.html"), "/proc")):
        rc, _, err = _main(["report", "enamel", "--thickness", "1", "--out", str(out)])
        assert rc == 2 and "--out" in err and why in err, err
    rc, _, err = _main(["report", "no-such-material", "--thickness", "1", "--bands", "paper",
                        "--photons", "200", "--out", str(tmp_path / "r.html")])
    assert rc == 2 and "no-such-material" in err
    assert not list(tmp_path.iterdir())  # nothing written, not even a partial file
    rc, _, err = _main(["report", "enamel", "--thickness", "1", "--instrument", "no-such-x",
                        "--bands", "paper", "--photons", "200", "--out",
                        str(tmp_path / "r.html")])
    assert rc == 2 and "no-such-x" in err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("thickness", ["-1", "0", "nan"])
def test_a_bad_thickness_is_refused_naming_thickness(tmp_path, thickness):
    rc, _, err = _main(["report", "enamel", "--thickness", thickness, "--bands", "paper",
                        "--photons", "200", "--out", str(tmp_path / "r.html")])
    assert rc == 2 and "thickness = " in err and "> 0" in err, err
    assert "tp-thicknesses" not in err and "Traceback" not in err, err
    assert not list(tmp_path.iterdir())


def _chromium() -> str | None:
    for name in (os.environ.get("DENTALUX_CHROMIUM"), "chromium", "chromium-browser",
                 "google-chrome"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


#: the largest difference [8-bit levels] between a swatch's sRGB and the screenshot's pixels
SWATCH_TOLERANCE = 3


def _swatches_render(page) -> int:
    """Each swatch's screenshot (the element's own, at the browser's sRGB) is its colour:
    the median of its inner pixels within SWATCH_TOLERANCE of ``data-srgb``; returns how
    many were checked."""
    import numpy as np
    from PIL import Image

    swatches = page.locator(".swatch")
    n = swatches.count()
    for i in range(n):
        sw = swatches.nth(i)
        want = np.array([int(x) for x in sw.get_attribute("data-srgb").split(",")])
        img = np.asarray(Image.open(io.BytesIO(sw.screenshot())).convert("RGB"), float)
        h, w = img.shape[:2]
        assert h >= 50 and w >= 50, (h, w)
        inner = img[h // 4: 3 * h // 4, w // 4: 3 * w // 4].reshape(-1, 3)
        got = np.median(inner, axis=0)
        assert np.abs(got - want).max() <= SWATCH_TOLERANCE, (i, got, want)
    return n


def test_report_in_headless_chromium(made, made_design):
    sync_api = pytest.importorskip("playwright.sync_api",
                                   reason="playwright is not installed (pip install -e .[test])")
    exe = _chromium()
    if exe is None:
        pytest.skip("no Chromium installed: `make browser` installs Debian's chromium (as root)")
    problems, requests = [], []
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=exe)
        try:
            page = browser.new_page(viewport={"width": 1100, "height": 900})
            page.on("console", lambda m: m.type in ("error", "warning") and problems.append(
                f"console {m.type}: {m.text}"))
            page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
            page.on("requestfailed", lambda r: problems.append(f"request failed: {r.url}"))
            page.on("request", lambda r: requests.append(r.url))
            page.goto(made["html"].as_uri(), wait_until="load")
            assert page.title().startswith("dentalux shade report")
            for material, out in made["shade"].items():
                section = page.locator(f'section[data-material="{material}"]')
                cells = section.locator("[data-key]").evaluate_all(
                    "els => els.map(e => [e.dataset.key, e.dataset.value, e.innerText.trim()])")
                found = {}
                for key, raw, text in cells:
                    found.setdefault(key, (raw, text))
                _check_cells(found, out)
            images = page.locator("img").evaluate_all(
                "els => els.map(e => [e.complete, e.naturalWidth, e.naturalHeight, "
                "e.getBoundingClientRect().width, e.getBoundingClientRect().height])")
            assert len(images) == 3
            for complete, nw, nh, w, h in images:
                assert complete and nw > 0 and nh > 0 and w > 0 and h > 0, images
            assert page.locator("#instrument .note").first.is_visible()
            # the summary comes first, and its swatches render in their colours
            assert page.locator("body > section").first.get_attribute("id") == "summary"
            assert _swatches_render(page) == 2 * len(made["shade"])
            shot = made["tmp"] / "report.png"
            page.screenshot(path=str(shot), full_page=True)
            page.goto(made_design["html"].as_uri(), wait_until="load")
            assert _swatches_render(page) == 1 + len(made_design["json"]["designs"])
            cells = page.locator("#designs [data-key]").evaluate_all(
                "els => els.map(e => [e.dataset.key, e.dataset.value, e.innerText.trim()])")
            assert {c[0] for c in cells} >= {"designs.0.delta_e00", "designs.0.verdict"}
        finally:
            browser.close()
    assert not problems, problems
    assert all(u.startswith(("file:", "data:")) for u in requests), requests
    assert shot.stat().st_size > 10_000
    print(f"screenshot: {shot}")


# -- the summary a clinician reads ---------------------------------------------------------


def test_summary_opens_the_page_in_plain_words(made):
    from dentalux import dental
    from dentalux.color import lab_to_display_srgb

    text = made["html"].read_text(encoding="utf-8")
    body = text[text.index("<body>"):]
    assert body.index('id="summary"') < body.index('id="instrument"') \
        < body.index("data-material=")
    summary = body[body.index('id="summary"'):body.index('id="instrument"')]
    for material, out in made["shade"].items():
        de, se = out["delta_e00"], out["delta_e00_stderr"]
        assert out["verdict"] == dental.verdict(de, se)
        assert "ΔE00 to dentin@" in summary
        assert f"{de:.2f} ± {se:.2f}, {out['verdict']}:" in summary, material
        assert f"TP00 {out['tp00']:.1f} ± {out['stderr']['tp00']:.1f}" in summary
        assert "Probability of each verdict: imperceptible" in summary
        # the prediction's swatch is its CIELAB over white in display sRGB
        rgb = ",".join(map(str, lab_to_display_srgb(out["lab_white"])["rgb"]))
        assert f'data-srgb="{rgb}" data-lab-key="lab_white"' in summary
    assert summary.count('class="swatch"') == 2 * len(made["shade"])
    assert summary.count('data-lab-key="target.lab_white"') == len(made["shade"])
    # the instrument is stated once, not for each material
    assert text.count('data-key="instrument.name"') == 1
    assert text.count("As read by instrument") == 1


def test_lab_to_display_srgb():
    from dentalux.color import lab_to_display_srgb

    assert lab_to_display_srgb([100.0, 0.0, 0.0])["rgb"] == (255, 255, 255)
    grey = lab_to_display_srgb([50.0, 0.0, 0.0])
    assert grey["rgb"] == (119, 119, 119) and grey["hex"] == "#777777" and not grey["clipped"]
    assert lab_to_display_srgb([50.0, 120.0, -120.0])["clipped"]


# -- a design result (report --design) -------------------------------------------------------


@pytest.fixture(scope="module")
def made_design(tmp_path_factory):
    """A two-layer design of library materials (few photons, three bands), its --json
    result, and the report of it."""
    tmp = tmp_path_factory.mktemp("report-design")
    rc, out, err = _main(["design", "--target", "lab:62,1,8", "--layer", "enamel:0.2-0.8",
                          "--layer", "dentin:0.3-1.0", "--bands", "450,550,650",
                          "--photons", "1500", "--designs", "2", "--json"])
    assert rc in (0, None), err
    return _design_report(tmp, json.loads(out))


def _design_report(tmp, doc) -> dict:
    path = tmp / "design.json"
    path.write_text(json.dumps(doc))
    html = tmp / "design report.html"
    rc, out, err = _main(["report", "--design", str(path), "--photons", "1500",
                          "--out", str(html)])
    assert rc == 0, err
    return {"html": html, "json": doc, "path": path, "tmp": tmp}


def test_design_report_carries_the_design_numbers(made_design):
    from dentalux.color import lab_to_display_srgb

    doc = made_design["json"]
    text = made_design["html"].read_text(encoding="utf-8")
    assert {"substrate", "layers", "cement", "bands_nm"} <= set(doc)  # design --json's new keys
    parser = _Cells()
    parser.feed(text)
    cells = parser.sections["#designs"]
    for i, d in enumerate(doc["designs"]):
        for key, digits in (("delta_e00", 2), ("delta_e00_stderr", 2)):
            raw, shown = cells[f"designs.{i}.{key}"]
            assert json.loads(raw) == d[key] and shown == f"{d[key]:.{digits}f}"
        assert cells[f"designs.{i}.verdict"] == (d["verdict"], d["verdict"])
        for j, (x, e) in enumerate(zip(d["lab"], d["lab_stderr"], strict=True)):
            assert json.loads(cells[f"designs.{i}.lab.{j}"][0]) == x
            assert json.loads(cells[f"designs.{i}.lab_stderr.{j}"][0]) == e
        rgb = ",".join(map(str, lab_to_display_srgb(d["lab"])["rgb"]))
        assert f'data-srgb="{rgb}" data-lab-key="designs.{i}.lab"' in text
    _check_cells(parser.sections["#instrument"], doc, only=report.INSTRUMENT_KEY)
    best = doc["designs"][0]
    summary = text[text.index('id="summary"'):text.index('id="instrument"')]
    assert f"{best['delta_e00']:.2f} ± {best['delta_e00_stderr']:.2f}, {best['verdict']}" \
        in summary
    assert "Best design for L*a*b* 62.0 1.0 8.0: enamel@" in summary
    assert "Translucency TP00" in summary  # read from the best design's specimen
    assert summary.count('class="swatch"') == 1 + len(doc["designs"])
    assert text.count('<img src="data:image/png;base64,') == 2  # spectra, optics
    assert "dentalux design report" in text and "<script" not in text


def test_design_report_refuses_bad_files_before_any_work(made_design, tmp_path):
    out = tmp_path / "r.html"
    bad = tmp_path / "bad.json"
    for content, why in (('{"designs": []}', "no 'designs' list"),
                         (json.dumps({**made_design["json"], "target": {}}), "'lab' triple"),
                         (json.dumps({**made_design["json"], "designs": [{"lab": [1, 2, 3]}]}),
                          "designs[0] lacks thickness_mm")):
        bad.write_text(content)
        rc, _, err = _main(["report", "--design", str(bad), "--out", str(out)])
        assert rc == 2 and "--design" in err and why in err, err
    rc, _, err = _main(["report", "--design", str(tmp_path / "none.json"), "--out", str(out)])
    assert rc == 2 and "not found" in err
    rc, _, err = _main(["report", "enamel", "--design", str(made_design["path"]),
                        "--out", str(out)])
    assert rc == 2 and "alone" in err
    rc, _, err = _main(["report", "--out", str(out)])
    assert rc == 2 and "--design" in err
    assert not out.exists()
    # a design file without the new keys still reports, saying why no spectra were read
    old = {k: v for k, v in made_design["json"].items()
           if k not in ("substrate", "layers", "cement", "bands_nm")}
    html = report.render_html(report.build_design(_write(tmp_path / "old.json", old),
                                                  photons=500))
    assert "does not name its substrate" in html and "Translucency was not read" in html


def _write(path, doc):
    path.write_text(json.dumps(doc))
    return path


def test_an_evaluate_result_of_a_toml_material_is_reported(made):
    """`design --evaluate --json` of a TOML material: the report takes its ranked candidates,
    and reads the best one's spectra again from the material file (``layers[].spec``)."""
    toy = made["tmp"] / "toy.toml"
    rc, out, err = _main(["design", "--target", "lab:60,1,8", "--layer", str(toy),
                          "--substrate", "none", "--bands", "450,550,650", "--photons",
                          "1000", "--evaluate", "0.5,1.0", "--json"])
    assert rc == 0, err
    doc = json.loads(out)
    assert doc["layers"][0]["spec"] == str(toy)
    path = _write(made["tmp"] / "evaluated.json", doc)
    html = report.render_html(report.build_design(path, photons=1000))
    assert "Best of the thicknesses evaluated for L*a*b* 60.0 1.0 8.0: toy" in html
    assert 'data-key="evaluated.1.delta_e00"' in html
    assert "Translucency TP00" in html and "report test material" in html  # read, provenance
