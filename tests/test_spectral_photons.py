"""The spectral photon pass from the command line and the Python API: `--spectral-photons`
reaches the core and render.json, the photons are traced once (the progress count says so),
and it is refused where it cannot apply (integrators without a one-pass volume photon map,
progressive and distributed renders, which run a task per band). The physics (closed-form
ledgers per band, agreement with band-by-band passes, the shared noise) is the core's test:
crates/dentalux-core/tests/spectral_photons.rs."""

import json

import dentalux
import numpy as np
import pytest
from cli_run import SCENES, cli
from dentalux import limits
from dentalux.scene.builtin import discs

FAST = ["--resolution", "24x18", "--spp", "1", "--bands", "450,540,605", "--photons", "2000",
        "--volume-photons", "20000"]


def test_cli_spectral_render_records_it(tmp_path):
    out = tmp_path / "s"
    r = cli("render", str(SCENES / "discs.toml"), "--out", str(out), "--spectral-photons",
            "--seed", "3", *FAST, "--json")
    assert r.returncode == 0, r.stderr
    summary = json.loads((out / "render.json").read_text())
    assert summary["settings"]["spectral_photons"] is True
    # the Table 1 biomaterial's index varies with wavelength: the user is told what that costs
    assert any("media.disc's refractive index differs" in w for w in summary["warnings"])
    assert all(b["spectral_photons"] == 1.0 for b in summary["stats"])
    # one photon pass: every band's maps hold the same photons
    assert len({b["volume_photons"] for b in summary["stats"]}) == 1
    img = np.load(out / "radiance.npy")
    assert img.shape == (18, 24, 3) and np.isfinite(img).all() and (img.mean(axis=(0, 1)) > 0).all()


def test_no_warning_where_the_indices_agree():
    d = discs(resolution=(8, 6))
    d["media"]["disc"] = {"material": "enamel"}  # n 1.633 at every band
    res = dentalux.render(d, integrator="vpm", spp=1, photons=500, volume_photons=2000,
                          bands=[450, 540, 605], spectral_photons=True, progress=False)
    assert res.stats["warnings"] == []
    # the bands share one photon pass: the totals count it once
    assert res.stats["photons_emitted_total"] == res.stats["bands"][0]["photons_emitted"] == 2000
    plain = dentalux.render(discs(resolution=(8, 6)), integrator="vpm", spp=1, photons=500,
                            volume_photons=2000, bands=[450, 540, 605], progress=False)
    assert plain.stats["warnings"] == []


def test_api_progress_counts_photons_once(monkeypatch):
    """The bar's total is what the core counts for a spectral pass: the photons once and
    every band's pixels (crates/dentalux-core/tests/spectral_photons.rs checks the core's
    side). A core that reports exactly that fills the bar, not a third of it."""
    from dentalux import _core
    from dentalux.render import photons_traced

    counted = {}

    def core(scene_json, settings_json, keys, progress=None):
        settings = json.loads(settings_json)
        n = len(keys)
        camera = json.loads(scene_json)["camera"]
        w, h = camera["width"], camera["height"]
        counted["done"] = photons_traced(settings) + n * w * h
        progress(counted["done"])
        return np.ones((n, h, w), np.float32), [{"seconds_total": 0.0}] * n

    monkeypatch.setattr(_core, "render_bands", core)
    seen = []
    res = dentalux.render(discs(resolution=(16, 12)), integrator="vpm", spp=1, photons=1000,
                          volume_photons=5000, bands=[450, 540, 605], spectral_photons=True,
                          progress=lambda done, total: seen.append((done, total)))
    assert res.radiance.shape == (12, 16, 3)
    # the core's own report (before the bar's closing update) already fills the bar
    done, total = seen[-2]
    assert done == total, seen


@pytest.mark.parametrize("args,message", [
    (["--integrator", "pm"], "settings.spectral_photons = true applies to vpm, vpm-full, bre"),
    (["--passes", "2"], "spectral_photons = true: a progressive or distributed render"),
])
def test_refusals_name_the_setting(tmp_path, args, message):
    r = cli("render", str(SCENES / "discs.toml"), "--out", str(tmp_path / "o"),
            "--spectral-photons", *FAST, *args)
    assert r.returncode == 2, r.stderr
    assert message in r.stderr and "Traceback" not in r.stderr


def test_memory_counts_every_band_maps():
    s = {"integrator": "vpm", "photons": 1_000_000, "volume_photons": 10_000_000,
         "spectral_photons": False}
    one = limits.render_memory_bytes(64, 48, 3, s)
    three = limits.render_memory_bytes(64, 48, 3, dict(s, spectral_photons=True))
    maps = 11_000_000 * limits.PHOTON_BYTES * 1.05
    assert three - one == pytest.approx(maps * (3 + 3 * 4 / limits.PHOTON_BYTES), rel=1e-9)
    # a spectral pass holds every band's copy of the textures; band by band holds one
    on = dict(s, spectral_photons=True)
    textured = limits.render_memory_bytes(64, 48, 3, on, texels=1000)
    assert textured - three == pytest.approx(1000 * limits.TEXEL_BYTES * 3, rel=1e-9)
    assert limits.render_memory_bytes(64, 48, 3, s, texels=1000) == one
