"""``dentalux report``: one self-contained HTML file whose numbers are ``shade --json``'s,
opened in a real browser (headless Chromium through playwright; skipped with the reason when
no browser is installed: ``make browser`` installs Debian's ``chromium``)."""

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


def _expected_cells(shade_json: dict) -> dict[str, tuple[object, str]]:
    """JSON path -> (value, text the page shows) for every leaf of a shade JSON object."""
    cells = {}
    for key, value in report._leaves(shade_json):
        top = key.split(".", 1)[0]
        if top in report.SPECTRUM_KEYS or top in report.RUN_COST_KEYS:
            continue  # spectra are charted; a run's cost differs between runs
        if isinstance(value, float) and top in report.DIGITS:
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


def _check_cells(found: dict[str, tuple[str, str]], shade_json: dict) -> None:
    expected = _expected_cells(shade_json)
    assert set(expected) <= set(found), f"not in the page: {sorted(set(expected) - set(found))}"
    for key, (value, text) in expected.items():
        raw, shown = found[key]
        assert (raw if isinstance(value, str) else json.loads(raw)) == value, key
        assert shown == text, (key, shown, text)


def test_page_carries_the_shade_json_numbers(made):
    parser = _Cells()
    parser.feed(made["html"].read_text(encoding="utf-8"))
    assert set(parser.sections) == set(made["shade"])
    for material, out in made["shade"].items():
        assert {"lab_white", "tp00", "delta_e00", "verdict"} <= set(out)
        _check_cells(parser.sections[material], out)


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


def _chromium() -> str | None:
    for name in (os.environ.get("DENTALUX_CHROMIUM"), "chromium", "chromium-browser",
                 "google-chrome"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


def test_report_in_headless_chromium(made):
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
            assert page.locator("#geometry .note").first.is_visible()
            shot = made["tmp"] / "report.png"
            page.screenshot(path=str(shot), full_page=True)
        finally:
            browser.close()
    assert not problems, problems
    assert all(u.startswith(("file:", "data:")) for u in requests), requests
    assert shot.stat().st_size > 10_000
    print(f"screenshot: {shot}")
