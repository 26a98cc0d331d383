"""The figures pipeline: the enamel scaling of Fig. 4, tiny renders of each scene, the CLI."""

import json

import numpy as np
import pytest
from dentalux import materials
from dentalux.cli import main
from dentalux.figures import (
    Quality,
    make_figures,
    match_enamel_scale,
    transmittance_d65,
)

TINY = Quality("tiny", (24, 18), 1, 2_000, 20_000, 0.5, (12, 9), 4, 16, 0.5, 20_000, 1.0, 1)


def test_enamel_scale_matches_the_biomaterial_transmittance():
    """Fig. 4: the scaled enamel disc transmits what the biomaterial disc transmits. The
    check reruns both with another seed; tolerance: 4 standard errors of the difference of
    two 20 000-photon estimates (each TT has s.e. <= 0.0035) plus the bisection width."""
    bio = materials.get("biomaterial-table1")
    enamel = materials.get("enamel")
    target = transmittance_d65(bio, 0.5)
    s = match_enamel_scale(target, 0.5, enamel)
    assert s > 1.0  # the library enamel is clearer than the biomaterial
    check = transmittance_d65(enamel.scaled(s, s), 0.5, seed=11)
    assert abs(check - transmittance_d65(bio, 0.5, seed=11)) < 4 * np.sqrt(2) * 0.0035 + 1e-3


@pytest.mark.parametrize("figure", ["fig3", "crown"])
def test_tiny_figures_render_with_colour_and_settings(tmp_path, figure):
    report = make_figures(tmp_path, quality=TINY, only=[figure], log=lambda *_: None)
    for summary in report["figures"][figure]:
        folder = tmp_path / summary["figure"]
        for name in ("image.png", "image.exr", "spectral.exr", "radiance.npy", "figure.json",
                     "colour.json"):
            assert (folder / name).is_file(), name
        radiance = np.load(folder / "radiance.npy")
        assert radiance.shape == (18, 24, 3) and np.all(np.isfinite(radiance))
        assert radiance.mean() > 0
        on_disk = json.loads((folder / "figure.json").read_text())
        assert on_disk["quality"]["name"] == "tiny"
        assert on_disk["settings"]["volume_photons"] == 20_000
    if figure == "crown":
        crown = report["figures"]["crown"][0]
        assert np.isfinite(crown["delta_e00"]) and crown["delta_e00"] >= 0
        assert crown["verdict"] in ("imperceptible", "acceptable", "unacceptable")
        assert (tmp_path / "crown_vs_natural.png").is_file()


def test_cli_figures(tmp_path):
    with pytest.raises(SystemExit) as exc:
        main(["figures", "--out", str(tmp_path), "--only", "fig2"])
    assert exc.value.code == 0
    assert (tmp_path / "fig2_spd.png").is_file() and (tmp_path / "fig2_spd.svg").is_file()
    for bad in (["--quality", "best"], ["--only", "fig9"]):
        with pytest.raises(SystemExit) as exc:
            main(["figures", "--out", str(tmp_path), *bad])
        assert exc.value.code == 2
