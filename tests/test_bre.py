"""The beam radiance estimate from the command line and the Python API (issue 16's
contracts): `--integrator bre` takes vpm's options and writes the same outputs, render.json
records the estimator, its radius and the photon counts; bad radii, unknown estimators and
a beam in a scene without scattering media are refused naming the setting. The physics
checks (against volpath-nee, the furnace closed form, the progressive form) are the core's
tests: crates/dentalux-core/tests/beam_estimate.rs."""

import json

import dentalux
import numpy as np
import pytest
from cli_run import SCENES, cli

FAST = ["--resolution", "24x18", "--spp", "1", "--bands", "540", "--photons", "2000",
        "--volume-photons", "20000"]


def test_bre_renders_and_records_its_estimator(tmp_path):
    out = tmp_path / "bre"
    r = cli("render", str(SCENES / "discs.toml"), "--out", str(out), "--integrator", "bre",
            "--radius", "0.5", "--seed", "3", *FAST, "--json")
    assert r.returncode == 0, r.stderr
    summary = json.loads((out / "render.json").read_text())
    band = summary["stats"][0]
    assert band["integrator"] == "bre" and band["volume_estimator"] == "beam"
    assert band["radius_medium1"] == 0.5
    assert band["photons_emitted"] == 20000 and band["volume_photons"] > 0
    img = np.load(out / "radiance.npy")
    assert img.shape == (18, 24, 1) and np.isfinite(img).all() and img.mean() > 0


def test_ppm_with_the_beam_records_its_radius_per_pass():
    sc = dentalux.scene.load.load_scene(SCENES / "discs.toml")
    res = dentalux.render(sc, integrator="ppm", volume_estimator="beam", passes=3, radius=1.0,
                          spp=1, photons=2000, volume_photons=20000, bands=[540.0],
                          resolution=(16, 12), progress=False)
    band = res.stats["bands"][0]
    assert band["volume_estimator"] == "beam"
    radii = [band[f"radius_medium1_pass{p}"] for p in (1, 2, 3)]
    assert radii[0] == 1.0 and radii[0] > radii[1] > radii[2]


def test_python_api_renders_bre():
    sc = dentalux.scene.load.load_scene(SCENES / "discs.toml")
    res = dentalux.render(sc, integrator="bre", spp=1, photons=2000, volume_photons=20000,
                          bands=[540.0], resolution=(16, 12), progress=False, seed=2)
    again = dentalux.render(sc, integrator="bre", spp=1, photons=2000, volume_photons=20000,
                            bands=[540.0], resolution=(16, 12), progress=False, seed=2)
    assert np.array_equal(res.radiance, again.radiance)
    assert res.stats["bands"][0]["integrator"] == "bre"


@pytest.mark.parametrize("args,field", [
    (["--radius", "0"], "radius"),
    (["--radius", "-1"], "radius"),
    (["--radius", "nan"], "radius"),
    (["--volume-estimator", "beams"], "volume_estimator"),
])
def test_bad_beam_settings_exit_2_naming_the_setting(tmp_path, args, field):
    r = cli("render", str(SCENES / "discs.toml"), "--out", str(tmp_path / "o"),
            "--integrator", "bre", *FAST, *args)
    assert r.returncode == 2, r.stderr
    assert field in r.stderr and "Traceback" not in r.stderr


def test_unknown_estimator_in_python_is_a_value_error():
    sc = dentalux.scene.load.load_scene(SCENES / "discs.toml")
    with pytest.raises(ValueError, match="volume_estimator.*did you mean 'beam'"):
        dentalux.render(sc, integrator="ppm", volume_estimator="beem", progress=False,
                        resolution=(8, 6), bands=[540.0])


def test_beam_in_a_scene_without_scattering_media_is_refused(tmp_path):
    r = cli("render", str(SCENES / "cornell.toml"), "--out", str(tmp_path / "o"),
            "--integrator", "bre", *FAST)
    assert r.returncode == 2, r.stderr
    assert "integrator" in r.stderr and "no scattering medium" in r.stderr
