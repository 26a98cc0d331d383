"""Restoration design (issue 19): shade-guide loader, round trip, verification, physics, bad input.

The candidate materials are this file's own TOML (fixed numbers), so the tests hold whatever
the library's enamel and dentin become; the ``dentin`` and ``stump`` substrates use the
library's dentin, and the tests ask only for relations and round trips.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from dentalux import dental, design, shade_guides
from dentalux.color import delta_e00
from dentalux.design import constraints, search, substrates

BANDS = [450.0, 500.0, 550.0, 600.0, 650.0]
INSTRUMENT = "d8-benchtop-sav"

TOML = """
[materials.eshade]
description = "translucent enamel-shade composite (test material)"
wavelength_nm = [400.0, 700.0]
mua = [0.08, 0.02]
mus = [6.0, 3.0]
g = [0.8, 0.8]
fd = [0.0, 0.0]
n = [1.52, 1.52]

[materials.eshade.provenance]
kind = "derived"
source = "test material"

[materials.dshade]
description = "opaque, yellowish dentin-shade composite (test material)"
wavelength_nm = [400.0, 700.0]
mua = [0.9, 0.05]
mus = [30.0, 22.0]
g = [0.7, 0.7]
fd = [0.0, 0.0]
n = [1.52, 1.52]

[materials.dshade.provenance]
kind = "derived"
source = "test material"

[materials.opaquer]
description = "white opaquer (test material)"
wavelength_nm = [400.0, 700.0]
mua = [0.05, 0.02]
mus = [40.0, 35.0]
g = [0.5, 0.5]
fd = [0.0, 0.0]
n = [1.52, 1.52]

[materials.opaquer.provenance]
kind = "derived"
source = "test material"

[materials.redonly]
description = "a material with data only in the red (test material)"
wavelength_nm = [632.0, 780.0]
mua = [0.1, 0.1]
mus = [5.0, 4.0]
g = [0.8, 0.8]
fd = [0.0, 0.0]
n = [1.5, 1.5]

[materials.redonly.provenance]
kind = "derived"
source = "test material"
"""


@pytest.fixture(scope="module")
def mats(tmp_path_factory):
    path = tmp_path_factory.mktemp("design") / "shades.toml"
    path.write_text(TOML)
    return {name: f"{path}:{name}" for name in ("eshade", "dshade", "opaquer", "redonly")}


def _main(args):
    from dentalux.cli import main

    with pytest.raises(SystemExit) as exc:
        main(args)
    return exc.value.code


# -- shade guides ------------------------------------------------------------------------


def test_shade_guides_loader():
    assert {"vita-classical", "vita-3d-master"} <= set(shade_guides.guides())
    tabs = shade_guides.load("vita-classical")
    assert "A2" in tabs and len(tabs) == 16
    with pytest.raises(ValueError, match=r"vita-classical:A2.*no published CIELAB"):
        shade_guides.lab("vita-classical", "A2")
    with pytest.raises(ValueError, match=r"vita-3d-master:2M2.*no published CIELAB"):
        shade_guides.lab("vita-3d-master", "2M2")
    with pytest.raises(ValueError, match=r"tab 'Z9'.*allowed A1, A2"):
        shade_guides.lab("vita-classical", "Z9")
    with pytest.raises(ValueError, match=r"shade guide 'vita-clasical' is unknown.*did you mean"):
        shade_guides.load("vita-clasical")
    with pytest.raises(ValueError, match="no tab has published CIELAB"):
        shade_guides.nearest((70, 0, 15), "vita-classical")
    # the one transcribed cross-check row is readable, and nearest finds it at ΔE00 0
    lab = shade_guides.lab("vita-classical@sahrir2024", "A2")
    assert len(lab) == 3 and 0 < lab[0] < 100
    (tab, de), = shade_guides.nearest(lab, "vita-classical@sahrir2024", n=1)
    assert tab == "A2" and de == pytest.approx(0.0, abs=1e-9)


# -- specimen ----------------------------------------------------------------------------


def test_specimen_and_backings(mats, tmp_path):
    spec = design.specimen([("enamel", 0.5), ("dentin", 0.7)], "dentin")
    assert spec[:2] == [("enamel", 0.5), ("dentin", 0.7)]
    assert spec[2] == ("dentin", substrates.SUBSTRATE_DENTIN_MM)
    assert design.backings("dentin") == {}
    assert design.specimen([("enamel", 0.5)], "none") == [("enamel", 0.5)]
    assert design.backings("zirconia") == {"backing_black": 0.75, "backing_white": 0.75}
    assert design.specimen([("enamel", 0.5)], "zirconia") == [("enamel", 0.5)]
    spec = design.specimen([("enamel", 0.5)], "stump", cement=(mats["opaquer"], 0.1))
    assert spec[1] == (mats["opaquer"], 0.1)
    assert "+scaled" in spec[2][0].name and spec[2][1] == substrates.SUBSTRATE_DENTIN_MM
    assert design.backings("reflectance:0.2") == {"backing_black": 0.2, "backing_white": 0.2}
    assert design.parse_fixed_layers(["enamel:0.5", f"{mats['dshade']}:0.7"]) == [
        ("enamel", 0.5), (mats["dshade"], 0.7)]
    for bad, msg in ((["enamel:0"], "out of range"), (["enamel"], "MATERIAL:THICKNESS"),
                     ([], "at least one"), (["enamel:0.5"] * 4, "allowed 1 to 3")):
        with pytest.raises(ValueError, match=msg):
            design.parse_fixed_layers(bad)
    with pytest.raises(ValueError, match="substrate = 'bone' is unknown: allowed none"):
        design.specimen([("enamel", 0.5)], "bone")
    with pytest.raises(ValueError, match=r"reflectance:R needs R in \[0, 1\]"):
        design.backings("reflectance:1.5")
    csv = tmp_path / "stump.csv"
    csv.write_text("wavelength_nm,reflectance\n400,0.1\n700,0.3\n")
    assert design.backings(f"reflectance:{csv}")["backing_white"] == ((400.0, 700.0), (0.1, 0.3))
    csv.write_text("wavelength_nm,reflectance\n400,0.1\n700,1.3\n")
    with pytest.raises(ValueError, match=r"reflectance must lie in \[0, 1\]"):
        design.backings(f"reflectance:{csv}")


# -- round trip and verification -----------------------------------------------------------

TRUTH = (0.5, 0.6)


@pytest.fixture(scope="module")
def round_trip(mats):
    """A 0.5 / 0.6 mm stack of the two test composites read alone (substrate none, so the
    library's tissues do not enter) is the target; the design searches both thicknesses.
    The target and the verification are read with 60 000 photons per band: two reads of the
    same colour at 20 000 photons already differ by 0.3-0.6 ΔE00 at 5 bands, which would
    leave no room under 0.8 for the thickness error."""
    layers = [(mats["eshade"], TRUTH[0]), (mats["dshade"], TRUTH[1])]
    ref = design.read(layers, "none", instrument=INSTRUMENT, bands=BANDS, photons=60_000,
                      seed=2)
    target = design.Target(tuple(ref.lab_white), None, {"kind": "test"},
                           tuple(ref.stderr[f"lab_white.{c}"] for c in "Lab"))
    res = design.optimise(target, [(mats["eshade"], (0.2, 1.0)), (mats["dshade"], (0.2, 1.0))],
                          total=(0.6, 1.6), substrate="none", instrument=INSTRUMENT,
                          bands=BANDS, photons=40_000, verify_photons=60_000, designs=1,
                          seed=1)
    return ref, res


def test_round_trip_recovers_thicknesses(round_trip):
    ref, res = round_trip
    best = res.designs[0]
    assert best["delta_e00"] < dental.PT, best
    assert all(s > 0.05 for s in best["sensitivity"]), best
    # the sensitivity-implied tolerance: the colour's uncertainty (target and fast model,
    # per L*, a*, b*) mapped to thickness through the fast model's sensitivities
    # J = dLab/dt, Cov(t) = (J^T C^-1 J)^-1; the truth must lie within 4 of its standard
    # deviations of the design (Mahalanobis distance; along the valley where thinner enamel
    # and more dentin give the same colour, the tolerance is long, across it short)
    j = search.jacobian(res.surface, np.asarray(best["thickness_mm"]))
    var = (np.asarray(best["fast_model"]["lab_stderr"]) ** 2
           + np.asarray([ref.stderr[f"lab_white.{c}"] for c in "Lab"]) ** 2)
    cov_t = np.linalg.inv(j.T @ np.diag(1.0 / var) @ j)
    dt = np.asarray(best["thickness_mm"]) - np.asarray(TRUTH)
    distance = float(np.sqrt(dt @ np.linalg.inv(cov_t) @ dt))
    assert distance <= 4.0, (distance, best["thickness_mm"], np.sqrt(np.diag(cov_t)))


def test_verification_agrees_with_fast_model(round_trip):
    _, res = round_trip
    best = res.designs[0]
    assert best["verification"]["max_abs_z"] <= 4.0, best["verification"]
    # verified means the check could have failed: 4 combined standard errors under a
    # perceptible ΔE00 0.8 (with 5 bands at 60 000 photons they amount to about 1.2)
    v = best["verification"]
    assert v["could_fail"] == (v["resolution_delta_e00"] <= dental.PT)
    assert best["verified"] is v["could_fail"], v
    # the reported numbers are the Monte Carlo read's
    fast = np.asarray(best["fast_model"]["lab"])
    assert float(delta_e00(fast, np.asarray(best["lab"]))) < 2.0
    assert best["verdict"] == dental.verdict(best["delta_e00"], best["delta_e00_stderr"])
    assert len(best["sensitivity"]) == 2 and all(s >= 0 for s in best["sensitivity"])


# -- physics sense -------------------------------------------------------------------------


def test_thicker_opaque_layer_masks_the_stump(mats):
    kw = dict(instrument=INSTRUMENT, bands=BANDS, photons=8000)
    influence = []
    for t in (0.1, 0.6):
        on_stump = design.read([(mats["opaquer"], t)], "stump", seed=11, **kw)
        on_dentin = design.read([(mats["opaquer"], t)], "dentin", seed=12, **kw)
        cmp = dental.compare(on_stump, on_dentin)
        influence.append((cmp["delta_e00"], cmp["delta_e00_stderr"]))
    (thin, s_thin), (thick, s_thick) = influence
    assert thin - thick > 3 * math.hypot(s_thin, s_thick), influence


def test_more_enamel_shade_raises_tp(mats):
    kw = dict(instrument=INSTRUMENT, bands=BANDS, photons=8000)
    # the same 1.0 mm restoration, more of it enamel-shade (alone, as a disc is read)
    less = design.read([(mats["eshade"], 0.3), (mats["dshade"], 0.7)], "none", seed=21, **kw)
    more = design.read([(mats["eshade"], 0.7), (mats["dshade"], 0.3)], "none", seed=22, **kw)
    assert more.tp00 - less.tp00 > 3 * math.hypot(more.stderr["tp00"], less.stderr["tp00"])


# -- contract and bad input ----------------------------------------------------------------


def test_cli_json_contract_and_plot(mats, tmp_path, capsys):
    png = tmp_path / "plane.png"
    code = _main(["design", "--target", "lab:70,2,15", "--layer", f"{mats['eshade']}:0.2-0.6",
                  "--layer", f"{mats['dshade']}:0.3-0.8", "--total", "0.5-1.2", "--substrate",
                  "zirconia", "--instrument", INSTRUMENT, "--bands", "450,550,650",
                  "--photons", "1500", "--designs", "2", "--plot", str(png), "--json"])
    assert code in (0, None)
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"target", "designs", "instrument", "seconds", "cpu_seconds",
                        "photons_per_band", "substrate", "layers", "cement", "bands_nm"}
    assert out["substrate"] == "zirconia" and out["cement"] is None
    assert [lay["range_mm"] for lay in out["layers"]] == [[0.2, 0.6], [0.3, 0.8]]
    assert out["target"]["lab"] == [70.0, 2.0, 15.0]
    assert out["instrument"]["backing_white"] == 0.75  # the zirconia core is the backing
    assert 1 <= len(out["designs"]) <= 2
    for d in out["designs"]:
        assert {"thickness_mm", "lab", "delta_e00", "delta_e00_stderr", "verdict",
                "sensitivity", "verified"} <= set(d)
        assert len(d["thickness_mm"]) == 2 and 0.5 - 1e-9 <= sum(d["thickness_mm"]) <= 1.2
        assert isinstance(d["verified"], bool)
        assert len(d["thickness_stderr_mm"]) == 2
        assert all(x is None or x > 0 for x in d["thickness_stderr_mm"])
    assert png.stat().st_size > 1000


def test_target_tp_is_reported(mats):
    res = design.optimise("lab:70,2,15", [(mats["eshade"], (0.2, 1.0))], substrate="none",
                          instrument=INSTRUMENT, bands=[450, 550, 650], target_tp=10.0,
                          photons=1500, designs=1)
    d = res.designs[0]
    assert {"tp00", "delta_tp00", "translucency_verdict"} <= set(d)
    assert res.to_json()["target"]["tp00"] == 10.0


@pytest.mark.parametrize("args, message", [
    (["--layer", "E:0.8-0.3"], "inverted"),
    (["--layer", "E:0.5-0.5"], "empty"),
    (["--layer", "E:"], "expected MIN-MAX"),
    (["--layer", "E:0.2-0.4", "--layer", "D:0.2-0.4", "--total", "2.0-3.0"], "cannot be met"),
    (["--layer", "E:0.2-0.4"] * 4, "allowed 1 to 3 layers"),
    (["--layer", "R:0.2-0.4"], "no data over the bands"),
    (["--layer", "E:0.2-0.4", "--target", "vita-classical:Z9"], "tab 'Z9'"),
    (["--layer", "E:0.2-0.4", "--target", "vita-modern:A2"], "neither lab, stack nor"),
    (["--layer", "E:0.2-0.4", "--target", "vita-classical:A2"], "no published CIELAB"),
    (["--layer", "E:0.2-0.4", "--target", "lab:101,0,0"], "outside the CIELAB range"),
    (["--layer", "E:0.2-0.4", "--target", "lab:50,0,200"], "outside the CIELAB range"),
    (["--layer", "E:0.2-0.4", "--target-tp", "-1"], "target_tp"),
    (["--layer", "E:0.2-0.4", "--substrate", "bone"], "substrate"),
    (["--layer", "E:0.2-0.4", "--substrate", "zirconia", "--target-tp", "5"], "TP is 0"),
    (["--layer", "E:0.2-0.4", "--substrate", "zirconia", "--render", "out"],
     "cannot be rendered"),
    (["--layer", "E:0.2-0.4"] * 3 + ["--plot", "plane.png"], "1 or 2 layers"),
    (["--layer", "E:0.2-0.4", "--layer", "D:0.2-0.4", "--plot", "plane.txt"], "end in .png"),
])
def test_cli_bad_input_exits_2(mats, capsys, args, message):
    names = {"E": mats["eshade"], "D": mats["dshade"], "R": mats["redonly"]}
    args = [a.replace(a[:1], names[a[:1]], 1) if a[:1] in names and ":" in a
            and not a.startswith(("lab:", "vita")) else a for a in args]
    if "--target" not in args:
        args = ["--target", "lab:70,0,15"] + args
    code = _main(["design", *args, "--bands", "450,500,550,600,650", "--photons", "100",
                  "--json"])
    assert code == 2
    assert message in capsys.readouterr().err


def test_api_bad_input_is_valueerror(mats):
    with pytest.raises(ValueError, match="inverted"):
        design.optimise("lab:70,0,15", [(mats["eshade"], (0.8, 0.3))])
    with pytest.raises(ValueError, match="at least one layer"):
        design.optimise("lab:70,0,15", [])
    with pytest.raises(ValueError, match="cannot be met"):
        design.optimise("lab:70,0,15", [(mats["eshade"], (0.2, 0.4))], total=(1.0, 2.0))
    with pytest.raises(ValueError, match=r"a\* = -200 is outside the CIELAB range"):
        design.optimise((70, -200, 15), [(mats["eshade"], (0.2, 0.4))])
    with pytest.raises(ValueError, match="no data over the bands"):
        design.optimise("lab:70,0,15", [(mats["redonly"], (0.2, 0.4))], bands=BANDS)
    assert constraints.parse_range("0.3-0.8", "x") == (0.3, 0.8)


def test_infinite_geometry_design_agrees_and_an_imprecise_check_verifies_nothing(mats):
    """The ``infinite`` instrument (the adding formula of dental.read) drives the fast model
    too, and the verification agrees with it; at 4 000 photons and 3 bands, 4 standard
    errors amount to more than a perceptible difference, so it cannot call the design
    verified and says why."""
    res = design.optimise("lab:70,2,15", [(mats["dshade"], (0.2, 1.0))], substrate="dentin",
                          instrument="infinite", bands=[450, 550, 650], photons=4000,
                          designs=1, solver="monte-carlo")
    d = res.designs[0]
    v = d["verification"]
    assert v["max_abs_z"] <= 4.0, v
    assert v["resolution_delta_e00"] > dental.PT and not v["could_fail"]
    assert d["verified"] is False and "inconclusive" in v["note"]
    assert res.to_json()["instrument"]["name"] == "infinite"


def test_a_noise_free_verification_can_fail():
    """Both reads noise-free (the layered solver, no rim): the comparison still allows only
    the floor that stands for the fast model's interpolation (verify.FLOOR), so a
    disagreement of 4 floors or more is caught and a smaller one passes; with a zero floor
    every z would be 0 and the check could not fail."""
    from types import SimpleNamespace

    from dentalux.design import verify

    lab = [70.0, 2.0, 15.0]
    zero = {"lab_white.L": 0.0, "lab_white.a": 0.0, "lab_white.b": 0.0, "tp00": 0.0}
    read = SimpleNamespace(lab_white=lab, tp00=10.0, stderr=zero)

    def fast(shift):
        return {"values": {"lab_white": [lab[0], lab[1], lab[2] + shift], "tp00": 10.0},
                "stderr": {"lab_white": [0.0, 0.0, 0.0], "tp00": 0.0}}

    near = verify.compare(fast(0.5 * verify.SIGMAS * verify.FLOOR), read, tp=True)
    far = verify.compare(fast(1.5 * verify.SIGMAS * verify.FLOOR), read, tp=True)
    assert near["verified"] and near["could_fail"], near
    assert not far["verified"] and not far["agrees"] and far["could_fail"], far
    assert far["max_abs_z"] == pytest.approx(1.5 * verify.SIGMAS)
