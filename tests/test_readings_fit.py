"""dentalux fit --readings: readings files, their bad input, the Kubelka-Munk baseline, and
the round trip shade --readings-out -> fit -> predict another thickness (issue 41)."""

import json
import math

import numpy as np
import pytest
from cli_run import run_main
from dentalux import dental, instrument, readings
from dentalux.color import delta_e00
from dentalux.inverse import readings_fit as rf
from dentalux.reading.layered.stack import ACCURACY
from dentalux.testing import STAND_IN_COMPOSITE

INST = "contact-probe-3mm"
BANDS = [450.0, 500.0, 550.0, 600.0, 650.0]
# a material unknown to the fit (constant g, as the fit assumes): a composite-like spectrum
MATERIAL = STAND_IN_COMPOSITE


run = run_main  # the command line in process: (exit code, stdout, stderr)


GOOD = ("thickness_mm,backing,L,a,b\n0.5,black,40,-1,2\n0.5,white,70,1,8\n"
        "1.0,black,45,-1,4\n1.0,white,60,0,8\n")


@pytest.mark.parametrize("text,needle", [
    ("", "empty"),
    ("thickness_mm,backing,L,a,b\n", "empty"),
    ("thickness_mm,L,a,b\n0.5,40,0,0\n", "missing column(s) backing"),
    ("thickness_mm,backing,L,a\n0.5,black,40,0\n", "missing column(s) b"),
    ("thickness_mm,backing,L,a,b\n0,black,40,0,0\n", "line 2: thickness_mm"),
    ("thickness_mm,backing,L,a,b\n-1,black,40,0,0\n", "line 2: thickness_mm"),
    ("thickness_mm,backing,L,a,b\n0.5,black,nan,0,0\n", "line 2: L"),
    ("thickness_mm,backing,L,a,b\n0.5,black,140,0,0\n", "line 2: L = 140"),
    ("thickness_mm,backing,r500\n0.5,black,1.2\n", "line 2: r500 = 1.2"),
    ("thickness_mm,backing,r500\n0.5,1.5,0.2\n", "line 2: backing"),
    ("thickness_mm,backing,r505\n0.5,black,0.2\n", "'r505' is off the 10 nm grid"),
    ("thickness_mm,backing,r500,r510\n0.5,black,0.3,0.3\n0.5,white,0.4,0.2\n",
     "line 3: column r510 = 0.2 over white is darker"),
    ("thickness_mm,backing,L,a,b\n0.5,black,50,0,0\n0.5,white,40,0,0\n",
     "line 3: column L = 40 over white is darker"),
    ("thickness_mm,backing,L,a,b,foo\n0.5,black,50,0,0,1\n", "unknown column 'foo'"),
    ("thickness_mm,backing,r500,L\n0.5,black,0.3,140\n", "missing column(s) a, b"),
    ("thickness_mm,backing,L,a,b,illuminant\n0.5,black,40,0,0,D99\n",
     "r.csv: illuminant = 'D99': allowed"),
    ("thickness_mm,backing,L,a,b,observer\n0.5,black,40,0,0,7\n", "r.csv: observer = '7'"),
    ("thickness_mm,backing,L,a,b,L\n0.5,black,40,0,0,90\n", "line 1: column 'L' appears twice"),
    ("thickness_mm,backing,L,a,b,sd_L\n0.5,black,50,0,0,1\n", "column sd_L without sd_a, sd_b"),
    ("thickness_mm,backing,r500,r510,sd_r510\n0.5,black,0.3,0.3,0.01\n",
     "column sd_r510 without sd_r500: give the spread of every column"),
])
def test_bad_readings_exit_2_and_write_nothing(tmp_path, capsys, text, needle):
    f = tmp_path / "r.csv"
    f.write_text(text)
    out = tmp_path / "m.toml"
    code, stdout, err = run(capsys, "fit", "--readings", f, "--instrument", INST, "--model",
                            "km", "--out", out, "--json")
    assert code == 2, err
    assert needle in err, err
    assert not out.exists() and stdout == ""


def test_km_recovers_its_own_readings_and_reports_identifiability(tmp_path, capsys):
    """Readings made by the Kubelka-Munk forward model are fitted back to their
    coefficients; the JSON contract holds; one reading is not identifiable."""
    mua, mus = np.array([0.3, 0.1, 0.05]), np.array([12.0, 10.0, 9.0])
    wl = [450, 550, 650]
    rows = []
    inst = instrument.get(INST)
    sce = inst.spec.specular == "excluded"
    for t in (0.5, 1.0):
        for b in ("black", "white"):
            rb = getattr(inst, f"backing_{b}")
            r = rf.km_reflectance(mua, mus, 0.8, 1.5, t, rb, sce)
            rows.append(f"{t},{b}," + ",".join(f"{x:.8f}" for x in r))
    f = tmp_path / "km.csv"
    f.write_text("thickness_mm,backing," + ",".join(f"r{w}" for w in wl) + "\n"
                 + "\n".join(rows) + "\n")
    out = tmp_path / "km.toml"
    code, stdout, err = run(capsys, "fit", "--readings", f, "--instrument", INST, "--g", 0.8,
                            "--n", 1.5, "--model", "km", "--out", out, "--json")
    assert code == 0, err
    doc = json.loads(stdout)
    assert set(doc) == {"material", "file", "residuals", "identifiable", "model"}
    assert doc["model"] == "km" and doc["identifiable"] is True and doc["material"] == "km"
    assert [set(r) for r in doc["residuals"]] == [{"thickness_mm", "backing", "delta_e00"}] * 4
    assert max(r["delta_e00"] for r in doc["residuals"]) < 1e-3
    from dentalux import materials

    m = materials.load(out)["km"]
    assert np.allclose(m.mua, mua, rtol=1e-3) and np.allclose(m.mus, mus, rtol=1e-3)
    assert m.provenance["kind"] == "fitted" and m.provenance["instrument"] == INST
    assert len(m.provenance["readings_sha256"]) == 64
    assert m.provenance["values"]["g"].startswith("assumed")
    # one thickness over one backing cannot pin both coefficients
    f.write_text("thickness_mm,backing," + ",".join(f"r{w}" for w in wl) + "\n" + rows[0] + "\n")
    code, stdout, err = run(capsys, "fit", "--readings", f, "--instrument", INST, "--model",
                            "km", "--out", out, "--json")
    assert code == 0, err
    assert json.loads(stdout)["identifiable"] is False
    assert "cannot pin both" in err


@pytest.mark.parametrize("diffuse_only", [False, True])
def test_km_reflectance_is_the_km_model_of_a_disc_in_air(diffuse_only):
    """The readings' Kubelka-Munk over a backing of reflectance k2 (the disc's bottom face
    seen from inside) is the transport fit's Kubelka-Munk of the disc in air: the entering
    light loses k1 at the face whether or not the instrument sees the specular (SCE, 45/0
    and contact probes: the old form dropped 1 - k1 there and read 4 % too bright)."""
    from dentalux.inverse.models import Sample
    from dentalux.inverse.models.boundary import moments
    from dentalux.inverse.models.km import KubelkaMunk

    mua, mus, t = np.array([0.02, 0.1, 0.5]), np.array([3.0, 10.0, 20.0]), 0.7
    _, tr = KubelkaMunk().forward(mua, mus, Sample(g=0.8, n=1.5, thickness=t,
                                                   diffuse_only=diffuse_only))
    r = rf.km_reflectance(mua, mus, 0.8, 1.5, t, moments(1.5, 1.0)[0], diffuse_only)
    assert np.allclose(r, tr, rtol=1e-12, atol=0), (r, tr)


def _layered(mat, thickness, bands=BANDS, seed=12):
    return dental.read([(mat, thickness)], instrument=INST, photons=20_000, seed=seed,
                       bands=bands, solver="layered")


def _tolerance(pred, truth, prob):
    """Worst ΔE00 over black and white of ``pred`` against ``truth`` (both layered readings),
    and what it may be: 4 standard errors (the rim corrections') plus the ΔE00 of the
    solver's stated accuracy (the fit weighs its residuals by it)."""
    de = max(float(delta_e00(getattr(pred, f"lab_{b}"), getattr(truth, f"lab_{b}")))
             for b in ("black", "white"))
    se = math.hypot(dental.reading_precision(pred), dental.reading_precision(truth))
    acc = max(float(delta_e00(prob.lab(s), prob.lab(s * (1 + ACCURACY)))) for s in (
        np.asarray(truth.spectra[f"over_{b}"]) for b in ("black", "white")))
    return de, 4 * se + acc


def test_round_trip_shade_readings_fit_predicts_another_thickness(tmp_path, capsys):
    """shade --solver layered --readings-out at 0.5 and 1.0 mm -> fit (mc, layered) -> the
    reading at 1.5 mm within 4 standard errors plus the solver's accuracy; Kubelka-Munk's
    error on the same readings is printed beside it (it ignores edge loss)."""
    mat = tmp_path / "comp.toml"
    mat.write_text(MATERIAL)
    csv = tmp_path / "r.csv"
    for t in (0.5, 1.0):
        code, _, err = run(capsys, "shade", mat, "--thickness", t, "--instrument", INST,
                           "--bands", ",".join(f"{b:g}" for b in BANDS), "--photons", 20_000,
                           "--seed", 5, "--solver", "layered", "--readings-out", csv, "--json")
        assert code == 0, err
    data = readings.load(csv)
    assert data.form == "spectral" and len(data.rows) == 4
    out = tmp_path / "fit.toml"
    code, stdout, err = run(capsys, "fit", "--readings", csv, "--instrument", INST, "--g", 0.8,
                            "--n", 1.5, "--out", out, "--json")
    assert code == 0, err
    doc = json.loads(stdout)
    assert doc["model"] == "mc" and doc["identifiable"] is True
    from dentalux import materials

    fitted = materials.load(out)["fit"]
    assert fitted.provenance["solver"] == "layered"
    # the written TOML loads wherever a material is accepted
    code, stdout, err = run(capsys, "shade", "--layer", f"{out}:1.5", "--instrument", INST,
                            "--bands", "450,550,650", "--photons", 2000, "--json")
    assert code == 0, err
    code, _, err = run(capsys, "fit", "--readings", csv, "--instrument", INST, "--g", 0.8,
                       "--n", 1.5, "--model", "km", "--out", tmp_path / "km.toml", "--json")
    assert code == 0, err
    truth = _layered(str(mat), 1.5, seed=11)
    inst = instrument.get(INST)
    prob = rf.Problem(data, inst, 0.8, 1.5, "km", 0, 1, BANDS)
    de, tol = _tolerance(_layered(fitted, 1.5), truth, prob)
    km = materials.load(tmp_path / "km.toml")["km"]
    de_km = max(float(delta_e00(getattr(_layered(km, 1.5), f"lab_{b}"),
                                getattr(truth, f"lab_{b}"))) for b in ("black", "white"))
    # Kubelka-Munk's own prediction (no instrument): its model at 1.5 mm
    own = max(float(delta_e00(prob.lab(rf.km_reflectance(
        km.mua, km.mus, 0.8, 1.5, 1.5, prob.rg(b), prob.diffuse_only)), getattr(truth, f"lab_{b}")))
        for b in ("black", "white"))
    print(f"1.5 mm: mc fit {de:.3f} ΔE00 (allowed {tol:.3f}); KM fit: its own model "
          f"{own:.2f}, its coefficients read through the instrument {de_km:.2f} ΔE00")
    assert de < tol, (de, tol)


def test_round_trip_cielab_only(tmp_path, capsys):
    """CIELAB-only readings (L,a,b over black and white at 0.5 and 1.0 mm, layered) -> fit
    through the smooth spectrum -> the reading at 1.5 mm within 4 standard errors plus the
    solver's accuracy plus the fit's largest residual (the smooth spectrum is not the
    material's: what it misses at 0.5 and 1.0 mm it misses at 1.5 mm)."""
    mat = tmp_path / "comp.toml"
    mat.write_text(MATERIAL)
    bands = list(rf.LAB_BANDS)
    rows = ["thickness_mm,backing,L,a,b,sd_L,sd_a,sd_b"]
    for t in (0.5, 1.0):
        m = _layered(str(mat), t, bands, seed=5)
        for b in ("black", "white"):
            lab = getattr(m, f"lab_{b}")
            se = [m.stderr[f"lab_{b}.{c}"] for c in "Lab"]
            rows.append(f"{t},{b}," + ",".join(f"{x:.4f}" for x in (*lab, *se)))
    csv = tmp_path / "lab.csv"
    csv.write_text("\n".join(rows) + "\n")
    out = tmp_path / "lab.toml"
    code, stdout, err = run(capsys, "fit", "--readings", csv, "--instrument", INST, "--g", 0.8,
                            "--n", 1.5, "--out", out, "--json")
    assert code == 0, err
    doc = json.loads(stdout)
    assert doc["model"] == "mc"
    misfit = max(r["delta_e00"] for r in doc["residuals"])
    from dentalux import materials

    fitted = materials.load(out)["lab"]
    assert "log_mua_550" in fitted.provenance["notes"]  # which parameters the readings pin
    prob = rf.Problem(readings.load(csv), instrument.get(INST), 0.8, 1.5, "km", 0, 1, bands)
    de, tol = _tolerance(_layered(fitted, 1.5, bands), _layered(str(mat), 1.5, bands, 11), prob)
    print(f"CIELAB-only, 1.5 mm: mc fit {de:.3f} ΔE00 (allowed {tol:.3f} + fit residual "
          f"{misfit:.3f})")
    assert de < tol + misfit, (de, tol, misfit)


def test_monte_carlo_solver_and_its_refusals(tmp_path, capsys):
    """--solver monte-carlo keeps the Monte Carlo fit (its noise reported); auto picks the
    solver by the beam; --solver without --readings, and an unknown solver, are refused."""
    f = tmp_path / "r.csv"
    f.write_text(_km_rows([0.3, 0.1, 0.05], [12.0, 10.0, 9.0],
                          [(0.5, "black"), (0.5, "white")]))
    data = readings.load(f)
    res = rf.fit(data, INST, g=0.8, n=1.5, photons=2000, solver="monte-carlo")
    assert res.solver == "monte-carlo" and res.mc_stderr_de00 > 0
    assert all(math.isfinite(r["delta_e00"]) for r in res.residuals)
    # smoothing couples the bands of the table fit too: the whole fit is kept or not
    smooth = rf.fit(data, INST, g=0.8, n=1.5, photons=2000, solver="monte-carlo", smooth=1e4)
    assert smooth.smooth == 1e4 and all(math.isfinite(r["delta_e00"]) for r in smooth.residuals)
    assert np.all(smooth.mua_ci[:, 0] <= smooth.mua) and np.all(smooth.mua <= smooth.mua_ci[:, 1])
    # auto: the layered solver for a normal beam (the laterally infinite disc too) and for
    # d/8's 8 deg beam (engine.MAX_TILT_DEG)
    assert rf.fit(data, "infinite", g=0.8, n=1.5, photons=2000).solver == "layered"
    assert rf.fit(data, "d8-benchtop-sav", g=0.8, n=1.5, photons=2000).solver == "layered"
    out = tmp_path / "m.toml"
    code, stdout, err = run(capsys, "fit", "--tt", 0.5, "--tr", 0.3, "--n", 1.5, "--g", 0.8,
                            "--thickness", 1.0, "--solver", "auto")
    assert code == 2 and "--solver goes with --readings" in err, err
    code, stdout, err = run(capsys, "fit", "--readings", f, "--instrument", INST, "--solver",
                            "fast", "--out", out)
    assert code == 2 and "--solver = 'fast'" in err, err


def _km_rows(mua, mus, conditions, wl=(450, 550, 650)):
    inst = instrument.get(INST)
    rows = []
    for t, b in conditions:
        r = rf.km_reflectance(np.asarray(mua), np.asarray(mus), 0.8, 1.5, t,
                              getattr(inst, f"backing_{b}"), inst.spec.specular == "excluded")
        rows.append(f"{t},{b}," + ",".join(f"{x:.8f}" for x in r))
    return "thickness_mm,backing," + ",".join(f"r{w}" for w in wl) + "\n" + "\n".join(rows) + "\n"


def test_backings_that_barely_differ_through_a_thick_disc_are_not_identifiable(tmp_path,
                                                                             capsys):
    f = tmp_path / "thick.csv"
    f.write_text(_km_rows([0.5, 0.4, 0.3], [60.0, 50.0, 40.0], [(6.0, "black"), (6.0, "white")]))
    code, stdout, err = run(capsys, "fit", "--readings", f, "--instrument", INST, "--g", 0.8,
                            "--n", 1.5, "--model", "km", "--out", tmp_path / "m.toml", "--json")
    assert code == 0, err
    assert json.loads(stdout)["identifiable"] is False
    assert "barely constrain" in err


def test_readings_no_coefficients_reproduce_get_a_fit_and_a_warning(tmp_path, capsys):
    """Over black brighter at 1 mm than at 0.5 mm, over white darker: no μa, μs >= 0 gives
    both; the fit is written with finite residuals and a warning, never NaN."""
    f = tmp_path / "odd.csv"
    f.write_text("thickness_mm,backing,r450,r550,r650\n0.5,black,0.05,0.05,0.05\n"
                 "0.5,white,0.80,0.80,0.80\n1.0,black,0.60,0.60,0.60\n"
                 "1.0,white,0.62,0.62,0.62\n")
    out = tmp_path / "m.toml"
    code, stdout, err = run(capsys, "fit", "--readings", f, "--instrument", INST, "--model",
                            "km", "--out", out, "--json")
    assert code == 0, err
    doc = json.loads(stdout)
    assert all(math.isfinite(r["delta_e00"]) for r in doc["residuals"])
    assert max(r["delta_e00"] for r in doc["residuals"]) > 2.0
    assert "no μa, μs >= 0" in err and out.is_file()


def test_smooth_penalises_second_differences_across_bands(tmp_path, capsys):
    """Noisy Kubelka-Munk readings of a smooth material at 11 bands: --smooth makes the fitted
    log μa and log μs less rough (second differences) without leaving the readings (the
    misfit stays of the order of the noise), and it is refused for CIELAB-only readings."""
    wl = list(range(450, 560, 10))
    x = (np.asarray(wl) - 500.0) / 100.0
    mua, mus = 0.1 * np.exp(-1.5 * x), 10.0 * np.exp(-0.3 * x)
    rng = np.random.default_rng(4)
    noise = 0.003  # readings.DEFAULT_SD["spectral"]: the spread the fit assumes
    text = _km_rows(mua, mus, [(0.5, "black"), (0.5, "white"), (1.0, "black"),
                               (1.0, "white")], wl)
    lines = text.splitlines()
    noisy = [lines[0]] + [",".join(c if i < 2 else f"{float(c) + rng.normal(0, noise):.6f}"
                                   for i, c in enumerate(ln.split(","))) for ln in lines[1:]]
    f = tmp_path / "noisy.csv"
    f.write_text("\n".join(noisy) + "\n")
    data = readings.load(f)

    def rough(res):
        return float(np.sqrt(np.mean(np.diff(np.log(res.mua), 2) ** 2)
                             + np.mean(np.diff(np.log(res.mus), 2) ** 2)))

    plain = rf.fit(data, INST, g=0.8, n=1.5, model="km")
    smooth = rf.fit(data, INST, g=0.8, n=1.5, model="km", smooth=1e4)
    chi2 = np.mean([r["delta_e00"] for r in smooth.residuals])
    print(f"roughness {rough(plain):.3f} -> {rough(smooth):.3f}; mean residual {chi2:.2f} ΔE00")
    assert rough(smooth) < 0.5 * rough(plain)
    # still on the readings: each residual within 3 times what the readings' noise makes
    spread = _noise_de(data, noise)
    assert max(r["delta_e00"] for r in smooth.residuals) < 3 * spread
    lab = tmp_path / "lab.csv"
    lab.write_text(GOOD)
    code, _, err = run(capsys, "fit", "--readings", lab, "--instrument", INST, "--model", "km",
                       "--smooth", 1, "--out", tmp_path / "m.toml")
    assert code == 2 and "CIELAB only" in err, err
    code, _, err = run(capsys, "fit", "--readings", f, "--instrument", INST, "--model", "km",
                       "--smooth", -1, "--out", tmp_path / "m.toml")
    assert code == 2 and "--smooth = -1" in err, err


def _noise_de(data, sd):
    """The ΔE00 spread of a reading from independent noise ``sd`` in each band."""
    prob = rf.Problem(data, instrument.get(INST), 0.8, 1.5, "km", 0, 1, data.wavelength_nm)
    return max(float(rf.delta_e00_scale(prob.lab(r.spectrum), rf._lab_spread(
        prob, r.spectrum, np.full(len(r.spectrum), sd)))) for r in data.rows)


def test_intervals_widen_with_a_misfit_beyond_the_assumed_spread(tmp_path):
    """Kubelka-Munk readings with noise 0.01 per band and no sd columns (the fit assumes
    0.003): the coefficients' standard deviations are widened by the residuals' chi-square per
    degree of freedom, so the fit's error from the truth is about one of them (the median
    |z| of a normal deviate is 0.67; the unscaled intervals, three times too narrow, gave 2.0
    on these readings)."""
    wl = list(range(400, 710, 10))
    x = (np.asarray(wl) - 550.0) / 100.0
    mua, mus = 0.1 * np.exp(-0.8 * x), 10.0 * np.exp(-0.3 * x)
    rng = np.random.default_rng(7)
    lines = _km_rows(mua, mus, [(t, b) for t in (0.3, 0.6, 1.0) for b in ("black", "white")],
                     wl).splitlines()
    noisy = [lines[0]] + [",".join(c if i < 2 else f"{float(c) + rng.normal(0, 0.01):.6f}"
                                   for i, c in enumerate(ln.split(","))) for ln in lines[1:]]
    f = tmp_path / "noisy.csv"
    f.write_text("\n".join(noisy) + "\n")
    res = rf.fit(readings.load(f), INST, g=0.8, n=1.5, model="km")
    z = np.concatenate([np.log(fit / true) / (np.log(ci[:, 1] / fit) / 1.96)
                        for fit, ci, true in ((res.mua, res.mua_ci, mua),
                                              (res.mus, res.mus_ci, mus))])
    print(f"median |z| {np.median(np.abs(z)):.2f} over {z.size} coefficients")
    assert 0.4 < np.median(np.abs(z)) < 1.2
