"""The design's smaller tools (issue 42): ``--evaluate`` given thicknesses, the one-layer ΔE00
curve and the "no feasible design" words of ``--plot``, the table at 80 columns, and a draft
render's annotated image (large enough to judge, labels off the teeth).

Few photons and three bands throughout: the numbers are noise, the plumbing and the rules
are what is checked.
"""

from __future__ import annotations

import contextlib
import io
import json
import re

import numpy as np
import pytest
from dentalux import dental, design
from dentalux.design import evaluate as E
from dentalux.design import plot as P
from dentalux.design import render as R

BANDS = [450.0, 550.0, 650.0]
INSTRUMENT = "d8-benchtop-sav"


def _main(args) -> tuple[int, str, str]:
    from dentalux.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            pytest.raises(SystemExit) as exc:
        main(args)
    return exc.value.code or 0, out.getvalue(), err.getvalue()


# -- --evaluate ------------------------------------------------------------------------------


def test_candidates_are_parsed_and_bad_ones_refused():
    assert E.parse_candidates("0.5/0.9, 0.6/0.8", 2) == [[0.5, 0.9], [0.6, 0.8]]
    assert E.parse_candidates([[0.4], [0.7]], 1) == [[0.4], [0.7]]
    for text, layers, why in (("0.5/0.9,0.6", 2, "1 thickness(es) for 2 layer"),
                              ("0.5/x", 2, "'x' is out of range"),
                              ("0.5/0", 2, "'0' is out of range"),
                              ("", 1, "give thicknesses"),
                              (",".join(["0.5"] * 51), 1, "at most 50")):
        with pytest.raises(ValueError, match=re.escape(why)):
            E.parse_candidates(text, layers)
    assert E.parse_layers(["enamel", "dentin:0.3-1"]) == [("enamel", None),
                                                          ("dentin", (0.3, 1.0))]
    assert E.parse_layers(["x.toml:opaquer"])[0] == ("x.toml:opaquer", None)


def test_evaluate_reads_through_dental_read_and_ranks():
    """Each candidate is dental.read of the design's specimen (layers + substrate) with the
    seed of the verification; ranked by ΔE00, each with its error and verdict."""
    kw = dict(instrument=INSTRUMENT, bands=BANDS, photons=1500, seed=3)
    res = E.evaluate("lab:70,2,15", ["enamel:0.3-0.8", "dentin"],
                     "0.5/0.9,0.3/1.2,0.9/0.5", substrate="dentin", **kw)
    ev = res.evaluated
    assert [d["rank"] for d in ev] == [1, 2, 3]
    assert [d["delta_e00"] for d in ev] == sorted(d["delta_e00"] for d in ev)
    for d in ev:
        m = design.read(list(zip(["enamel", "dentin"], d["thickness_mm"], strict=True)),
                        "dentin", **{**kw, "seed": kw["seed"] + E.SEED_OFFSET})
        assert d["lab"] == m.lab_white  # the same reading, same seed
        assert d["verdict"] == dental.verdict(d["delta_e00"], d["delta_e00_stderr"])
        assert d["delta_e00_stderr"] > 0
    # 0.9 mm lies outside the enamel range 0.3-0.8: read, and marked
    assert {tuple(d["thickness_mm"]): d["within_ranges"] for d in ev} == {
        (0.5, 0.9): True, (0.3, 1.2): True, (0.9, 0.5): False}
    out = res.to_json()
    assert json.loads(json.dumps(out))["evaluated"][0]["thickness_mm"] == ev[0]["thickness_mm"]
    for d in out["evaluated"]:
        assert {"thickness_mm", "delta_e00", "delta_e00_stderr", "verdict"} <= set(d)


def test_cli_evaluate_json_and_table(capsys):
    args = ["design", "--target", "lab:70,2,15", "--layer", "enamel", "--instrument",
            INSTRUMENT, "--bands", "450,550,650", "--photons", "1000", "--substrate", "none",
            "--evaluate", "0.4,0.8,1.2"]
    rc, out, err = _main([*args, "--json"])
    assert rc == 0, err
    doc = json.loads(out)
    assert [d["thickness_mm"] for d in doc["evaluated"]] != []
    assert sorted(d["thickness_mm"][0] for d in doc["evaluated"]) == [0.4, 0.8, 1.2]
    assert doc["substrate"] == "none" and doc["layers"][0]["range_mm"] is None
    rc, out, err = _main([*args, "--evaluate", "0.4/0.5"])
    assert rc == 2 and "2 thickness(es) for 1 layer" in err
    rc, out, err = _main([*args, "--plot", "x.png"])
    assert rc == 2 and "--plot with --evaluate" in err


# -- the table at 80 columns -----------------------------------------------------------------


def test_design_table_is_readable_at_80_columns():
    from dentalux.cli.design import design_table
    from dentalux.design.targets import Target
    from rich.console import Console

    verdicts = ["imperceptible or acceptable", "unacceptable", "acceptable or unacceptable"]
    designs = [{"thickness_mm": [0.55, 0.85, 0.35], "lab": [71.23, -1.52, 16.04],
                "delta_e00": 1.234, "delta_e00_stderr": 0.321, "verdict": v,
                "sensitivity": [0.81, 1.23, 0.45], "verified": i != 1, "within_ranges": True}
               for i, v in enumerate(verdicts)]
    target = Target((70.0, 2.0, 15.0), 12.0, {"kind": "lab"})
    for evaluated in (False, True):
        console = Console(width=80, record=True, color_system=None)
        console.print(design_table(target, designs, "stump", "d8-benchtop-sav", evaluated))
        text = console.export_text()
        assert all(len(line) <= 80 for line in text.splitlines())
        assert "…" not in text
        words = text.split()
        for word in ("imperceptible", "unacceptable", "acceptable", "0.55/0.85/0.35",
                     "1.23±0.32", "71.2"):
            assert word in words, (word, text)
        if not evaluated:
            assert "0.81" in words and "NO" in words


# -- --plot -----------------------------------------------------------------------------------


def _texts(fig) -> str:
    return "\n".join(t.get_text() for ax in fig.axes for t in ax.texts)


def test_plot_one_layer_curve_and_no_feasible_design(tmp_path):
    kw = dict(instrument=INSTRUMENT, bands=BANDS, photons=1500, designs=2, substrate="none")
    # a target the layer reaches: its own colour at 0.7 mm
    lab = design.read([("enamel", 0.7)], "none", instrument=INSTRUMENT, bands=BANDS,
                      photons=4000).lab_white
    res = design.optimise(tuple(lab), [("enamel", (0.3, 1.2))], **kw)
    fig = P.figure(res, total="0.4-1.0")
    try:
        ax = fig.axes[0]
        curve = [ln for ln in ax.lines if len(ln.get_xdata()) == P.CURVE_POINTS]
        assert len(curve) == 1
        x, y = curve[0].get_xdata(), curve[0].get_ydata()
        assert x[0] == pytest.approx(0.3) and x[-1] == pytest.approx(1.2)
        assert np.all(np.isfinite(y)) and np.all(y >= 0)
        assert "thickness [mm]" in ax.get_xlabel()
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)
    png = tmp_path / "curve.png"
    rc, _, err = _main(["design", "--target", "lab:70,2,15", "--layer", "enamel:0.3-1.2",
                        "--instrument", INSTRUMENT, "--bands", "450,550,650", "--photons",
                        "1000", "--substrate", "none", "--designs", "1", "--plot", str(png),
                        "--json"])
    assert rc == 0, err
    assert png.stat().st_size > 10_000
    # a target nothing reaches: the words are on the curve and on the plane
    far = design.optimise("lab:20,30,-30", [("enamel", (0.3, 1.2))], **kw)
    far2 = design.optimise("lab:20,30,-30", [("enamel", (0.2, 0.6)), ("dentin", (0.3, 0.8))],
                           **kw)
    import matplotlib.pyplot as plt

    for r in (far, far2):
        fig = P.figure(r)
        try:
            assert "no feasible design" in _texts(fig)
            best = min(d["delta_e00"] for d in r.designs)
            assert best > dental.AT
        finally:
            plt.close(fig)
        # the plane's colours are not one flat field
        if r is far2:
            mesh = fig.axes[0].collections[0]
            assert mesh.norm.vmin > 0 and mesh.norm.vmax > mesh.norm.vmin
    fig = P.figure(res)
    try:
        assert "no feasible design" not in _texts(fig)
    finally:
        plt.close(fig)


# -- the draft render's annotated image ------------------------------------------------------


def test_draft_is_large_enough_and_labels_leave_the_teeth_free(tmp_path):
    from PIL import Image

    assert R.DRAFT.resolution[0] >= 160 and R.DRAFT.resolution[1] >= 120
    w, h = R.DRAFT.resolution
    rng = np.random.default_rng(1)
    img = (rng.random((h, w, 3)) * 255).astype(np.uint8)
    src, dst = tmp_path / "image.png", tmp_path / "crown.png"
    Image.fromarray(img).save(src)
    regions = {"natural": [49, 47, 60, 58], "crown": [100, 47, 111, 58]}
    layout = R.annotate(src, dst, regions, "ΔE00 1.23 (slab 1.10)")
    out = np.asarray(Image.open(dst).convert("RGB"))
    assert out.shape[1] >= R.ANNOTATED_MIN_WIDTH and out.shape[1] == layout["size"][0]
    s = layout["scale"]
    px0, py0, px1, py1 = layout["picture"]
    for box in [*layout["labels"].values(), layout["caption"]]:  # nothing on the picture
        _, y0, _, y1 = box
        assert y1 <= py0 or y0 >= py1, (box, layout["picture"])
    for name, (x0, _, x1, _) in regions.items():  # each label over its own square
        lx0, _, lx1, _ = layout["labels"][name]
        assert lx0 < (x0 + x1) / 2 * s < lx1
    # the picture is the render enlarged, pixel for pixel (away from the outlines)
    for x, y in ((10, 10), (80, 100), (55, 52), (150, 20)):
        got = out[int(py0) + y * s + s // 2, x * s + s // 2]
        assert np.abs(got.astype(int) - img[y, x].astype(int)).max() <= 2, (x, y)
