"""Progressive rendering: single ppm passes as tasks, the pass-spread error estimate, stop rules
and the `dentalux render --passes/--time-budget/--target-rmse` CLI."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from dentalux import _core
from dentalux.cli import main
from dentalux.progressive import Accumulator, StopRule, render_progressive
from dentalux.render import build_settings, render
from dentalux.scene.load import as_scene

DISCS = Path(__file__).resolve().parents[1] / "scenes" / "discs.toml"
# a tiny disc render: 16x12 px, few photons (tens of ms per pass)
TINY = dict(integrator="ppm", spp=1, photons=2000, volume_photons=5000, resolution=(16, 12),
            seed=3)


def _band(passes, pass_index=None, integrator="ppm", **extra):
    sc = as_scene(DISCS)
    s = build_settings(sc, integrator=integrator, spp=1, photons=2000, volume_photons=5000,
                       threads=1, **extra)
    s = {**s, "band": 540, "passes": passes}
    if pass_index is not None:
        s["pass_index"] = pass_index
    return _core.render_band(sc.to_json(540.0, (16, 12)), json.dumps(s))


def test_single_ppm_passes_average_to_the_in_process_render():
    full, st = _band(5)
    acc = np.zeros(full.shape)
    radii = []
    for p in range(5):
        image, s = _band(1, pass_index=p)
        # the 2000 surface photons are the volume pass's first 2000 of its 5000
        assert s["pass_first"] == p + 1 and s["photons_emitted"] == 5000
        # a pass after the first traces pass 1's maps once more to find r_1
        assert ("pilot_photons" in s) == (p > 0)
        acc += image
        radii.append(s["surface_radius_last"])
    assert np.array_equal((acc / 5).astype(np.float32), full)
    assert radii[-1] == st["surface_radius_last"]
    # Knaus-Zwicker: r_i^2 / r_1^2 = prod_{j<i} (j + alpha) / (j + 1), alpha = 0.7
    for i, r in enumerate(radii, start=1):
        want = math.prod((j + 0.7) / (j + 1) for j in range(1, i))
        assert (r / radii[0]) ** 2 == pytest.approx(want, rel=1e-12)


def test_a_chunk_of_passes_is_the_mean_of_its_passes():
    a, _ = _band(1, pass_index=2)
    b, _ = _band(1, pass_index=3)
    both, _ = _band(2, pass_index=2)
    assert np.array_equal(((a.astype(np.float64) + b) / 2).astype(np.float32), both)


def test_pass_index_of_other_integrators_is_an_independent_seed():
    plain, _ = _band(1, integrator="volpath")
    zero, _ = _band(1, pass_index=0, integrator="volpath")
    one, _ = _band(1, pass_index=1, integrator="volpath")
    assert np.array_equal(plain, zero) and not np.array_equal(plain, one)


def test_pass_index_out_of_range_is_refused():
    with pytest.raises(ValueError, match="pass_index"):
        _band(1, pass_index=-1)
    with pytest.raises(ValueError, match="pass_index"):
        _band(2, pass_index=4094)


def test_error_estimate_matches_the_known_noise(np_rng):
    # N passes of mu + sigma * z per pixel: the relative error of the mean is
    # sqrt(mean(sigma^2) / N) / mean(mu); the estimate uses N - 1 = 49 dof x 2000 pixels, so
    # its relative standard error is about sqrt(1 / (2 * 98000)) = 0.23 %; allow 4 of them
    mu = np_rng.uniform(1.0, 3.0, (40, 50))
    sigma = np_rng.uniform(0.1, 1.0, mu.shape)
    acc = Accumulator.empty(mu.shape)
    n = 50
    for _ in range(n):
        acc.add((mu + sigma * np_rng.standard_normal(mu.shape)).astype(np.float32))
    want = math.sqrt(float((sigma**2).mean()) / n) / float(mu.mean())
    assert acc.relative_error() == pytest.approx(want, rel=4 * 0.0023 + 0.005)
    one = Accumulator.empty(mu.shape)
    one.add(mu)
    assert one.relative_error() == math.inf


def test_progressive_equals_render_and_target_error_stops():
    a = render(DISCS, passes=6, bands=[450, 605], progress=False, **TINY)
    b = render_progressive(DISCS, StopRule(passes=6), bands=[450, 605], progress=False, **TINY)
    assert np.array_equal(a.radiance, b.radiance)
    pr = b.stats["progressive"]
    assert pr["passes"] == 6 and pr["stop"] == "passes"
    assert set(pr["radius_last"]) == {"surface_radius_last", "radius_medium1_last"}
    assert pr["radius_last"]["surface_radius_last"] == a.stats["bands"][1]["surface_radius_last"]

    t = render_progressive(DISCS, StopRule(target_rmse=0.3), progress=False, bands=[540],
                           **TINY)
    pr = t.stats["progressive"]
    assert pr["stop"] == "target_rmse" and pr["error_estimate"] <= 0.3 and pr["passes"] >= 4
    # the error curve falls and the image is the fixed-pass render of that many passes
    errs = [c["error"] for c in pr["curve"] if math.isfinite(c["error"])]
    assert errs[-1] < errs[0]
    same = render(DISCS, passes=pr["passes"], bands=[540], progress=False, **TINY)
    assert np.array_equal(t.radiance, same.radiance)


def test_error_estimate_predicts_the_spread_between_independent_renders():
    # two 24-pass renders with different seeds differ by noise only (same schedule), so
    # rms(a - b) / sqrt(2) / mean is the noise the estimate claims; per-pixel outliers make the
    # image-level comparison loose: a factor 1.3 either way (measured 0.96-1.01)
    kw = {**TINY, "resolution": (24, 18)}
    a = render_progressive(DISCS, StopRule(passes=24), bands=[540], progress=False, **kw)
    kw["seed"] = 11
    b = render_progressive(DISCS, StopRule(passes=24), bands=[540], progress=False, **kw)
    x, y = a.radiance[..., 0].astype(np.float64), b.radiance[..., 0].astype(np.float64)
    seen = math.sqrt(float(((x - y) ** 2).mean()) / 2) / float((x + y).mean() / 2)
    est = (a.stats["progressive"]["error_estimate"] + b.stats["progressive"]["error_estimate"]) / 2
    assert 1 / 1.3 < est / seen < 1.3, (est, seen)


def test_time_budget_stops():
    r = render_progressive(DISCS, StopRule(time_budget=0.5), bands=[540], progress=False,
                           **TINY)
    pr = r.stats["progressive"]
    assert pr["stop"] == "time_budget" and pr["passes"] >= 1


def test_stop_rule_validation():
    for kw in ({}, {"passes": 0}, {"time_budget": -1.0}, {"target_rmse": 1.5},
               {"passes": 5000}):
        with pytest.raises(ValueError):
            StopRule(**kw)


def test_cli_progressive_writes_passes_error_and_last_radius(tmp_path, capsys):
    out = tmp_path / "o"
    with pytest.raises(SystemExit) as exc:
        main(["render", str(DISCS), "--out", str(out), "--integrator", "ppm", "--passes", "3",
              "--resolution", "16x12", "--spp", "1", "--photons", "2000", "--volume-photons",
              "5000", "--bands", "540", "--json"])
    assert exc.value.code == 0
    rj = json.loads((out / "render.json").read_text())
    assert rj["progressive"]["passes"] == 3 and rj["settings"]["passes"] == 3
    assert rj["radius_last"]["surface_radius_last"] > 0
    assert rj["progressive"]["error_estimate"] > 0
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        main(["render", str(DISCS), "--out", str(tmp_path / "p"), "--target-rmse", "2"])
    assert exc.value.code == 2 and "target_rmse" in capsys.readouterr().err


def test_progress_bar_runs_for_every_stop_rule():
    for stop in (StopRule(passes=2), StopRule(time_budget=0.3), StopRule(target_rmse=0.6)):
        r = render_progressive(DISCS, stop, bands=[540], progress=True, **TINY)
        assert r.stats["progressive"]["stop"] in ("passes", "time_budget", "target_rmse")
