"""The native `render_band` binding: the resolved-scene JSON of docs/render-contract.md in,
a float32 H x W image and a stats dict out; bad input is a ValueError naming the key path.
(The physics of the integrators is tested in Rust: crates/dentalux-core/tests.)"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
from dentalux import _core


def plane_scene(width: int = 12, height: int = 8, fov_deg: float = 30.0) -> dict:
    """A diffuse plane z = 0 (reflectance 0.5) under a point light, camera looking down."""
    return {
        "camera": {"position": [0, 0, 10], "look_at": [0, 0, 0], "up": [0, 1, 0],
                   "fov_deg": fov_deg, "width": width, "height": height},
        "ambient_medium": 0,
        "media": [{"name": "air", "mua": 0.0, "mus": 0.0, "n": 1.0,
                   "phase": {"g": 0.0, "fd": 0.0, "lobes": None}}],
        "surfaces": [{"type": "lambertian", "reflectance": 0.5}],
        "shapes": [{"type": "quad", "corner": [-50, -50, 0], "u": [100, 0, 0],
                    "v": [0, 100, 0], "boundary": {"kind": "opaque", "surface": 0}}],
        "lights": [{"type": "point", "position": [0, 0, 5], "intensity": 20.0}],
    }


SETTINGS = {"integrator": "path", "spp": 4, "photons": 1000, "seed": 1, "band": 0,
            "threads": None}


def render(scene: dict, **settings):
    return _core.render_band(json.dumps(scene), json.dumps({**SETTINGS, **settings}))


def test_image_shape_dtype_and_centre_value():
    image, stats = render(plane_scene(fov_deg=2.0))
    assert image.shape == (8, 12) and image.dtype == np.float32
    assert stats["integrator"] == "path" and stats["rays"] > 0 and stats["spp"] == 4
    # the centre pixels look straight down at the point under the light: L = rho I / (pi h^2);
    # they reach 0.07 mm off axis (fov 2 deg), where cos^3 falls by < 0.1 %
    centre = image[3:5, 5:7].mean()
    assert centre == pytest.approx(0.5 * 20.0 / (math.pi * 25.0), rel=2e-3)


def test_pm_stats_and_progress():
    calls = []
    image, stats = _core.render_band(
        json.dumps(plane_scene(32, 32)),
        json.dumps({**SETTINGS, "integrator": "pm", "photons": 200_000, "spp": 64}),
        calls.append,
    )
    assert stats["photons_emitted"] == 200_000 and stats["bytes_per_photon"] <= 20
    assert np.isfinite(image).all()
    assert all(isinstance(c, int) for c in calls)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda s: s["shapes"].append({"type": "sphere", "center": [0, 0, 0], "radius": -1,
                                       "boundary": {"kind": "opaque", "surface": 0}}),
         "shapes[1].radius"),
        (lambda s: s["shapes"][0].update(colour=1), "shapes[0].colour: unknown key"),
        (lambda s: s["shapes"][0]["boundary"].update(surface=3), "shapes[0].boundary.surface"),
        (lambda s: s["media"][0].update(mua=-1.0), "media[0].mua"),
        (lambda s: s["media"][0]["phase"].update(g=1.5), "media[0].phase.g"),
        (lambda s: s["lights"].clear(), "lights"),
        (lambda s: s["camera"].update(fov_deg="wide"), "camera.fov_deg"),
        (lambda s: s["surfaces"][0].update(reflectance=1.2), "surfaces[0].reflectance"),
        (lambda s: s["lights"][0].update(type="laser"), "lights[0].type"),
        (lambda s: s["shapes"].append({"type": "box", "min": [-1, -1, 5], "max": [1, 1, 15],
                                       "boundary": {"kind": "opaque", "surface": 0}}),
         "camera.position lies inside shapes[1]"),
        (lambda s: s["shapes"].append({
            "type": "mesh", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
            "triangles": [[0, 1, 2]], "uvs": None,
            "boundary": {"kind": "dielectric", "inside": 0, "outside": 0}}),
         "shapes[1]: a dielectric boundary needs a closed mesh"),
        (lambda s: s["shapes"].append({
            "type": "mesh", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
            "triangles": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 3, 2]],
            "boundary": {"kind": "dielectric", "inside": 0, "outside": 0}}),
         "shapes[1]: a dielectric boundary needs a consistently oriented mesh"),
        (lambda s: s["shapes"][0].update(boundary={"kind": "dielectric", "inside": 0,
                                                   "outside": 0}),
         "shapes[0]: a quad is open"),
    ],
)
def test_bad_scene_names_the_key(edit, message):
    scene = copy.deepcopy(plane_scene())
    edit(scene)
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("]", r"\]")):
        render(scene)


@pytest.mark.parametrize(
    ("settings", "message"),
    [({"integrator": "magic"}, "settings.integrator"), ({"spp": 0}, "settings.spp"),
     ({"radius": -1.0}, "settings.radius"), ({"sp": 3}, "settings.sp: unknown key"),
     ({"kernel_clip": 1}, "settings.kernel_clip"),
     ({"surface_radius": 0.0}, "settings.surface_radius"),
     ({"surface_k": 0}, "settings.surface_k"), ({"surface_k": 2.5}, "settings.surface_k")],
)
def test_bad_settings_name_the_key(settings, message):
    with pytest.raises(ValueError, match=message):
        render(plane_scene(), **settings)


def test_malformed_json():
    with pytest.raises(ValueError, match="scene JSON is malformed"):
        _core.render_band("{", json.dumps(SETTINGS))


def test_kernel_clip_reaches_the_core():
    """`kernel_clip` (the layer kernel clipped by every face) renders the Fig. 3 discs: a
    finite image, the same scene brightness within the estimate's noise and bias budget, and
    a different image (the option is not dropped on the way). Its physics is tested in Rust
    (photon_map::tests::clipped_layer_kernel_is_right_at_a_rim)."""
    import dentalux
    from dentalux.scene.builtin import discs

    images = [dentalux.render(discs(resolution=(24, 18)), integrator="vpm", bands=[540.0],
                              spp=2, photons=20_000, volume_photons=200_000, seed=3,
                              progress=False, kernel_clip=clip).radiance[..., 0]
              for clip in (False, True)]
    assert all(np.isfinite(i).all() and (i >= 0).all() for i in images)
    assert not np.array_equal(images[0], images[1])
    assert images[1].mean() == pytest.approx(images[0].mean(), rel=0.05)


def test_surface_radius_sets_the_surface_map_alone():
    """`surface_radius` caps the surface map's gathering radius and leaves the media's; unset,
    the surface map takes `radius` (the same image bit for bit as before the key existed)."""
    import dentalux
    from dentalux.scene.builtin import discs

    base = dict(integrator="vpm", bands=[540.0], spp=2, photons=20_000,
                volume_photons=200_000, seed=3, progress=False, radius=0.3)
    runs = [dentalux.render(discs(resolution=(24, 18)), **base, **extra)
            for extra in ({}, {"surface_radius": 0.3}, {"surface_radius": 2.0})]
    stats = [r.stats["bands"][0] for r in runs]
    assert [s["surface_radius"] for s in stats] == [0.3, 0.3, 2.0]
    assert [s["radius_medium1"] for s in stats] == [0.3, 0.3, 0.3]
    assert np.array_equal(runs[0].radiance, runs[1].radiance)
    assert not np.array_equal(runs[0].radiance, runs[2].radiance)
    assert np.isfinite(runs[2].radiance).all()


def test_surface_k_sets_the_surface_map_alone():
    """`surface_k` sets the photons of a surface-map estimate and leaves the media's `k`;
    unset, the surface map takes `k` (the same image bit for bit as before the key existed).
    With fewer photons the surface map's derived largest radius shrinks; the media's stays.

    The derived radius is 2·sqrt(k·A/(π n)) over the map's box (A ≤ diagonal²/2), capped at
    0.1 × the scene diagonal: n ≥ 512 surface photons keep k = 8 under the cap whatever the
    box, so the comparison cannot tie at the cap. 200 k emitted store about 750 on the discs'
    table (20 k stored about 65, and a stray photon far out on the table then capped both)."""
    import dentalux
    from dentalux.scene.builtin import discs

    base = dict(integrator="vpm", bands=[540.0], spp=2, photons=200_000,
                volume_photons=200_000, seed=3, progress=False, k=64)
    runs = [dentalux.render(discs(resolution=(24, 18)), **base, **extra)
            for extra in ({}, {"surface_k": 64}, {"surface_k": 8})]
    stats = [r.stats["bands"][0] for r in runs]
    assert np.array_equal(runs[0].radiance, runs[1].radiance)
    assert not np.array_equal(runs[0].radiance, runs[2].radiance)
    assert np.isfinite(runs[2].radiance).all()
    assert stats[2]["surface_photons"] >= 512
    assert stats[2]["surface_radius"] < stats[0]["surface_radius"]
    assert stats[2]["radius_medium1"] == stats[0]["radius_medium1"]


def assert_band_by_band(sc, res, opts: dict, resolution, correlated: bool = False):
    """Each band of the RenderResult ``res`` equals the one-band ``render_band`` call with
    the band's own scene JSON and random-stream key."""
    from dentalux.render import build_settings

    settings = build_settings(sc, **opts)
    for b, wl in enumerate(res.bands):
        key = 0 if correlated else int(wl)
        image, _ = _core.render_band(sc.to_json(wl, resolution),
                                     json.dumps({**settings, "band": key}))
        assert np.array_equal(res.radiance[..., b], image), (correlated, wl)


def test_render_bands_equals_a_render_band_per_band():
    """``dentalux.render`` sends every band in one ``render_bands`` call (the shapes decoded
    and their BVH built once); each band is bit-identical to the one-band call with the
    band's own scene JSON and key, for uncorrelated and correlated bands."""
    import dentalux
    from dentalux.scene import scene_from_dict
    from dentalux.scene.builtin import discs

    sc = scene_from_dict(discs(resolution=(16, 12)))
    bands = [450.0, 540.0, 620.0]
    opts = dict(integrator="vpm", spp=2, photons=2000, volume_photons=3000, seed=5)
    for correlated in (False, True):
        res = dentalux.render(sc, bands=bands, correlated_bands=correlated, progress=False,
                              **opts)
        assert_band_by_band(sc, res, opts, (16, 12), correlated)
        assert [s["wavelength_nm"] for s in res.stats["bands"]] == bands


def test_render_bands_refusals():
    one = plane_scene()
    shared = {k: one[k] for k in ("camera", "ambient_medium", "shapes")}
    band = {k: one[k] for k in ("media", "surfaces", "lights")}
    settings = json.dumps(SETTINGS)
    two = json.dumps({**shared, "bands": [band, band]})
    with pytest.raises(ValueError, match=r"band_keys has 1 entries for 2 bands"):
        _core.render_bands(two, settings, [540])
    bad = copy.deepcopy(band)
    bad["surfaces"][0]["reflectance"] = 2.0
    with pytest.raises(ValueError, match=r"bands\[1\]"):
        _core.render_bands(json.dumps({**shared, "bands": [band, bad]}), settings, [1, 2])
    with pytest.raises(ValueError, match=r"bands: empty"):
        _core.render_bands(json.dumps({**shared, "bands": []}), settings, [])
    cube, stats = _core.render_bands(two, settings, [7, 7])
    assert cube.shape == (2, 8, 12) and np.array_equal(cube[0], cube[1]) and len(stats) == 2


def test_bands_of_textured_scenes_go_one_call_each(monkeypatch):
    """An image texture is in every band's surfaces: such scenes send one band per core call
    (one copy of the pixels at a time), others all bands in one; the images are the same
    as one render_band per band either way."""
    import dentalux
    from dentalux.scene import scene_from_dict
    from dentalux.scene.builtin import cornell_box

    calls = []
    real = _core.render_bands

    def counting(scene_json, settings_json, keys, progress=None):
        calls.append(len(keys))
        return real(scene_json, settings_json, keys, progress)

    monkeypatch.setattr(_core, "render_bands", counting)
    textured = cornell_box(resolution=(8, 6))
    textured["surfaces"]["white"] = {"type": "image", "width": 2, "height": 2,
                                     "data": [0.2, 0.8, 0.8, 0.2], "mapping": "uv"}
    bands = [450.0, 540.0, 605.0]
    opts = dict(integrator="pm", spp=1, photons=2000, seed=3)
    for d, expect in ((textured, [1, 1, 1]), (cornell_box(resolution=(8, 6)), [3])):
        calls.clear()
        sc = scene_from_dict(d)
        res = dentalux.render(sc, bands=bands, progress=False, **opts)
        assert calls == expect
        assert_band_by_band(sc, res, opts, (8, 6))


def test_a_band_error_names_the_wavelength():
    """The core names a bad band by its index in the call (bands[i]); dentalux.render
    names it by its wavelength."""
    import dentalux
    from dentalux.scene.builtin import cornell_box

    d = cornell_box(resolution=(8, 6))
    d["lights"][0]["spectrum"] = {"wavelengths_nm": [400.0, 500.0, 700.0],
                                  "values": [0.0, 0.0, 1.0]}
    with pytest.raises(ValueError, match=r"^at 450 nm: lights: total power is 0"):
        dentalux.render(d, bands=[605, 450], integrator="pm", spp=1, photons=100,
                        progress=False)
