"""The scene checks' inside-a-shape test is the core's (``_core.shape_contains``): it agrees
with the shapes' formulas, refuses bad shape JSON naming the key, gives open meshes no inside,
counts a mesh whose vertices are duplicated along a seam as closed (as the Python check it
replaces did), and the scene JSON the render gets is byte for byte what it was."""

from __future__ import annotations

import json

import numpy as np
import pytest
from dentalux import _core
from dentalux.scene import SceneError, scene_from_dict
from dentalux.scene.resolve import shape_contains, to_plain

TILT = {"rotate": [{"axis": [1, 1, 0], "angle_deg": 35.0}], "scale": 1.5,
        "translate": [2, -1, 3]}


def scene(shapes: list, camera=(0, -60, 20), lights=None) -> dict:
    return {
        "camera": {"position": list(camera), "look_at": [0, 0, 0], "up": [0, 0, 1]},
        "media": {"glass": {"mua": 0.0, "mus": 0.0, "n": 1.5}},
        "surfaces": {"white": {"reflectance": 0.8}},
        "shapes": shapes,
        "lights": lights or [{"type": "point", "position": [0, 0, 40], "intensity": 10.0}],
    }


def cube_obj(seam: bool = False) -> str:
    """The unit cube; with ``seam``, corner 7 written twice (as a uv seam does) and one
    triangle using the copy, so the cube is open by index but closed as a solid."""
    v = ["0 0 0", "1 0 0", "1 1 0", "0 1 0", "0 0 1", "1 0 1", "1 1 1", "0 1 1"]
    f = ["1 3 2", "1 4 3", "5 6 7", "5 7 8", "1 2 6", "1 6 5", "2 3 7", "2 7 6", "3 4 8",
         "3 8 7", "4 1 5", "4 5 8"]
    if seam:
        v.append("1 1 1")
        f[2] = "5 6 9"
    return "".join(f"v {x}\n" for x in v) + "".join(f"f {x}\n" for x in f)


def reference(shape: dict, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inside by the shape's formula in object space, and the distance [mm] from the
    boundary in object units (points within 1e-6 of it are left out of the comparison)."""
    m = np.asarray(shape["transform"])
    p = (np.linalg.inv(m) @ np.c_[pts, np.ones(len(pts))].T).T[:, :3]
    if shape["type"] == "sphere":
        d = shape["radius"] - np.linalg.norm(p - shape["center"], axis=1)
    elif shape["type"] == "box":
        d = np.minimum(p - shape["min"], np.subtract(shape["max"], p)).min(axis=1)
    else:
        a = np.asarray(shape["axis"])
        rel = p - shape["center"]
        h = rel @ a
        radial = np.linalg.norm(rel - h[:, None] * a, axis=1)
        d = np.minimum(np.minimum(h, shape["height"] - h), shape["radius"] - radial)
    return d > 0, np.abs(d)


def test_core_agrees_with_the_shapes_formulas(np_rng):
    shapes = [
        {"type": "sphere", "center": [1, 2, 3], "radius": 4.0, "surface": "white"},
        {"type": "box", "min": [-3, -2, -1], "max": [4, 3, 2], "surface": "white",
         "transform": TILT},
        {"type": "cylinder", "center": [0, 0, -2], "axis": [1, 2, 2], "radius": 3.0,
         "height": 5.0, "inside": "glass", "transform": TILT},
    ]
    sc = scene_from_dict(scene(shapes))
    pts = np_rng.uniform(-9, 9, size=(4000, 3))
    for i, shape in enumerate(sc._shapes):
        want, dist = reference(shape, pts)
        got = shape_contains(shape, pts)
        keep = dist > 1e-6
        assert 100 < want[keep].sum() < keep.sum() - 100, shape["type"]
        assert np.array_equal(got[keep], want[keep]), shape["type"]
        assert np.array_equal(sc._inside(i, pts), got)


def test_bad_shape_json_is_a_value_error_naming_the_key():
    sphere = {"type": "sphere", "center": [0, 0, 0], "radius": 1.0,
              "boundary": {"kind": "opaque", "surface": 0}}
    with pytest.raises(ValueError, match=r"^shape\.colour: unknown key; allowed: boundary, "
                                         r"center, radius, transform, type$"):
        _core.shape_contains(json.dumps({**sphere, "colour": 1}), [(0.0, 0.0, 0.0)])
    with pytest.raises(ValueError, match=r"^shape\.radius"):
        _core.shape_contains(json.dumps({**sphere, "radius": 0}), [])
    with pytest.raises(ValueError, match="^shape JSON is malformed"):
        _core.shape_contains("{", [])
    assert _core.shape_contains(json.dumps(sphere), [(0, 0, 0), (0, 0, 1), (2, 0, 0)]) == \
        [True, False, False]


def test_meshes_open_closed_and_seamed(tmp_path):
    (tmp_path / "cube.obj").write_text(cube_obj())
    (tmp_path / "seam.obj").write_text(cube_obj(seam=True))
    (tmp_path / "open.obj").write_text("".join(cube_obj().splitlines(True)[:-2]))
    place = {"scale": 4.0, "translate": [-2, -32, 8]}  # [-2, 2] x [-32, -28] x [8, 12]
    inside_it, outside = [0.5, -29.5, 10.5], [0.5, -33, 10.5]
    for name in ("cube.obj", "seam.obj"):
        shapes = [{"type": "mesh", "file": name, "surface": "white", "transform": place}]
        sc = scene_from_dict(scene(shapes), base_dir=tmp_path)
        assert list(sc._inside(0, [inside_it, outside])) == [True, False]
        with pytest.raises(SceneError, match=r"inside the opaque shapes\[0\] \(mesh\)"):
            scene_from_dict(scene(shapes, camera=inside_it), base_dir=tmp_path)
    shapes = [{"type": "mesh", "file": "open.obj", "surface": "white", "transform": place}]
    sc = scene_from_dict(scene(shapes, camera=inside_it), base_dir=tmp_path)
    assert not sc._inside(0, [inside_it]).any()
    # a light inside a dielectric mesh, as the core sees it
    shapes = [{"type": "mesh", "file": "cube.obj", "inside": "glass", "transform": place}]
    light = [{"type": "point", "position": inside_it, "intensity": 1.0}]
    with pytest.raises(SceneError, match=r"lights\[0\]: lies inside shapes\[0\]"):
        scene_from_dict(scene(shapes, lights=light), base_dir=tmp_path)


def test_far_meshes_are_not_serialised_for_the_checks_and_the_json_is_unchanged(tmp_path):
    (tmp_path / "cube.obj").write_text(cube_obj())
    shapes = [{"type": "mesh", "file": "cube.obj", "inside": "glass"},
              {"type": "sphere", "center": [0, 0, 5], "radius": 2, "surface": "white"},
              {"type": "quad", "corner": [-9, -9, 0], "u": [18, 0, 0], "v": [0, 18, 0],
               "surface": "white"}]
    sc = scene_from_dict(scene(shapes), base_dir=tmp_path)
    assert sc._shape_texts[0] is None  # the camera and the light are outside its bounds
    assert sc.to_json(540.0).endswith(
        ',"shapes":' + json.dumps(sc._shapes, separators=(",", ":"), default=to_plain) + "}")


def test_a_seamed_dielectric_mesh_renders_as_the_closed_one(tmp_path):
    # the core judges closedness for Python's check (_core.mesh_topology) and for the render
    # alike, on merged positions: the seamed cube (open by index) is the same solid
    from dentalux.render import render

    (tmp_path / "cube.obj").write_text(cube_obj())
    (tmp_path / "seam.obj").write_text(cube_obj(seam=True))
    place = {"scale": 8.0, "translate": [-4, -4, -4]}
    images = []
    for name in ("cube.obj", "seam.obj"):
        floor = {"type": "quad", "corner": [-20, -20, -5], "u": [40, 0, 0], "v": [0, 40, 0],
                 "surface": "white"}
        d = scene([{"type": "mesh", "file": name, "inside": "glass", "transform": place}, floor])
        d["camera"]["resolution"] = [8, 6]
        sc = scene_from_dict(d, base_dir=tmp_path)
        images.append(render(sc, integrator="path", bands=[540.0], spp=2, seed=3,
                             progress=False).radiance)
    assert images[0].max() > 0
    assert np.array_equal(images[0], images[1])


def test_open_or_misoriented_dielectric_meshes_are_refused_with_the_core_counts(tmp_path):
    lines = cube_obj().splitlines(True)
    (tmp_path / "open.obj").write_text("".join(lines[:-2]))
    flipped = lines[:-1] + ["f 4 8 5\n"]  # the last triangle wound the wrong way
    (tmp_path / "flipped.obj").write_text("".join(flipped))
    for name, message in (("open.obj", r"^shapes\[0\]: the mesh is open \(not watertight: 4"),
                          ("flipped.obj", r"inconsistently oriented \(3 edges")):
        d = scene([{"type": "mesh", "file": name, "inside": "glass"}])
        with pytest.raises(SceneError, match=message):
            scene_from_dict(d, base_dir=tmp_path)
    tetra = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    assert _core.mesh_topology(tetra, faces) == ("closed", 0, False)
    assert _core.mesh_topology(tetra, faces[:3]) == ("open", 3, False)
    # wound inward: closed, and the core says so (Python then flips it, as the decoder would)
    inward = [(a, c, b) for a, b, c in faces]
    assert _core.mesh_topology(tetra, inward) == ("closed", 0, True)
    with pytest.raises(ValueError, match=r"^triangles\[0\] = \[0, 1, 3\] refers to a vertex"):
        _core.mesh_topology([(0, 0, 0)] * 3, [(0, 1, 3)])
