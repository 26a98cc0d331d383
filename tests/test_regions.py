"""Named image regions: validated with the scene, their mean CIELAB lands in colour.json."""

import json

import numpy as np
import pytest
from dentalux.cli import main
from dentalux.scene.builtin import cornell_box
from dentalux.scene.load import scene_from_dict
from dentalux.scene.schema import SceneError


def test_bad_regions_name_the_key_path():
    d = cornell_box(resolution=(8, 6))
    for bad, match in (([0, 0, 9, 2], r"regions\.wall = \[0, 0, 9, 2\]: .*x1 <= 8"),
                       ([0, 0, 1], r"regions\.wall = \[0, 0, 1\]: must be"),
                       ([2, 0, 1, 2], r"regions\.wall"),
                       ([-1, 0, 1, 2], r"regions\.wall\[0\]")):
        d["regions"] = {"wall": bad}
        with pytest.raises(SceneError, match=match):
            scene_from_dict(d)


def test_render_writes_region_colours(tmp_path):
    """A real 8x6 render of the Cornell box: colour.json holds the CIELAB of the mean
    spectrum of each named rectangle, the same as recomputing it from radiance.npy."""
    import tomli_w
    from dentalux.color import system
    from dentalux.scene.resolve import d65_relative

    d = cornell_box(resolution=(8, 6))
    d["regions"] = {"left": [0, 0, 2, 6], "centre": [3, 2, 5, 4]}
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(tomli_w.dumps(d))
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        main(["render", str(scene_file), "--out", str(out), "--spp", "1", "--photons", "2000",
              "--json"])
    assert exc.value.code == 0
    colour = json.loads((out / "colour.json").read_text())
    assert set(colour["regions"]) == {"left", "centre"}
    radiance = np.load(out / "radiance.npy")
    bands = [450.0, 540.0, 605.0]
    divisor = np.array([d65_relative(b) for b in bands])
    mean = radiance[0:6, 0:2].reshape(-1, 3).mean(axis=0) / divisor / 15.0
    lab = system("D65", "2").spectrum_to_Lab(mean, bands)
    assert np.allclose(colour["regions"]["left"]["lab"], lab, atol=1e-6)


def _cornell_with_regions(tmp_path):
    import tomli_w

    d = cornell_box(resolution=(8, 6))
    d["regions"] = {"left": [0, 0, 2, 6], "centre": [3, 2, 5, 4]}
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(tomli_w.dumps(d))
    return scene_file


def test_render_match_gives_each_region_its_nearest_tabs(tmp_path):
    """--match GUIDE: each measured region's entry lists the guide's nearest tabs, nearest
    first, with the ΔE00 that dentalux.shade_guides.nearest computes from the region's
    CIELAB (the guide with values in the table: the 3D-Master rows of one repository)."""
    from dentalux.shade_guides import nearest

    guide = "vita-3d-master@dr-lamia-repo"
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        main(["render", str(_cornell_with_regions(tmp_path)), "--out", str(out), "--spp", "1",
              "--photons", "2000", "--match", guide, "--json"])
    assert exc.value.code == 0
    colour = json.loads((out / "colour.json").read_text())
    for reg in colour["regions"].values():
        want = nearest(reg["lab"], guide)
        assert [(m["tab"], m["delta_e00"]) for m in reg["shade_match"]] == want
        assert reg["shade_match_guide"] == guide and "geometry" in "".join(reg)
        des = [m["delta_e00"] for m in reg["shade_match"]]
        assert des == sorted(des)


@pytest.mark.parametrize("extra, message", [
    (["--match", "vita-classicl"], "did you mean 'vita-classical'"),
    (["--match", "vita-classical"], "no tab has published CIELAB"),
    (["--match", "vita-3d-master@dr-lamia-repo", "--resolution", "4x3"], "own pixels"),
])
def test_render_match_refuses_before_rendering(tmp_path, capsys, extra, message):
    with pytest.raises(SystemExit) as exc:
        main(["render", str(_cornell_with_regions(tmp_path)), "--out", str(tmp_path / "o"),
              "--spp", "1", "--photons", "2000", *extra])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "o" / "radiance.npy").exists()
