"""Hero-wavelength camera paths from the command line and the Python API: `--hero-camera`
reaches the core and render.json, the image does not depend on the thread count, the memory
check counts every band's maps, and it is refused where it cannot apply. The physics (one
band bit for bit `vpm`'s pass, every band's mean equal to its own camera pass's over the same
maps, with and without dispersion) is the core's test: crates/dentalux-core/tests/hero_camera.rs."""

import json

import dentalux
import numpy as np
import pytest
from cli_run import SCENES, cli
from dentalux import limits
from dentalux.scene.builtin import discs

FAST = ["--resolution", "24x18", "--spp", "1", "--bands", "450,540,605", "--photons", "2000",
        "--volume-photons", "20000"]


def test_cli_hero_render_records_it(tmp_path):
    out = tmp_path / "h"
    r = cli("render", str(SCENES / "discs.toml"), "--out", str(out), "--hero-camera",
            "--seed", "3", *FAST, "--json")
    assert r.returncode == 0, r.stderr
    summary = json.loads((out / "render.json").read_text())
    assert summary["settings"]["hero_camera"] is True
    assert all(b["hero_camera"] == 1.0 for b in summary["stats"])
    img = np.load(out / "radiance.npy")
    assert img.shape == (18, 24, 3) and np.isfinite(img).all() and (img.mean(axis=(0, 1)) > 0).all()


def test_same_image_at_any_thread_count():
    kw = dict(integrator="vpm", spp=2, photons=1000, volume_photons=8000, seed=4,
              bands=[450, 540, 605], hero_camera=True, correlated_bands=True, progress=False)
    one = dentalux.render(discs(resolution=(20, 16)), threads=1, **kw)
    two = dentalux.render(discs(resolution=(20, 16)), threads=2, **kw)
    assert np.array_equal(one.radiance, two.radiance)
    # the photon maps are the band-by-band render's: the same photons stored per band
    plain = dentalux.render(discs(resolution=(20, 16)), threads=2,
                            **{**kw, "hero_camera": False})
    assert [b["photons_stored"] for b in one.stats["bands"]] == \
        [b["photons_stored"] for b in plain.stats["bands"]]


@pytest.mark.parametrize("args,message", [
    (["--integrator", "pm"], "settings.hero_camera = true applies to vpm, vpm-full, bre"),
    (["--passes", "2"], "hero_camera = true: a progressive or distributed render"),
])
def test_refusals_name_the_setting(tmp_path, args, message):
    r = cli("render", str(SCENES / "discs.toml"), "--out", str(tmp_path / "o"),
            "--hero-camera", *FAST, *args)
    assert r.returncode == 2, r.stderr
    assert message in r.stderr and "Traceback" not in r.stderr


def test_bad_value_is_refused():
    with pytest.raises(ValueError, match="hero_camera"):
        dentalux.render(discs(resolution=(8, 6)), integrator="vpm", hero_camera="yes",
                        bands=[540], progress=False)


def test_memory_counts_every_band_maps():
    s = {"integrator": "vpm", "photons": 1_000_000, "volume_photons": 10_000_000}
    one = limits.render_memory_bytes(64, 48, 3, s)
    three = limits.render_memory_bytes(64, 48, 3, dict(s, hero_camera=True))
    maps = 11_000_000 * limits.PHOTON_BYTES * 1.05
    assert three - one == pytest.approx(maps * 2, rel=1e-9)
    # one band: nothing held beyond a band-by-band render
    assert limits.render_memory_bytes(64, 48, 1, dict(s, hero_camera=True)) == \
        limits.render_memory_bytes(64, 48, 1, s)
    assert limits.render_memory_bytes(64, 48, 3, dict(s, hero_camera=True), texels=1000) - \
        three == pytest.approx(1000 * limits.TEXEL_BYTES * 3, rel=1e-9)
