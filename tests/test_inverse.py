"""Inversion (dentalux.inverse): forward models against closed forms and adding-doubling,
the paper's Table 1, bounds, intervals and the CLI contract.

Longer validation (every model on every Table 1 row with Monte Carlo round trips, the full
synthetic grid with ad and mc) is in test_inverse_slow.py under @pytest.mark.slow.
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest
import tomllib
from dentalux.cli import main
from dentalux.inverse import FitResult, fit, fit_table
from dentalux.inverse.models import Sample, get_model
from dentalux.inverse.models.boundary import moments, specular
from dentalux.inverse.result import JSON_KEYS
from dentalux.slab import Layer, simulate

DATA = Path(__file__).resolve().parents[1] / "python" / "dentalux" / "data"
TABLE1 = DATA / "table1.csv"
ROWS = {  # wavelength: (tt, tr, n) from the paper's Table 1; g = 0.75, d = 0.5 mm
    450: (0.4897, 0.3016, 1.550),
    540: (0.6016, 0.3243, 1.540),
    605: (0.6540, 0.3255, 1.537),
}


# ---------------------------------------------------------------- forward models

def test_fresnel_moments_match_tabulated_boundary_numbers():
    # docs/explanation/tooth-optics.md 2.5: diffuse internal reflectance r_i for n = 1.50,
    # 1.54, 1.63 (to air)
    for n, r_i in ((1.50, 0.5963), (1.54, 0.6195), (1.63, 0.6652)):
        r_phi, r_j = moments(n, 1.0)
        assert abs(r_phi - r_i) < 1e-4
        # r_i = 1 - (1 - r_e)/n^2 with r_e the external diffuse reflectance (2.5 table)
        assert 0.0 < r_j < r_phi
    assert moments(1.0, 1.0) == pytest.approx((0.0, 0.0), abs=1e-15)


@pytest.mark.parametrize("name", ["telegrapher", "km"])
def test_no_absorption_conserves_energy(name):
    model = get_model(name)
    mus = np.array([0.1, 1.0, 10.0, 100.0])
    for g, n, d in ((0.0, 1.0, 1.0), (0.75, 1.55, 0.5), (0.96, 1.63, 3.0)):
        tt, tr = model.forward(np.zeros_like(mus), mus, Sample(g=g, n=n, thickness=d))
        assert np.allclose(tt + tr, 1.0, atol=1e-12)


def test_telegrapher_clear_slab_is_exact():
    # No scattering: the collimated beam bounces between the faces (closed form).
    n, d = 1.55, 0.8
    r0 = specular(n, 1.0)
    model = get_model("telegrapher")
    for mua in (0.0, 0.3, 3.0):
        att = math.exp(-mua * d)
        t_exact = (1 - r0) ** 2 * att / (1 - r0**2 * att**2)
        r_exact = r0 + (1 - r0) ** 2 * r0 * att**2 / (1 - r0**2 * att**2)
        tt, tr = model.forward(mua, 1e-12, Sample(g=0.5, n=n, thickness=d))
        assert abs(tt - t_exact) < 1e-9 and abs(tr - r_exact) < 1e-9


def test_km_thick_slab_tends_to_r_infinity():
    # KM: R_inf = a - b with a = 1 + K/S; through Saunderson's faces (k1, k2).
    mua, mus, g, n = 0.2, 10.0, 0.5, 1.5
    k, s = 2 * mua, 0.75 * mus * (1 - g)
    a = 1 + k / s
    r_inf = a - math.sqrt(a * a - 1)
    k1 = specular(n, 1.0)
    k2 = moments(n, 1.0)[0]
    expect = k1 + (1 - k1) * (1 - k2) * r_inf / (1 - k2 * r_inf)
    tt, tr = get_model("km").forward(mua, mus, Sample(g=g, n=n, thickness=200.0))
    assert abs(tr - expect) < 1e-12 and tt < 1e-12


AD_CASES = [  # mua, mus, g, n, d
    (0.35, 28.0, 0.93, 1.54, 1.0),
    (0.3, 10.0, 0.75, 1.55, 0.5),
    (0.01, 6.0, 0.96, 1.63, 1.0),
    (0.05, 3.0, 0.75, 1.54, 0.5),
    (0.1, 20.0, 0.9, 1.0, 2.0),
]


def test_ad_reproduces_tooth_optics_anchors():
    # docs/explanation/tooth-optics.md section 7 (iadpython 0.5.3, 16/32 points): UR1, UT1
    ad = get_model("ad")
    tt, tr = ad.forward(0.01, 6.0, Sample(g=0.96, n=1.63, thickness=1.0))
    assert abs(tr - 0.2156) < 5e-4 and abs(tt - 0.7475) < 5e-4
    tt, tr = ad.forward(0.35, 28.0, Sample(g=0.93, n=1.54, thickness=1.0))
    assert abs(tr - 0.1931) < 5e-4 and abs(tt - 0.1553) < 5e-4


def test_telegrapher_error_against_ad_is_as_documented():
    # docs/inversion.md states |delta| <= 0.02 on TT and TR for these slabs (delta-P1).
    ad, tel = get_model("ad"), get_model("telegrapher")
    for mua, mus, g, n, d in AD_CASES:
        s = Sample(g=g, n=n, thickness=d)
        a = np.array(ad.forward(mua, mus, s))
        t = np.array(tel.forward(mua, mus, s), dtype=float)
        assert np.max(np.abs(a - t)) < 0.02, (mua, mus, g, n, d, a, t)


def test_mc_model_agrees_with_ad():
    # Same physics; tolerance: 4 standard errors of the run plus 5e-4 for AD's quadrature.
    mc = get_model("mc", photons=200_000, seed=11)
    ad = get_model("ad")
    for mua, mus, g, n, d in AD_CASES[1:4]:
        s = Sample(g=g, n=n, thickness=d)
        m = np.array(mc.forward(mua, mus, s))
        a = np.array(ad.forward(mua, mus, s))
        assert np.all(np.abs(m - a) < 4 * np.array(mc.last_stderr) + 5e-4), (m, a)


# ---------------------------------------------------------------- Table 1

def test_table1_540_mc_round_trip():
    tt, tr, n = ROWS[540]
    res = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="mc")
    assert isinstance(res, FitResult)
    assert res.residual <= 1e-3 + 1e-12
    assert res.mua > 0 and res.mua_resolved
    # Forward Monte Carlo with an independent seed at the solution: within 0.003 absolute.
    check = simulate([Layer(mua=res.mua, mus=res.mus, g=0.75, n=n, thickness=0.5)],
                     n_photons=1_000_000, seed=987, estimator="weighted")
    assert abs(check.total_transmittance - tt) < 0.003
    assert abs(check.total_reflectance - tr) < 0.003
    # The independent ad fit lies inside the mc interval.
    ad = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="ad")
    assert res.mua_ci[0] <= ad.mua <= res.mua_ci[1]
    assert res.mus_ci[0] <= ad.mus <= res.mus_ci[1]


def test_table1_analytic_models_and_ad():
    results = {m: fit_table(TABLE1, model=m) for m in ("telegrapher", "ad")}
    results["km (k2 = 0)"] = fit_table(TABLE1, model="km", km_k2=0.0)
    ad = get_model("ad")
    for name, rows in results.items():
        assert [r.wavelength_nm for r in rows] == [450.0, 540.0, 605.0]
        for r in rows:
            assert r.residual < 1e-4, name
            assert r.mua > 0 and r.mus > 0
            assert r.mua_ci[0] <= r.mua <= r.mua_ci[1]
        # absorption falls with wavelength, as TA does (20.9 %, 7.4 %, 2.1 %)
        assert rows[0].mua > rows[1].mua > rows[2].mua, name
    # ad at its own solution reproduces the data: an independent forward evaluation.
    for r in results["ad"]:
        tt, tr = ad.forward(r.mua, r.mus, Sample(g=0.75, n=r.n, thickness=0.5))
        assert abs(tt - r.tt) < 1e-4 and abs(tr - r.tr) < 1e-4
    # telegrapher within its documented model error of the ad solution's data.
    for r_ad, r_tel in zip(results["ad"], results["telegrapher"], strict=True):
        assert abs(r_tel.mus - r_ad.mus) < 0.05 * r_ad.mus
        assert abs(r_tel.mua - r_ad.mua) < 0.25 * r_ad.mua + 0.005


def test_km_with_fresnel_k2_reports_the_bound_it_cannot_reach():
    # KM's clear-slab limit: TR = k1 + (1 - k1) k2 / (1 + k2) > measured TR.
    tt, tr, n = ROWS[450]
    k1, k2 = specular(n, 1.0), moments(n, 1.0)[0]
    assert k1 + (1 - k1) * k2 / (1 + k2) > tr
    with pytest.raises(ValueError, match="cannot reproduce"):
        fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="km")


def test_table1_d65_row_fits():
    rows = (DATA / "table1_d65.csv").read_text().splitlines()
    head = [ln for ln in rows if not ln.startswith("#")]
    rec = dict(zip(head[0].split(","), head[1].split(","), strict=True))
    r = fit(tt=float(rec["tt"]), tr=float(rec["tr"]), n=float(rec["n"]), g=float(rec["g"]),
            thickness=float(rec["thickness_mm"]), model="telegrapher")
    assert r.residual < 1e-6 and r.mua_resolved


# ---------------------------------------------------------------- weak absorption, bounds

def test_weak_absorption_gives_an_upper_bound_not_zero():
    # ad at mua = 5e-4: absorptance ~1e-4, far below the 0.005 uncertainty.
    s = Sample(g=0.75, n=1.54, thickness=0.5)
    tt, tr = get_model("ad").forward(5e-4, 5.0, s)
    for model in ("ad", "telegrapher"):
        r = fit(tt=tt, tr=tr, n=1.54, g=0.75, thickness=0.5, model=model)
        assert r.mua > 0
        assert not r.mua_resolved and r.mua_ci[0] == 0.0
        assert 5e-4 <= r.mua_upper_bound == r.mua_ci[1] < 0.1
        assert any("not resolved" in note for note in r.notes)
    # and iadpython's own inverse, which the issue warns about, is not used: (our answer
    # is never exactly 0)


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        (dict(tt=0.7, tr=0.4), r"TT \+ TR <= 1"),
        (dict(tt=0.6, tr=0.03), r"TR >= R0"),
        (dict(tt=0.95, tr=0.05), r"unscattered limit"),
        (dict(tt=0.5, tr=0.3, thickness=-1), r"thickness"),
        (dict(tt=0.5, tr=0.3, g=1.0), r"^g = "),
        (dict(tt=0.5, tr=0.3, n=0.9), r"^n = "),
        (dict(tt=0.5, tr=0.3, fd=1.5), r"^fd = "),
        (dict(tt=-0.1, tr=0.3), r"^tt = "),
        (dict(tt=0.5, tr=0.3, model="diffusion"), r"model = 'diffusion'"),
        (dict(tt=0.5, tr=0.3, tt_err=0.0), r"tt_err"),
    ],
)
def test_bad_input_is_a_value_error_naming_the_bound(kwargs, pattern):
    args = dict(n=1.55, g=0.75, thickness=0.5, model="telegrapher")
    args.update(kwargs)
    with pytest.raises(ValueError, match=pattern):
        fit(**args)


def test_diffuse_only_tr_drops_the_specular_bound_and_agrees():
    tt, tr, n = ROWS[450]
    full = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="ad")
    diff = fit(tt=tt, tr=tr - specular(n, 1.0), n=n, g=0.75, thickness=0.5, model="ad",
               tr_diffuse_only=True)
    assert diff.mua == pytest.approx(full.mua, rel=1e-3)
    assert diff.mus == pytest.approx(full.mus, rel=1e-3)


def test_table_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        fit_table(tmp_path / "missing.csv", model="telegrapher")
    bad = tmp_path / "bad.csv"
    bad.write_text("# comment\nwavelength_nm,tt,tr,n,g\n500,0.5,0.3,1.5,0.7\n")
    with pytest.raises(ValueError, match="thickness_mm"):
        fit_table(bad, model="telegrapher")
    bad.write_text("wavelength_nm,tt,tr,n,g,thickness_mm\n500,abc,0.3,1.5,0.7,1\n")
    with pytest.raises(ValueError, match="tt = 'abc'"):
        fit_table(bad, model="telegrapher")
    bad.write_text("wavelength_nm,tt,tr,n,g,thickness_mm\n500,0.8,0.3,1.5,0.7,1\n")
    with pytest.raises(ValueError, match=r"row 1 \(wavelength_nm = 500.0\).*TT \+ TR"):
        fit_table(bad, model="telegrapher")


# ---------------------------------------------------------------- synthetic round trips

def _grid_round_trip(model: str, generator: str, cases, rng):
    """Data from ``generator`` + uniform noise within +-0.005 -> fit with ``model``."""
    gen = get_model(generator)
    covered = fitted = refused = 0
    misses = []
    for mua, mus, g, n, d in cases:
        tt, tr = gen.forward(mua, mus, Sample(g=g, n=n, thickness=d))
        e = rng.uniform(-0.005, 0.005, 2)
        try:
            r = fit(tt=float(tt) + e[0], tr=float(tr) + e[1], n=n, g=g, thickness=d,
                    model=model)
        except ValueError as exc:
            # only data pushed across a physical bound by the noise may be refused
            assert "bound crossed" in str(exc) or "out of range" in str(exc), str(exc)
            refused += 1
            continue
        fitted += 1
        ok = r.mua_ci[0] <= mua <= r.mua_ci[1] and r.mus_ci[0] <= mus <= r.mus_ci[1]
        covered += ok
        if not ok:
            misses.append((mua, mus, g, n, d, r.mua, r.mua_ci, r.mus, r.mus_ci))
    return covered, fitted, refused, misses


GRID = list(itertools.product([0.001, 0.03, 0.3, 2.0], [0.5, 5.0, 50.0], [0.0, 0.75, 0.96],
                              [1.0, 1.63], [0.2, 1.0, 3.0]))


def test_synthetic_grid_coverage_telegrapher(np_rng):
    covered, fitted, refused, misses = _grid_round_trip("telegrapher", "telegrapher", GRID,
                                                        np_rng)
    assert fitted >= 150 and refused + fitted == len(GRID)
    assert covered >= 0.95 * fitted, misses


def test_synthetic_noise_free_round_trip_is_exact():
    tel = get_model("telegrapher")
    for mua, mus, g, n, d in GRID[::7]:
        tt, tr = tel.forward(mua, mus, Sample(g=g, n=n, thickness=d))
        if tt < 1e-6:
            continue  # an opaque slab: TT carries no information on the scale
        r = fit(tt=float(tt), tr=float(tr), n=n, g=g, thickness=d, model="telegrapher")
        assert r.mua == pytest.approx(mua, rel=1e-3) and r.mus == pytest.approx(mus, rel=1e-3)


def test_synthetic_round_trip_mc_small(np_rng):
    # Independent data (adding-doubling) + noise, inverted with Monte Carlo.
    cases = [(0.03, 5.0, 0.75, 1.55, 0.5), (0.3, 2.0, 0.9, 1.0, 1.0), (0.001, 20.0, 0.0, 1.4, 0.3)]
    covered, fitted, refused, misses = _grid_round_trip("mc", "ad", cases, np_rng)
    assert fitted == 3 and covered == 3, misses


# ---------------------------------------------------------------- CLI and output files

def _run_cli(argv: list[str]) -> int:
    """Run ``dentalux`` in-process; its exit code (typer always exits)."""
    try:
        main(argv)
    except SystemExit as exc:
        return exc.code or 0
    return 0


def test_cli_json_has_exactly_the_contract_keys(capsys):
    code = _run_cli(["fit", "--tt", "0.4897", "--tr", "0.3016", "--n", "1.55", "--g", "0.75",
                     "--thickness", "0.5", "--json", "--photons", "100000"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == set(JSON_KEYS)
    assert out["model"] == "mc"
    assert len(out["mua_ci"]) == 2 and len(out["mus_ci"]) == 2
    assert out["musp"] == pytest.approx(out["mus"] * 0.25)
    assert out["albedo"] == pytest.approx(out["mus"] / (out["mua"] + out["mus"]))
    assert abs(out["fit_tt"] - 0.4897) <= 1e-3 + 1e-12 and out["residual"] <= 1e-3 + 1e-12


def test_cli_bad_input_exits_2(capsys):
    code = _run_cli(["fit", "--tt", "0.7", "--tr", "0.4", "--n", "1.55", "--g", "0.75",
                     "--thickness", "0.5", "--model", "telegrapher", "--json"])
    assert code == 2
    assert "TT + TR <= 1" in capsys.readouterr().err


def test_cli_table_writes_material_toml(tmp_path):
    out = tmp_path / "bio.toml"
    code = _run_cli(["fit", "--table", str(TABLE1), "--model", "telegrapher", "--out",
                     str(out), "--name", "biomaterial-table1", "--json"])
    assert code == 0
    doc = tomllib.loads(out.read_text())
    mat = doc["materials"]["biomaterial-table1"]
    assert mat["wavelength_nm"] == [450.0, 540.0, 605.0]
    assert len(mat["mua"]) == len(mat["mus"]) == len(mat["mua_ci"]) == 3
    assert mat["n"] == [1.55, 1.54, 1.537] and mat["g"] == [0.75] * 3
    assert mat["provenance"]["kind"] == "fitted"
    assert mat["provenance"]["model"] == "telegrapher"
    assert mat["provenance"]["source"] == "table1.csv"


def test_shipped_biomaterial_toml_matches_a_fresh_fit():
    doc = tomllib.loads((DATA / "biomaterial-table1.toml").read_text())
    mat = doc["materials"]["biomaterial-table1"]
    assert mat["provenance"]["model"] == "mc"
    ad = fit_table(TABLE1, model="ad")
    for i, r in enumerate(ad):
        lo, hi = mat["mua_ci"][i]
        assert lo <= r.mua <= hi
        lo, hi = mat["mus_ci"][i]
        assert lo <= r.mus <= hi


def test_data_below_the_clear_slab_line_is_refused_with_that_bound():
    # A thin, barely scattering disc: TR just below the non-scattering slab's TR at this TT.
    from dentalux.inverse.bounds import clear_slab_tr

    tt, n = 0.5692, 1.63
    tr = clear_slab_tr(tt, n, 1.0, False) - 0.0015
    with pytest.raises(ValueError, match=r"TR >= TR_clear\(TT\)"):
        fit(tt=tt, tr=tr, n=n, g=0.96, thickness=0.2, model="telegrapher")


def test_mc_without_iadpython_uses_the_telegrapher_as_stand_in(monkeypatch):
    # iadpython is optional at run time: mc then starts from and steers by the telegrapher.
    import sys

    fit_mod = sys.modules["dentalux.inverse.fit"]  # the module (the package exports the function)

    monkeypatch.setattr(fit_mod, "_stand_in", lambda sample, q: get_model("telegrapher"))
    tt, tr, n = ROWS[540]
    r = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model="mc", photons=200_000)
    assert r.converged and r.residual <= 1e-3 + 1e-12
    assert r.evaluations <= 8


def test_ad_refuses_surroundings_other_than_air_and_mc_still_fits():
    with pytest.raises(ValueError, match="n_outside = 1.33: model 'ad'"):
        fit(tt=0.5, tr=0.2, n=1.5, g=0.5, thickness=1.0, n_outside=1.33, model="ad")
    # mc in water, steered by the telegrapher; an independent Monte Carlo run checks it.
    r = fit(tt=0.5, tr=0.2, n=1.5, g=0.5, thickness=1.0, n_outside=1.33, model="mc",
            photons=200_000)
    chk = simulate([Layer(mua=r.mua, mus=r.mus, g=0.5, n=1.5, thickness=1.0)],
                   n_photons=400_000, seed=55, n_above=1.33, n_below=1.33, estimator="weighted")
    assert abs(chk.total_transmittance - 0.5) < 0.003
    assert abs(chk.total_reflectance - 0.2) < 0.003
