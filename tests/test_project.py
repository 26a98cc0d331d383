"""Image regions placed by 3-D points (dentalux.scene.project) land where the renderer draws
those points: checked against a render, not against a second copy of the camera formula."""

import numpy as np
import pytest
from dentalux.render import render
from dentalux.scene.load import scene_from_dict
from dentalux.scene.project import project, square_region

CAMERA = {"position": [0.0, 0.0, -40.0], "look_at": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
          "fov_deg": 30.0, "resolution": [64, 48]}


def _sphere_scene(centre) -> dict:
    return {"camera": CAMERA,
            "surfaces": {"white": {"type": "lambertian", "reflectance": 0.9}},
            "shapes": [{"type": "sphere", "center": list(centre), "radius": 0.6,
                        "surface": "white"}],
            "lights": [{"type": "point", "position": [0.0, 0.0, -39.0], "intensity": 100.0}]}


@pytest.mark.parametrize("centre", [(5.0, 2.0, 0.0), (-4.0, -3.0, 2.0)])
def test_projection_finds_the_rendered_sphere(centre):
    r = render(scene_from_dict(_sphere_scene(centre)), integrator="pm", bands=[540.0], spp=4,
               photons=1000, progress=False)
    img = r.radiance[..., 0]
    ys, xs = np.nonzero(img > 0.5 * img.max())
    (px, py), = project(CAMERA, [centre])
    # the sphere (about 4 pixels across) is centred on the projected point
    assert abs(xs.mean() + 0.5 - px) < 1.0 and abs(ys.mean() + 0.5 - py) < 1.0
    # the render's handedness: looking along +z with +y up, +x lies on the image's left
    assert (px < 32) == (centre[0] > 0)
    x0, y0, x1, y1 = square_region(CAMERA, centre, 0.6)
    assert x0 <= xs.min() and xs.max() < x1 and y0 <= ys.min() and ys.max() < y1


def test_projection_refuses_bad_input():
    assert np.isnan(project(CAMERA, [[0.0, 0.0, -50.0]])).all()  # behind the camera
    with pytest.raises(ValueError, match="points"):
        project(CAMERA, [[1.0, 2.0]])
    with pytest.raises(ValueError, match="behind the camera"):
        square_region(CAMERA, [0.0, 0.0, -60.0], 1.0)


def _centre(shape: dict) -> np.ndarray:
    return np.asarray(shape["corner"]) + 0.5 * (np.asarray(shape["u"]) + np.asarray(shape["v"]))


@pytest.mark.parametrize("which", ["cornell_box", "fig5"])
def test_walls_named_left_and_right_are_seen_there(which):
    """The Cornell boxes' walls named left (red) and right (green) lie on those sides of the
    image the renderer makes (Fig. 5 once had them the other way round)."""
    if which == "cornell_box":
        from dentalux.scene.builtin import cornell_box

        scene = cornell_box(resolution=(64, 64))
    else:
        from dentalux.figures import QUALITIES, cornell_teeth_scene

        scene = cornell_teeth_scene(QUALITIES["preview"])
    walls = {s["name"]: s for s in scene["shapes"] if s.get("name") in ("left", "right")}
    assert walls["left"]["surface"] == "red" and walls["right"]["surface"] == "green"
    w = scene["camera"]["resolution"][0]
    (xl, _), (xr, _) = project(scene["camera"], [_centre(walls["left"]), _centre(walls["right"])])
    assert xl < w / 2 < xr
