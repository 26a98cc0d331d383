"""The reading engine (dentalux.reading): one walk per band read over every backing.

Checked against something independent: separate slab walks per backing (the core's own
backing in the walk, independent seeds), a backing the engine never simulated, and the
spread of readings over seeds against the standard errors they claim.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_run import run_main
from dentalux import dental, instrument, reading
from dentalux.slab import simulate
from dentalux.spectra import resolve_bands

BANDS = [450.0, 550.0, 650.0]
STACK = [("enamel", 0.6), ("dentin", 0.9)]


def _engine(inst, rb_black, rb_white, photons, seed, bands=BANDS):
    wl = resolve_bands(bands)
    mats = [(dental._resolve_material(m), t) for m, t in STACK]
    return reading.measure(reading.stacks(mats, wl), wl, inst, np.full(len(wl), rb_black),
                           np.full(len(wl), rb_white), photons, seed, solver="monte-carlo")


@pytest.mark.parametrize("preset", ["contact-probe-3mm", "45-0"])
def test_one_walk_per_band_matches_a_walk_per_backing(preset):
    """Over black, over white and transmitted, band by band, against separate runs with the
    backing inside the walk (the method before the engine); a grey backing (0.5), never
    simulated by the engine, is the same polynomial evaluated elsewhere."""
    inst = instrument.get(preset)
    got = _engine(inst, 0.0, 0.9, 20_000, seed=3)
    grey = _engine(inst, 0.5, 0.5, 20_000, seed=3)  # same photons: only R_b differs
    mats = [(dental._resolve_material(m), t) for m, t in STACK]
    for k, stack in enumerate(reading.stacks(mats, np.asarray(BANDS))):
        common = dict(n_photons=20_000, estimator="weighted", seed=11, band=k,
                      incidence=inst.spec.incidence)
        for channel, rb, value, err in (("black", 0.0, got.values[0, k], got.stderr[0, k]),
                                        ("white", 0.9, got.values[1, k], got.stderr[1, k]),
                                        ("grey", 0.5, grey.values[1, k], grey.stderr[1, k])):
            res = simulate(stack, window=inst.window(rb), **common)
            ref, ref_err = inst.reading(res.window, res.window_stderr)
            z = (value - ref) / np.hypot(err, ref_err)
            assert abs(z) < 4, (preset, channel, BANDS[k], value, err, ref, ref_err)
        res = simulate(stack, window=inst.window(0.0), **common)
        ref = res.window["viewed_transmittance"] / inst.white_fraction()
        ref_err = res.window_stderr["viewed_transmittance"] / inst.white_fraction()
        z = (got.values[2, k] - ref) / np.hypot(got.stderr[2, k], ref_err)
        assert abs(z) < 4, (preset, "transmitted", BANDS[k])
    assert got.extra["truncated_max"] < 1e-6


def test_backings_share_their_photons():
    """Black and white come from the same walk: the replicates' correlation between the two
    readings of a band is strongly positive (independent runs would give about 0)."""
    got = _engine(instrument.get("contact-probe-3mm"), 0.0, 0.9, 20_000, seed=5)
    for k in range(len(BANDS)):
        r = np.corrcoef(got.replicates[:, 0, k], got.replicates[:, 1, k])[0, 1]
        assert r > 0.5, (BANDS[k], r)


def test_reported_stderr_is_honest_over_seeds():
    """Over 100 seeds, the spread of L*, a*, b* over white and of TP00 and CR matches the
    standard error the readings claim within 30 % (the spread's own s.e. is 7 %)."""
    keys = ("lab_white.L", "lab_white.a", "lab_white.b", "tp00", "cr")
    values, claimed = {k: [] for k in keys}, {k: [] for k in keys}
    for seed in range(1, 101):
        m = dental.read(STACK, bands=BANDS, instrument="contact-probe-3mm", photons=1_500,
                        seed=seed)
        for k in keys:
            v = m.lab_white["Lab".index(k[-1])] if k.startswith("lab") else getattr(m, k)
            values[k].append(v)
            claimed[k].append(m.stderr[k])
    for k in keys:
        ratio = np.std(values[k], ddof=1) / np.sqrt(np.mean(np.square(claimed[k])))
        assert 0.7 < ratio < 1.3, (k, ratio)


def test_precision_chooses_the_photons_and_reaches_it():
    m = dental.read(STACK, bands=BANDS, instrument="contact-probe-3mm", precision=1.0, seed=3)
    p = m.precision
    assert p["requested"] == 1.0 and p["photons_per_band"] >= dental.PILOT_PHOTONS
    assert m.photons == p["photons_per_band"] * len(BANDS)
    # the pilot's estimate carries its own noise (about 10 %) and a 1.2 margin
    assert p["achieved"] < 1.25 * p["requested"], p


@pytest.mark.parametrize("bad", ["0", "-0.1", "nan", "inf"])
def test_bad_precision_is_refused_naming_the_field(bad, capsys):
    code, _, err = run_main(capsys, "shade", "enamel", "--bands", "550", "--precision", bad,
                            "--json")
    assert code == 2
    assert "precision" in err and "allowed" in err


def test_a_precision_past_the_ceiling_is_refused_with_its_estimate(capsys):
    # through a probe whose rim walk carries the noise (the default, 45-0, has none)
    code, _, err = run_main(capsys, "shade", "enamel", "--bands", "550", "--precision", "1e-5",
                            "--instrument", "contact-probe-3mm", "--json")
    assert code == 2
    assert "would need about" in err and "photons" in err and "CPU-s" in err


def test_shade_json_carries_stderr_under_the_values_keys(capsys):
    code, out, _ = run_main(capsys, "shade", "enamel", "--bands", "450,550,650", "--photons",
                            "2000", "--instrument", "contact-probe-3mm", "--json")
    assert code in (0, None)
    d = json.loads(out)
    for key in ("lab_black", "lab_white", "lab_transmitted", "tp", "tp00", "cr", "op"):
        assert key in d["stderr"]
        assert np.shape(d["stderr"][key]) == np.shape(d[key])
        assert np.all(np.asarray(d["stderr"][key]) > 0)
    assert d["cpu_seconds"] > 0
    assert len(d["reflectance_white"]) == len(d["wavelength_nm"]) == 3


def test_verdict_spans_the_classes_its_error_bar_reaches():
    assert dental.verdict(0.79, 0.21) == "imperceptible or acceptable"
    assert dental.verdict(0.3, 0.1) == "imperceptible"
    assert dental.verdict(1.7, 0.5) == "imperceptible or acceptable or unacceptable"
    p = dental.verdict_probabilities(0.79, 0.21)
    assert abs(sum(p.values()) - 1) < 1e-12 and 0.4 < p["imperceptible"] < 0.6


def test_shared_walks_match_one_walk_per_band():
    """Every band from shared walks (a hero band per photon, balance heuristic over the
    bands' path densities) against one walk per band: band by band within 4 s.e., over a
    stack whose dentin phase function differs between bands."""
    inst = instrument.get("contact-probe-3mm")
    bands = [420.0, 480.0, 540.0, 600.0, 660.0]
    wl = resolve_bands(bands)
    mats = [(dental._resolve_material(m), t) for m, t in STACK]
    band_stacks = reading.stacks(mats, wl)
    assert len({layer.g for stack in band_stacks for layer in stack[1:]}) > 1
    rb = (np.zeros(len(wl)), np.full(len(wl), 0.9))
    shared = reading.measure(band_stacks, wl, inst, *rb, 8_000, seed=4, walks="shared")
    alone = reading.measure(band_stacks, wl, inst, *rb, 8_000, seed=5)
    z = (shared.values - alone.values) / np.hypot(shared.stderr, alone.stderr)
    assert np.all(np.abs(z) < 4), z
    assert shared.method == "shared-walks" and 0 < shared.extra["concentration"] < 1
    with pytest.raises(ValueError, match="walks"):
        reading.measure(band_stacks, wl, inst, *rb, 100, seed=1, walks="hero")


def test_shared_walks_read_the_same_on_one_and_two_threads():
    """The shared walks' batches are taken by whichever thread is free (crate::batches) and
    put back in order: the same seed reads the same bits on any number of threads."""
    inst = instrument.get("contact-probe-3mm")
    wl = resolve_bands([450.0, 550.0, 650.0])
    mats = [(dental._resolve_material(m), t) for m, t in STACK]
    band_stacks = reading.stacks(mats, wl)
    rb = (np.zeros(len(wl)), np.full(len(wl), 0.9))
    one, two = (reading.measure(band_stacks, wl, inst, *rb, 3_000, seed=8, walks="shared",
                                threads=n) for n in (1, 2))
    np.testing.assert_array_equal(one.values, two.values)
    np.testing.assert_array_equal(one.stderr, two.stderr)


def test_command_line_and_api_read_through_the_same_default(capsys):
    """`dentalux shade X` and `dental.metrics(X)` give the same numbers for the same seed:
    one default instrument for both."""
    code, out, _ = run_main(capsys, "shade", "enamel", "--bands", "450,550,650", "--photons",
                            "1500", "--json")
    assert code in (0, None)
    cli = json.loads(out)
    api = dental.metrics("enamel", 1.0, bands=BANDS, photons=1500).to_json()
    assert cli["instrument"]["name"] == instrument.DEFAULT == api["instrument"]["name"]
    for key in ("lab_black", "lab_white", "tp00", "cr", "stderr"):
        assert cli[key] == json.loads(json.dumps(api[key])), key


def test_typed_results_with_short_reprs():
    m = dental.read(STACK, bands=BANDS, photons=1000)
    assert isinstance(m.lab_white, dental.Lab) and m.lab_white.L == m.lab_white[0]
    err = m.error("lab_white")
    assert err.a == m.stderr["lab_white.a"] and m.measured("tp00").stderr == m.stderr["tp00"]
    assert len(repr(m)) < 300 and "±" in repr(m)
    assert json.loads(json.dumps(m.to_json()))["lab_white"] == list(m.lab_white)


def test_a_monte_carlo_part_of_one_batch_is_refused(capsys):
    # its standard error comes from the spread between batches: one batch has none (it read
    # 0); the walks need more than the core's smallest batch, the rim walk's budget more
    # than RIM_SHARE of its smallest batches
    from dentalux.reading import engine

    walks = int(engine._core.SLAB_MIN_BATCH)
    rim = engine.RIM_SHARE * int(engine._core.SLAB_MIN_RIM_BATCH)
    probe = ["shade", "enamel", "--instrument", "contact-probe-3mm", "--bands", "450,550,650",
             "--json"]
    for args, floor in (([*probe, "--solver", "monte-carlo"], walks), (probe, rim)):
        code, out, err = run_main(capsys, *args, "--photons", str(floor))
        assert code == 2 and out == "" and "standard error" in err and str(floor + 1) in err
        code, out, _ = run_main(capsys, *args, "--photons", str(floor + 1))
        assert code in (0, None) and json.loads(out)["photons"] == 3 * (floor + 1)
