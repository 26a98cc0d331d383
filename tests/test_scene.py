"""Scenes: loading, validation (key paths, did-you-mean), transforms, meshes, the render
contract JSON, dentalux.render and the render/scene CLI.

Until the Rust core has ``render_bands``, rendering goes through ``fake_core`` (a stand-in
that checks the JSON against docs/render-contract.md and returns a known image). The real
renders at the bottom run once ``dentalux._core.render_bands`` exists.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import dentalux
import numpy as np
import pytest
from dentalux import _core
from dentalux.cli import main
from dentalux.scene import SceneError, load_scene, scene_from_dict
from dentalux.scene import transform as tf
from dentalux.scene.builtin import cornell_box, discs
from dentalux.scene.resolve import material_library
from dentalux.scene.schema import SETTING_KEYS
from dentalux.testing import bands_from_band

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell.toml"
DISCS = ROOT / "scenes" / "discs.toml"
HAS_CORE = hasattr(_core, "render_bands")

# ---------------------------------------------------------------------------------------
# The render contract (docs/render-contract.md), checked key by key.

VEC = "vec3"
CAMERA = {"position": VEC, "look_at": VEC, "up": VEC, "fov_deg": float, "width": int,
          "height": int}
SURFACES = {
    "lambertian": {"type": str, "reflectance": float},
    "checker": {"type": str, "a": float, "b": float, "size": float, "mapping": str},
    "image": {"type": str, "width": int, "height": int, "data": list, "mapping": str,
              "size": float},
    "black": {"type": str},
}
SHAPES = {
    "sphere": {"center": VEC, "radius": float},
    "quad": {"corner": VEC, "u": VEC, "v": VEC},
    "box": {"min": VEC, "max": VEC},
    "cylinder": {"center": VEC, "axis": VEC, "radius": float, "height": float},
    "mesh": {"positions": list, "triangles": list, "uvs": (list, type(None))},
}
LIGHTS = {
    "quad": {"corner": VEC, "u": VEC, "v": VEC, "radiance": float},
    "disc": {"center": VEC, "normal": VEC, "radius": float, "radiance": float},
    "point": {"position": VEC, "intensity": float},
    "spot": {"position": VEC, "direction": VEC, "intensity": float, "cone_deg": float,
             "falloff_deg": float},
}


def _typed(value, kind, path):
    if kind == VEC:
        assert isinstance(value, list) and len(value) == 3, path
        assert all(isinstance(x, float) and math.isfinite(x) for x in value), path
    elif kind is float:
        assert isinstance(value, float) and math.isfinite(value), f"{path} = {value!r}"
    elif kind is int:
        assert isinstance(value, int) and not isinstance(value, bool), path
    else:
        assert isinstance(value, kind), f"{path}: {type(value)}"


OPTIONAL = {"size"}  # image surfaces: an optional size [mm] for xy mapping


def _keys(d, spec, path):
    assert set(d) - OPTIONAL == set(spec) - OPTIONAL, f"{path}: {sorted(d)} != {sorted(spec)}"
    for k, kind in spec.items():
        if k not in d:
            continue
        _typed(d[k], kind, f"{path}.{k}")


def check_contract(scene: dict) -> None:
    """Assert that ``scene`` is exactly the resolved-scene JSON of the contract."""
    assert set(scene) == {"camera", "ambient_medium", "media", "surfaces", "shapes", "lights"}
    _keys(scene["camera"], CAMERA, "camera")
    n_media, n_surf = len(scene["media"]), len(scene["surfaces"])
    assert 0 <= scene["ambient_medium"] < n_media
    for i, m in enumerate(scene["media"]):
        assert set(m) == {"name", "mua", "mus", "n", "phase"}, i
        assert m["mua"] >= 0 and m["mus"] >= 0 and m["n"] >= 1
        assert set(m["phase"]) == {"g", "fd", "lobes"}
        assert -1 < m["phase"]["g"] < 1 and 0 <= m["phase"]["fd"] <= 1
    for i, s in enumerate(scene["surfaces"]):
        _keys(s, SURFACES[s["type"]], f"surfaces[{i}]")
    for i, s in enumerate(scene["shapes"]):
        spec = {"type": str, "boundary": dict, **SHAPES[s["type"]]}
        if s["type"] != "quad":
            spec["transform"] = list
            m = np.asarray(s["transform"], dtype=float)
            assert m.shape == (4, 4) and np.allclose(m[3], [0, 0, 0, 1])
        _keys(s, spec, f"shapes[{i}]")
        b = s["boundary"]
        if b["kind"] == "opaque":
            assert set(b) == {"kind", "surface"} and 0 <= b["surface"] < n_surf
        else:
            assert s["type"] != "quad"
            assert set(b) == {"kind", "inside", "outside"}
            assert 0 <= b["inside"] < n_media and 0 <= b["outside"] < n_media
        if s["type"] == "cylinder":
            assert abs(np.linalg.norm(s["axis"]) - 1) < 1e-12
        if s["type"] == "mesh":
            tri = np.asarray(s["triangles"])
            assert tri.ndim == 2 and tri.shape[1] == 3
            assert tri.min() >= 0 and tri.max() < len(s["positions"])
    assert len(scene["lights"]) >= 1
    for i, lt in enumerate(scene["lights"]):
        _keys(lt, {"type": str, **LIGHTS[lt["type"]]}, f"lights[{i}]")


class FakeCore:
    """A stand-in for ``_core.render_band``: checks both JSON strings against the contract
    and returns an image filled with the settings' ``band`` value."""

    def __init__(self):
        self.calls = []

    def __call__(self, scene_json, settings_json, progress=None):
        scene, settings = json.loads(scene_json), json.loads(settings_json)
        check_contract(scene)
        # every key of the core's settings schema but the per-call pass index
        assert set(settings) == set(SETTING_KEYS) - {"pass_index"}
        self.calls.append((scene, settings))
        if progress is not None:
            progress(1)
        h, w = scene["camera"]["height"], scene["camera"]["width"]
        image = np.full((h, w), float(settings["band"]), dtype=np.float32)
        return image, {"photons_emitted": settings["photons"], "seconds": 0.0}


@pytest.fixture
def fake_core(monkeypatch):
    fake = FakeCore()
    monkeypatch.setattr(_core, "render_bands", bands_from_band(fake), raising=False)
    return fake


# ---------------------------------------------------------------------------------------
# A scene with every shape, surface and light type, and a mesh file.

CUBE_OBJ = """# unit cube, outward-facing triangles
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""

TETRA_PLY = """ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
element face 4
property list uchar int vertex_indices
end_header
0 0 0
2 0 0
0 2 0
0 0 2
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
"""


def every_type(tmp_path: Path) -> dict:
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    (tmp_path / "tetra.ply").write_text(TETRA_PLY)
    return {
        "camera": {"position": [0, -50, 20], "look_at": [0, 0, 0], "up": [0, 0, 1],
                   "resolution": [8, 6]},
        "media": {"glass": {"mua": 0.0, "mus": 0.0, "n": 1.5},
                  "milk": {"mua": {"wavelengths_nm": [400, 700], "values": [0.1, 0.4]},
                           "mus": 5.0, "g": 0.8, "fd": 0.1, "n": 1.33}},
        "surfaces": {"white": {"reflectance": 0.8},
                     "check": {"type": "checker", "a": 0.9, "b": 0.05, "size": 2.0},
                     "img": {"type": "image", "width": 2, "height": 1, "data": [0.1, 0.9]},
                     "void": {"type": "black"}},
        "shapes": [
            {"type": "sphere", "center": [0, 0, 5], "radius": 2, "inside": "glass"},
            {"type": "rectangle", "corner": [-50, -50, 0], "u": [100, 0, 0],
             "v": [0, 100, 0], "surface": "check"},
            {"type": "box", "min": [5, 5, 0], "max": [8, 8, 3], "surface": "img"},
            {"type": "cylinder", "center": [-8, 0, 0], "radius": 5, "height": 5,
             "inside": "milk", "outside": "air"},
            {"type": "mesh", "file": "cube.obj", "inside": "glass",
             "transform": {"scale": 2, "translate": [10, -10, 0]}},
            {"type": "mesh", "file": "tetra.ply", "surface": "void"},
            {"type": "mesh", "positions": [[0, 0, 20], [1, 0, 20], [0, 1, 20]],
             "triangles": [[0, 1, 2]], "uvs": [[0, 0], [1, 0], [0, 1]], "surface": "white"},
        ],
        "lights": [
            {"type": "quad", "corner": [-5, -5, 40], "u": [0, 10, 0], "v": [10, 0, 0]},
            {"type": "disc", "center": [0, 0, 40], "normal": [0, 0, -1], "radius": 3,
             "radiance": 2.0, "spectrum": "flat"},
            {"type": "point", "position": [0, 0, 30], "intensity": 100.0},
            {"type": "spot", "position": [0, 0, 30], "direction": [0, 0, -1],
             "spectrum": {"wavelengths_nm": [400, 700], "values": [1.0, 2.0]}},
        ],
    }


def base() -> dict:
    """A small valid scene that the bad-input cases break one key at a time."""
    return {
        "camera": {"position": [0, -30, 10], "look_at": [0, 0, 0], "up": [0, 0, 1]},
        "media": {"enamel": {"mua": 0.01, "mus": 1.0, "g": 0.9, "n": 1.63}},
        "surfaces": {"white": {"type": "lambertian", "reflectance": 0.8}},
        "shapes": [
            {"type": "quad", "corner": [-10, -10, 0], "u": [20, 0, 0], "v": [0, 20, 0],
             "surface": "white"},
            {"type": "sphere", "center": [0, 0, 3], "radius": 2.0, "surface": "white"},
            {"type": "cylinder", "center": [5, 0, 0], "radius": 1.0, "height": 2.0,
             "inside": "enamel", "outside": "air"},
            {"type": "box", "min": [-6, -1, 0], "max": [-4, 1, 2], "surface": "white"},
        ],
        "lights": [{"type": "point", "position": [0, 0, 20], "intensity": 10.0}],
    }


# ---------------------------------------------------------------------------------------
# Loading


def test_cornell_toml_matches_builtin_and_contract():
    from_file = load_scene(CORNELL)
    built = scene_from_dict(cornell_box())
    assert from_file.bands == [450.0, 540.0, 605.0]
    for wl in from_file.bands:
        assert from_file.to_json(wl) == built.to_json(wl)
        check_contract(json.loads(from_file.to_json(wl)))
    assert from_file.hash == built.hash and len(from_file.hash) == 64
    assert from_file.default_integrator == "pm"


def test_discs_toml_matches_builtin():
    lib = material_library()
    if lib is None or "biomaterial-table1" not in lib.names():
        with pytest.raises(SceneError, match=r"media\.disc\.material = 'biomaterial-table1'"):
            load_scene(DISCS)
        pytest.skip("material biomaterial-table1 not in the library yet")
    from_file, built = load_scene(DISCS), scene_from_dict(discs())
    for wl in (450.0, 540.0, 605.0):
        assert from_file.to_json(wl) == built.to_json(wl)
        check_contract(from_file.resolve(wl))
    assert from_file.default_integrator == "vpm"


def test_discs_geometry_is_the_papers():
    """Fig. 3: 10 mm wide, 5 mm thick discs, one on the ribbon, one 5 mm above it."""
    d = discs(material="air")
    d["media"]["disc"] = {"mua": 0.1, "mus": 10.0, "g": 0.75, "n": 1.54}
    s = scene_from_dict(d)
    shapes = s.resolve(540)["shapes"]
    ribbon_z = shapes[1]["corner"][2]
    lying, above = shapes[2], shapes[3]
    for disc in (lying, above):
        assert disc["radius"] * 2 == 10.0 and disc["height"] == 5.0
        assert disc["axis"] == [0.0, 0.0, 1.0] and disc["boundary"]["kind"] == "dielectric"
    assert lying["center"][2] - ribbon_z == pytest.approx(0.01)
    assert above["center"][2] - ribbon_z == pytest.approx(5.0)


def test_every_type_resolves_to_the_contract(tmp_path):
    s = scene_from_dict(every_type(tmp_path), base_dir=tmp_path)
    for wl in (450.0, 605.0):
        out = s.resolve(wl)
        check_contract(out)
        json.loads(s.to_json(wl))
    out = s.resolve(550.0)
    names = [m["name"] for m in out["media"]]
    assert names == ["air", "glass", "milk"] and out["ambient_medium"] == 0
    assert out["media"][2]["mua"] == pytest.approx(0.1 + 0.3 * 150 / 300)
    assert out["shapes"][0]["boundary"] == {"kind": "dielectric", "inside": 1, "outside": 0}
    assert out["shapes"][2]["boundary"] == {"kind": "opaque", "surface": 2}
    # Light spectra: flat, and a table interpolated linearly.
    assert out["lights"][1]["radiance"] == 2.0
    assert out["lights"][3]["intensity"] == pytest.approx(1.0 + 150 / 300)
    assert out["surfaces"][0] == {"type": "lambertian", "reflectance": 0.8}


def test_d65_emission_matches_cie_table():
    """D65 relative power, normalised to 1 at 560 nm (CIE 15 table: 117.008 at 450 nm,
    100.000 at 560 nm, 80.0268 at 650 nm)."""
    d = base()
    d["lights"][0]["intensity"] = 3.0
    s = scene_from_dict(d)
    for wl, cie in ((450.0, 117.008), (560.0, 100.0), (650.0, 80.0268)):
        assert s.resolve(wl)["lights"][0]["intensity"] == pytest.approx(3.0 * cie / 100, rel=1e-4)
    with pytest.raises(SceneError, match=r"lights\[0\]\.spectrum = 'D65'"):
        s.resolve(800.0)


def test_material_library_media():
    lib = material_library()
    if lib is None or "enamel" not in lib.names():
        pytest.skip("material library not available")
    d = base()
    d["media"]["enamel"] = {"material": "enamel"}
    d["media"]["thin"] = {"material": "enamel", "mus": 2.0}
    s = scene_from_dict(d)
    for wl in (450.0, 540.0, 605.0):
        ref = lib.get("enamel").at(wl)
        media = {m["name"]: m for m in s.resolve(wl)["media"]}
        assert media["enamel"]["mua"] == ref.mua and media["enamel"]["mus"] == ref.mus
        assert media["enamel"]["n"] == ref.n and media["enamel"]["phase"]["g"] == ref.g
        assert media["thin"]["mus"] == 2.0 and media["thin"]["mua"] == ref.mua
    d["media"]["enamel"] = {"material": "enamle"}
    with pytest.raises(SceneError, match=r"media\.enamel\.material = 'enamle'"):
        scene_from_dict(d)


# ---------------------------------------------------------------------------------------
# Bad input: every case names the key path


def _set(d, path, value):
    keys = path.split("/")
    for k in keys[:-1]:
        d = d[int(k)] if isinstance(d, list) else d[k]
    last = keys[-1]
    if value is DELETE:
        del d[last]
    elif isinstance(d, list):
        d[int(last)] = value
    else:
        d[last] = value


DELETE = object()

BAD = [
    ("shapes/1/raduis", 2.0, r"shapes\[1\]\.raduis: unknown key; did you mean 'radius'"),
    ("camera/look", [0, 0, 0], r"camera\.look: unknown key; did you mean 'look_at'"),
    ("light", [], r"light: unknown key; did you mean 'lights'"),
    ("shapes/1/radius", "big", r"shapes\[1\]\.radius = 'big': must be a number"),
    ("shapes/1/radius", -1.0, r"shapes\[1\]\.radius = -1\.0: out of range: allowed \(0, inf\)"),
    ("shapes/2/height", 0, r"shapes\[2\]\.height = 0: out of range"),
    ("shapes/3/max", [-7, 1, 2], r"shapes\[3\]\.max\[0\] = -7\.0: must exceed min\[0\]"),
    ("shapes/1/center", [0, 0], r"shapes\[1\]\.center = \[0, 0\]: must be a list of 3"),
    ("shapes/1/type", "sphre", r"shapes\[1\]\.type = 'sphre': did you mean 'sphere'"),
    ("shapes/2/inside", "enamle",
     r"shapes\[2\]\.inside = 'enamle': no medium of that name is defined; did you mean "
     r"'enamel'"),
    ("shapes/2/outside", "water", r"shapes\[2\]\.outside = 'water': no medium"),
    ("shapes/1/surface", "whit", r"shapes\[1\]\.surface = 'whit': no surface.*'white'"),
    ("shapes/0/inside", "enamel", r"shapes\[0\]: give either surface .* not both"),
    ("shapes/0/surface", DELETE, r"shapes\[0\]: missing boundary"),
    ("lights", [], r"lights: the scene has no lights"),
    ("lights/0/intensity", -5.0, r"lights\[0\]\.intensity = -5\.0: out of range"),
    ("lights/0/type", "area", r"lights\[0\]\.type = 'area': .*allowed: quad, disc, point"),
    ("media/enamel/g", 1.0, r"media\.enamel\.g = 1\.0: out of range: allowed \(-1, 1\)"),
    ("media/enamel/n", 0.9, r"media\.enamel\.n = 0\.9: out of range: allowed \[1, inf\)"),
    ("media/enamel/mua", {"wavelengths_nm": [400, 700], "values": [0.1, -0.2]},
     r"media\.enamel\.mua\.values\[1\] = -0\.2: out of range"),
    ("media/enamel/mus", {"wavelengths_nm": [500, 700], "values": [1, 2]},
     r"media\.enamel\.mus: the table covers 500-700 nm, not the band 450 nm"),
    ("media/enamel/fd", True, r"media\.enamel\.fd = True: must be a number"),
    ("camera/fov_deg", 180, r"camera\.fov_deg = 180: out of range"),
    ("camera/resolution", [64, "48"], r"camera\.resolution\[1\] = '48': must be an integer"),
    ("camera/up", [0, 3, -1], r"camera\.up = .*parallel"),
    ("camera/position", [0.5, 0, 3.5],
     r"camera\.position = .*inside the opaque shapes\[1\] \(sphere\)"),
    ("camera/position", [-5, 0, 1], r"camera\.position = .*inside the opaque shapes\[3\] \(box\)"),
    ("camera/position", [5, 0, 1], r"camera\.medium = 'air': the camera is inside shapes\[2\]"),
    ("camera/medium", "vacuum", r"camera\.medium = 'vacuum': no medium"),
    ("surfaces/white/reflectance", 1.5, r"surfaces\.white\.reflectance = 1\.5: out of range"),
    ("surfaces/white/type", "lambert", r"surfaces\.white\.type = 'lambert': did you mean"),
    ("render/integrator", "vmp", r"render\.integrator = 'vmp': did you mean 'vpm'"),
    ("render/bands", [450, 900], r"render\.bands\[1\] = 900: out of range"),
    ("render/spp", 0, r"render\.spp = 0: out of range: allowed integer >= 1"),
    ("shapes/1/transform", {"scale": -2}, r"shapes\[1\]\.transform\.scale = -2: out of range"),
    ("shapes/1/transform", {"rotate": {"axis": [0, 0, 0], "angle_deg": 3}},
     r"shapes\[1\]\.transform\.rotate\.axis = .*non-zero"),
    ("shapes/1/transform", {"shift": [1, 2, 3]},
     r"shapes\[1\]\.transform\.shift: unknown key"),
    ("shapes/0/inside", "enamel", r"shapes\[0\]"),
    ("scene", {"units": "cm"}, r"scene\.units = 'cm': .*allowed: mm"),
]


@pytest.mark.parametrize("path,value,message", BAD, ids=[f"{p}={v!r}"[:40] for p, v, _ in BAD])
def test_bad_input_names_the_key_path(path, value, message):
    d = base()
    d.setdefault("render", {})
    _set(d, path, value)
    with pytest.raises(SceneError, match=message):
        scene_from_dict(d)


def test_camera_inside_transformed_shapes():
    d = base()
    d["shapes"][1]["transform"] = {"scale": 3.0, "translate": [0, -20, 0]}
    d["camera"]["position"] = [0, -20, 12]  # the sphere is now radius 6 centred at z = 9
    with pytest.raises(SceneError, match=r"inside the opaque shapes\[1\]"):
        scene_from_dict(d)
    d["camera"]["position"] = [0, -20, 16]
    scene_from_dict(d)
    # Nested: a camera in the enamel cylinder is fine once camera.medium says so.
    d = base()
    d["camera"]["position"] = [5, 0, 1]
    d["camera"]["medium"] = "enamel"
    assert scene_from_dict(d).resolve(540)["ambient_medium"] == 1


def test_missing_mesh_file_and_bad_meshes(tmp_path):
    d = base()
    d["shapes"].append({"type": "mesh", "file": "nope.obj", "surface": "white"})
    with pytest.raises(SceneError, match=r"shapes\[4\]\.file = 'nope\.obj': file not found"):
        scene_from_dict(d, base_dir=tmp_path)
    # Open mesh (a cube without its last face) as a dielectric boundary.
    (tmp_path / "open.obj").write_text("\n".join(CUBE_OBJ.splitlines()[:-2]) + "\n")
    d["shapes"][4] = {"type": "mesh", "file": "open.obj", "inside": "enamel"}
    with pytest.raises(SceneError, match=r"shapes\[4\]: the mesh is open"):
        scene_from_dict(d, base_dir=tmp_path)
    d["shapes"][4]["surface"] = "white"  # open but opaque: allowed
    d["shapes"][4].pop("inside")
    scene_from_dict(d, base_dir=tmp_path)
    # One face flipped: closed but inconsistently oriented.
    lines = CUBE_OBJ.splitlines()
    lines[-1] = "f 4 8 5"
    (tmp_path / "flip.obj").write_text("\n".join(lines) + "\n")
    d["shapes"][4] = {"type": "mesh", "file": "flip.obj", "inside": "enamel"}
    with pytest.raises(SceneError, match=r"shapes\[4\]: .*inconsistently oriented"):
        scene_from_dict(d, base_dir=tmp_path)
    d["shapes"][4] = {"type": "mesh", "positions": [[0, 0, 0]], "triangles": [[0, 1, 2]],
                      "surface": "white"}
    with pytest.raises(SceneError, match=r"shapes\[4\]\.triangles\[0\] .*out of range"):
        scene_from_dict(d)


def test_toml_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_scene(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[camera\nposition = 1\n")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(bad)


# ---------------------------------------------------------------------------------------
# Transforms and meshes


def test_transform_order_scale_rotate_translate():
    m = tf.compose({"scale": [2.0, 1.0, 1.0],
                    "rotate": [{"axis": [0, 0, 1], "angle_deg": 90.0}],
                    "translate": [10.0, 0.0, 0.0]})
    # (1, 0, 0) -> scaled (2, 0, 0) -> rotated (0, 2, 0) -> translated (10, 2, 0)
    assert np.allclose(tf.apply_point(m, [1, 0, 0]), [10, 2, 0])
    assert np.allclose(tf.apply_vector(m, [0, 1, 0]), [-1, 0, 0])
    two = tf.compose({"rotate": [{"axis": [1, 0, 0], "angle_deg": 90},
                                 {"axis": [0, 0, 1], "angle_deg": 90}]})
    # y -> z (about x) -> z (about z leaves it)
    assert np.allclose(tf.apply_vector(two, [0, 1, 0]), [0, 0, 1])
    assert np.allclose(tf.compose(None), np.eye(4))


def test_transform_reaches_the_contract():
    d = base()
    d["shapes"][0]["transform"] = {"translate": [0, 0, -1],
                                   "rotate": {"axis": [0, 0, 1], "angle_deg": 90}}
    d["shapes"][1]["transform"] = {"matrix": [[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0],
                                              [0, 0, 0, 1]]}
    out = scene_from_dict(d).resolve(540)
    quad = out["shapes"][0]
    assert np.allclose(quad["corner"], [10, -10, -1])  # (-10,-10,0) rotated 90 deg, moved
    assert np.allclose(quad["u"], [0, 20, 0]) and np.allclose(quad["v"], [-20, 0, 0])
    assert np.allclose(out["shapes"][1]["transform"][0], [1, 0, 0, 2])
    assert np.allclose(out["shapes"][2]["transform"], np.eye(4))


def test_obj_and_ply_loading(tmp_path):
    s = scene_from_dict(every_type(tmp_path), base_dir=tmp_path)
    out = s.resolve(540)
    cube, tetra, inline = out["shapes"][4], out["shapes"][5], out["shapes"][6]
    pos = np.asarray(cube["positions"])
    assert pos.shape == (8, 3) and len(cube["triangles"]) == 12
    assert np.allclose(sorted(map(tuple, pos)), sorted(
        (x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)))
    assert np.allclose(np.asarray(cube["transform"])[:3, :3], 2 * np.eye(3))
    assert len(tetra["positions"]) == 4 and len(tetra["triangles"]) == 4
    assert inline["uvs"] == [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]
    # The cube's enclosed volume from its triangles is +1 (outward-facing) [mm^3].
    tri = pos[np.asarray(cube["triangles"])]
    vol = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
    assert vol == pytest.approx(1.0)


def test_inward_mesh_is_flipped_outward(tmp_path):
    lines = [ln if not ln.startswith("f ") else "f " + " ".join(ln.split()[1:][::-1])
             for ln in CUBE_OBJ.splitlines()]
    (tmp_path / "inward.obj").write_text("\n".join(lines) + "\n")
    d = base()
    d["shapes"].append({"type": "mesh", "file": "inward.obj", "inside": "enamel",
                        "transform": {"translate": [0, 10, 0]}})
    mesh = scene_from_dict(d, base_dir=tmp_path).resolve(540)["shapes"][4]
    pos, tri = np.asarray(mesh["positions"]), np.asarray(mesh["triangles"])
    t = pos[tri]
    assert np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum() / 6 == \
        pytest.approx(1.0)


# ---------------------------------------------------------------------------------------
# dentalux.render and the CLI (with the fake core when the real one is missing)


def test_render_api_with_fake_core(fake_core):
    d = cornell_box(resolution=(6, 4))
    result = dentalux.render(d, spp=2, photons=100, bands=[605, 450], seed=7,
                             volume_photons=5, k=8, radius=1.5)
    assert result.radiance.shape == (4, 6, 2) and result.radiance.dtype == np.float32
    assert result.bands == [605.0, 450.0]
    # band b of the stack is the call made for that wavelength (seeded by its nm)
    assert np.all(result.radiance[..., 0] == 605) and np.all(result.radiance[..., 1] == 450)
    scene0, settings0 = fake_core.calls[0]
    assert settings0 == {"integrator": "pm", "spp": 2, "photons": 100, "volume_photons": 5,
                         "volume_stored": 0, "aim": 0.0, "k": 8, "surface_k": None,
                         "radius": 1.5,
                         "surface_radius": None, "step": None, "seed": 7, "band": 605,
                         "threads": None, "max_depth": 64, "passes": 1, "alpha": 0.7,
                         "final_gather": False, "kernel_layer": 0.3, "kernel_clip": True,
                         "volume_estimator": "points", "spectral_photons": False,
                         "hero_camera": False}
    # red wall at 605 nm from its reflectance table
    assert scene0["surfaces"][1]["reflectance"] == pytest.approx(np.interp(
        605, [400, 550, 580, 600, 700], [0.05, 0.05, 0.2, 0.6, 0.65]))
    assert result.stats["photons_emitted_total"] == 200
    res = dentalux.render(d, bands=[540], resolution="3x2", integrator="path")
    assert res.radiance.shape == (2, 3, 1) and fake_core.calls[-1][1]["integrator"] == "path"


def test_render_api_bad_arguments(fake_core):
    d = cornell_box(resolution=(4, 4))
    with pytest.raises(ValueError, match=r"radious: unknown render option; did you mean "
                                         r"'radius'"):
        dentalux.render(d, radious=1.0)
    with pytest.raises(ValueError, match=r"integrator = 'vmp': did you mean 'vpm'"):
        dentalux.render(d, integrator="vmp")
    with pytest.raises(ValueError, match=r"spp = 0: out of range"):
        dentalux.render(d, spp=0)
    with pytest.raises(ValueError, match=r"kernel_layer = 1.5: out of range"):
        dentalux.render(d, kernel_layer=1.5)
    with pytest.raises(ValueError, match=r"aim = 1: out of range"):
        dentalux.render(d, aim=1)
    with pytest.raises(ValueError, match=r"kernel_clip = 'yes'"):
        dentalux.render(d, kernel_clip="yes")
    with pytest.raises(ValueError, match=r"volume_stored = -5: out of range"):
        dentalux.render(d, volume_stored=-5)
    with pytest.raises(ValueError, match=r"bands\[0\] = 100: out of range"):
        dentalux.render(d, bands=[100])
    with pytest.raises(ValueError, match=r"bands must be distinct"):
        dentalux.render(d, bands=[540, 540.2])
    assert fake_core.calls == []


def test_cli_render_writes_outputs(fake_core, tmp_path, capsys):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        main(["render", str(CORNELL), "--out", str(out), "--spp", "1", "--photons", "10",
              "--bands", "450,540,605", "--resolution", "8x6", "--seed", "3", "--json"])
    assert exc.value.code == 0
    summary = json.loads(capsys.readouterr().out)
    radiance = np.load(out / "radiance.npy")
    assert radiance.shape == (6, 8, 3) and radiance.dtype == np.float32
    on_disk = json.loads((out / "render.json").read_text())
    assert on_disk["scene_hash"] == summary["scene_hash"] == load_scene(CORNELL).hash
    assert on_disk["bands_nm"] == [450.0, 540.0, 605.0]
    assert on_disk["settings"]["seed"] == 3 and on_disk["settings"]["spp"] == 1
    assert on_disk["photons"]["photons_emitted"] == [10, 10, 10]
    assert on_disk["peak_memory_bytes"] > 1e6 and on_disk["timings"]["total_s"] > 0
    for wl in (450, 540, 605):
        assert (out / f"band_{wl}nm.png").is_file()
    calls = fake_core.calls
    assert [c[1]["band"] for c in calls] == [450, 540, 605]
    assert all(c[0]["camera"]["width"] == 8 for c in calls)


def test_cli_render_kernel_clip_flag(fake_core, tmp_path):
    for flag, value in (([], True), (["--no-kernel-clip"], False), (["--kernel-clip"], True)):
        with pytest.raises(SystemExit) as exc:
            main(["render", str(CORNELL), "--out", str(tmp_path / "o"), "--spp", "1",
                  "--photons", "10", "--bands", "540", "--resolution", "4x3", "--overwrite",
                  *flag])
        assert exc.value.code == 0
        assert fake_core.calls[-1][1]["kernel_clip"] is value


def test_cli_render_surface_k_reaches_the_settings(fake_core, tmp_path):
    for flag, value in (([], None), (["--surface-k", "50"], 50)):
        with pytest.raises(SystemExit) as exc:
            main(["render", str(CORNELL), "--out", str(tmp_path / "o"), "--spp", "1",
                  "--photons", "10", "--bands", "540", "--resolution", "4x3", "--overwrite",
                  *flag])
        assert exc.value.code == 0
        assert fake_core.calls[-1][1]["surface_k"] == value


@pytest.mark.parametrize("args,message", [
    (["--bands", "450,x"], "--bands = '450,x'"),
    (["--resolution", "64by48"], "--resolution = '64by48'"),
    (["--integrator", "vmp"], "did you mean 'vpm'"),
    (["--spp", "0"], "spp = 0: out of range"),
    (["--kernel-layer", "2"], "kernel_layer = 2"),
    (["--aim", "-0.1"], "aim = -0.1"),
    (["--volume-stored", "-1"], "volume_stored = -1"),
    (["--surface-k", "0"], "surface_k = 0"),
])
def test_cli_render_bad_options_exit_2(fake_core, tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        main(["render", str(CORNELL), "--out", str(tmp_path / "o"), *args])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "o" / "radiance.npy").exists()


def test_cli_scene_check(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["scene", "check", str(CORNELL), "--json"])
    assert exc.value.code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["shapes"] == ["quad"] * 5 + ["box", "sphere"]
    with pytest.raises(SystemExit) as exc:
        main(["scene", "check", str(CORNELL), "--dump", "--bands", "540"])
    dumped = json.loads(capsys.readouterr().out)
    check_contract(dumped["resolved"]["540"])
    bad = tmp_path / "bad.toml"
    text = CORNELL.read_text().replace("radius = 100.0", "radius = -100.0")
    bad.write_text(text)
    with pytest.raises(SystemExit) as exc:
        main(["scene", "check", str(bad)])
    assert exc.value.code == 2
    assert "error: shapes[6].radius = -100.0: out of range" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["scene", "check", str(tmp_path / "missing.toml")])
    assert exc.value.code == 2


def test_render_without_core_is_a_clear_error(monkeypatch):
    monkeypatch.delattr(_core, "render_bands", raising=False)
    with pytest.raises(RuntimeError, match="render_bands"):
        dentalux.render(cornell_box(resolution=(2, 2)), bands=[540])


def test_dict_input_is_not_modified(tmp_path):
    for d in (cornell_box(), discs(), every_type(tmp_path), base()):
        before = copy.deepcopy(d)
        s = scene_from_dict(d, base_dir=tmp_path)
        s.resolve(540)
        assert d == before
        # and the scene does not share mutable parts with the input
        json.loads(s.to_json(540))
        for shape in d["shapes"]:
            for v in shape.values():
                if isinstance(v, list):
                    v.append("x")
        d["lights"][0]["type"] = "nonsense"
        assert json.loads(s.to_json(540)) == json.loads(scene_from_dict(before,
                                                                         base_dir=tmp_path)
                                                        .to_json(540))


# ---------------------------------------------------------------------------------------
# Real renders through the Rust core (once dentalux._core.render_bands exists)

needs_core = pytest.mark.skipif(not HAS_CORE, reason="dentalux._core.render_bands not built")


@needs_core
def test_cornell_render_is_deterministic():
    """Same seed, same image, for 1 and 2 threads; another seed, another image."""
    kw = dict(spp=2, photons=4000, bands=[540.0], resolution=(20, 20), progress=False)
    a = dentalux.render(CORNELL, seed=5, threads=1, **kw)
    b = dentalux.render(CORNELL, seed=5, threads=2, **kw)
    c = dentalux.render(CORNELL, seed=6, threads=2, **kw)
    assert a.radiance.shape == (20, 20, 1) and a.radiance.dtype == np.float32
    assert np.all(np.isfinite(a.radiance)) and a.radiance.min() >= 0
    assert a.radiance.mean() > 0
    assert np.array_equal(a.radiance, b.radiance)
    assert not np.array_equal(a.radiance, c.radiance)
    assert a.stats["bands"][0]["photons_emitted"] == 4000


def _plane_under_point_light(size: int, fov: float, height: float, distance: float,
                             intensity: float, rho: float) -> dict:
    return {
        "camera": {"position": [0, 0, distance], "look_at": [0, 0, 0], "up": [0, 1, 0],
                   "fov_deg": fov, "resolution": [size, size]},
        "surfaces": {"grey": {"reflectance": rho}},
        "shapes": [{"type": "quad", "corner": [-1000, -1000, 0], "u": [2000, 0, 0],
                    "v": [0, 2000, 0], "surface": "grey"}],
        "lights": [{"type": "point", "position": [0, 0, height], "intensity": intensity,
                    "spectrum": "flat"}],
    }


@needs_core
def test_plane_under_point_light_matches_closed_form():
    """A Lambertian plane (rho) under a point light (I, height h): per pixel
    L = rho/pi * I h / r^3 [mm units], averaged over the pixel's footprint. The tolerance is
    5 standard errors of the sub-pixel jitter (spp samples) plus 0.2 %."""
    size, fov, h, dist, intensity, rho, spp = 16, 40.0, 50.0, 100.0, 1000.0, 0.5, 16
    d = _plane_under_point_light(size, fov, h, dist, intensity, rho)
    img = dentalux.render(d, integrator="pm", spp=spp, photons=1000, bands=[550.0], seed=3,
                          progress=False).radiance[:, :, 0].astype(float)
    # Closed form on a 16 x 16 sub-grid of every pixel (symmetric about the light, so the
    # image's row/column orientation does not matter).
    sub = 16
    t = math.tan(math.radians(fov) / 2)
    s = (np.arange(size * sub) + 0.5) / (size * sub)
    ndc = (2 * s - 1) * t * dist
    x, y = np.meshgrid(ndc, -ndc)
    r = np.sqrt(x**2 + y**2 + h**2)
    fine = rho / math.pi * intensity * h / r**3
    blocks = fine.reshape(size, sub, size, sub)
    mean = blocks.mean(axis=(1, 3))
    sd = blocks.std(axis=(1, 3))
    tol = 5 * sd / math.sqrt(spp) + 0.002 * mean
    assert np.all(np.abs(img - mean) <= tol), np.max(np.abs(img - mean) / mean)
    assert img.mean() == pytest.approx(mean.mean(), rel=0.002)


@needs_core
def test_discs_scene_renders_with_vpm():
    lib = material_library()
    material = "biomaterial-table1"
    if lib is None or material not in lib.names():
        material = "enamel"
    d = discs(material=material, resolution=(16, 12))
    res = dentalux.render(d, integrator="vpm", spp=1, photons=2000, volume_photons=5000,
                          bands=[540.0], seed=1, progress=False)
    assert res.radiance.shape == (12, 16, 1)
    assert np.all(np.isfinite(res.radiance)) and res.radiance.min() >= 0
    assert res.radiance.mean() > 0


def test_discs_scene_renders_with_volpath_nee():
    # the planar next-event variant of the reference path tracer runs through the whole
    # pipeline (its physics is checked in crates/dentalux-core/tests/volume_transport.rs)
    d = discs(material="enamel", resolution=(16, 12))
    res = dentalux.render(d, integrator="volpath-nee", spp=4, bands=[540.0], seed=1,
                          progress=False)
    assert np.all(np.isfinite(res.radiance)) and res.radiance.min() >= 0
    assert res.radiance.mean() > 0
    assert res.stats["bands"][0]["integrator"] == "volpath-nee"


def test_image_texture_from_file(tmp_path):
    from PIL import Image

    Image.fromarray(np.array([[0, 51, 255]], dtype=np.uint8), mode="L").save(tmp_path / "t.png")
    d = base()
    d["surfaces"]["tex"] = {"type": "image", "file": "t.png", "scale": 0.5, "size": 4}
    d["shapes"][3]["surface"] = "tex"
    out = scene_from_dict(d, base_dir=tmp_path).resolve(540)
    tex = out["surfaces"][1]
    assert (tex["width"], tex["height"], tex["mapping"]) == (3, 1, "uv")
    assert tex["data"] == pytest.approx([0.0, 0.1, 0.5]) and tex["size"] == 4.0
    check_contract(out)
    d["surfaces"]["tex"]["file"] = "none.png"
    with pytest.raises(SceneError, match=r"surfaces\.tex\.file = 'none\.png': file not found"):
        scene_from_dict(d, base_dir=tmp_path)


def test_cli_render_hands_equal_energy_radiance_to_colour(fake_core, tmp_path, monkeypatch,
                                                          capsys):
    """write_images applies the illuminant itself, so D65-lit radiance is divided by the
    D65 relative spectrum (CIE: 1.17008 at 450 nm, 1 at 560 nm) and white = the light's
    radiance scale (15 in cornell.toml)."""
    from dentalux import color

    seen = {}

    def fake_write_images(radiance, wavelengths_nm, out_dir, illuminant="D65", regions=None,
                          exposure=None, white=1.0, region_extra=None):
        seen.update(radiance=np.array(radiance), bands=list(wavelengths_nm),
                    illuminant=illuminant, white=white)
        return {"illuminant": illuminant}

    monkeypatch.setattr(color, "write_images", fake_write_images)
    with pytest.raises(SystemExit) as exc:
        main(["render", str(CORNELL), "--out", str(tmp_path), "--bands", "450,560",
              "--resolution", "2x2", "--json"])
    assert exc.value.code == 0
    assert seen["illuminant"] == "D65" and seen["white"] == 15.0
    # the fake core fills band b with its nm value
    assert seen["radiance"][0, 0, 0] == pytest.approx(450 / 1.17008, rel=1e-5)
    assert seen["radiance"][0, 0, 1] == pytest.approx(560.0)
    assert json.loads(capsys.readouterr().out)["colour"] == {"illuminant": "D65"}


def test_cli_volume_options_reach_the_core(fake_core, tmp_path, capsys):
    """Issue 5's flags: --integrator, --photons, --volume-photons, --k, --radius, --step."""
    with pytest.raises(SystemExit) as exc:
        main(["render", str(CORNELL), "--out", str(tmp_path), "--integrator", "vpm-full",
              "--photons", "123", "--volume-photons", "456", "--k", "16", "--radius", "0.5",
              "--step", "0.1", "--threads", "2", "--bands", "540", "--resolution", "4x3",
              "--json"])
    assert exc.value.code == 0
    settings = fake_core.calls[0][1]
    assert (settings["integrator"], settings["photons"], settings["volume_photons"],
            settings["k"], settings["radius"], settings["step"], settings["threads"]) == \
        ("vpm-full", 123, 456, 16, 0.5, 0.1, 2)
    assert json.loads(capsys.readouterr().out)["settings"]["integrator"] == "vpm-full"


def test_render_with_progress_bar(fake_core):
    res = dentalux.render(cornell_box(resolution=(3, 2)), bands=[450, 540], progress=True)
    assert res.radiance.shape == (2, 3, 2) and len(fake_core.calls) == 2


def test_nested_media_must_be_declared_consistently():
    """A dentin core inside an enamel shell: outside = 'enamel' is required."""
    d = base()
    d["media"]["dentin"] = {"mua": 0.3, "mus": 20.0, "g": 0.9, "n": 1.5}
    d["shapes"] = [
        {"type": "sphere", "center": [0, 0, 5], "radius": 3.0, "inside": "enamel"},
        {"type": "cylinder", "center": [0, 0, 4], "radius": 1.0, "height": 2.0,
         "inside": "dentin", "outside": "air"},
    ]
    with pytest.raises(SceneError, match=r"shapes\[1\]\.outside = 'air': shapes\[1\] lies "
                                         r"inside shapes\[0\], whose inside medium is 'enamel'"):
        scene_from_dict(d)
    d["shapes"][1]["outside"] = "enamel"
    media = [m["name"] for m in scene_from_dict(d).resolve(540)["media"]]
    assert media == ["air", "enamel", "dentin"]
    # Moved so that it pokes out of the sphere: the boundaries cross (issue 18, item 10).
    d["shapes"][1].update(center=[0, 0, 7], outside="air")
    with pytest.raises(SceneError, match=r"shapes\[0\] and shapes\[1\].*overlap in part"):
        scene_from_dict(d)
    # Moved clear of the sphere: no constraint.
    d["shapes"][1].update(center=[0, 0, 9])
    scene_from_dict(d)


def test_inline_mesh_from_numpy_arrays():
    """The dict API takes numpy arrays; a bad entry is still named precisely."""
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    tri = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    d = base()
    d["shapes"].append({"type": "mesh", "positions": pos, "triangles": tri,
                        "inside": "enamel", "transform": {"translate": [0, 10, 0]}})
    s = scene_from_dict(d)
    mesh = s.resolve(540)["shapes"][4]
    assert mesh["positions"] == pos.tolist() and mesh["triangles"] == tri.tolist()
    check_contract(json.loads(s.to_json(540)))
    assert len(s.hash) == 64
    d["shapes"][4]["positions"] = [[0, 0, 0], [1, 0, 0], [0, "1", 0], [0, 0, 1]]
    with pytest.raises(SceneError, match=r"shapes\[4\]\.positions\[2\]\[1\] = '1': must be a "
                                         r"number"):
        scene_from_dict(d)
    d["shapes"][4]["positions"] = pos
    d["shapes"][4]["triangles"] = tri.astype(float)
    with pytest.raises(SceneError, match=r"shapes\[4\]\.triangles\[0\]\[0\] = 0\.0: must be an "
                                         r"integer"):
        scene_from_dict(d)


def test_camera_inside_a_closed_mesh(tmp_path):
    """Parity ray test: inside the (scaled, moved) cube mesh is refused when it is opaque;
    an open mesh has no inside."""
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    d = base()
    d["shapes"].append({"type": "mesh", "file": "cube.obj", "surface": "white",
                        "transform": {"scale": 4.0, "translate": [-2, -32, 8]}})
    d["camera"]["position"] = [0.5, -29.5, 10.5]  # in [-2, 2] x [-32, -28] x [8, 12]
    with pytest.raises(SceneError, match=r"camera\.position = .*inside the opaque shapes\[4\] "
                                         r"\(mesh\)"):
        scene_from_dict(d, base_dir=tmp_path)
    d["camera"]["position"] = [0.5, -33, 10.5]  # just outside
    scene_from_dict(d, base_dir=tmp_path)
    d["camera"]["position"] = [0.5, -29.5, 10.5]
    (tmp_path / "open.obj").write_text("\n".join(CUBE_OBJ.splitlines()[:-2]) + "\n")
    d["shapes"][4]["file"] = "open.obj"
    scene_from_dict(d, base_dir=tmp_path)


def test_point_inside_mesh_matches_the_sphere_it_approximates(np_rng):
    import trimesh
    from dentalux.scene.meshes import MeshData, point_inside

    ico = trimesh.creation.icosphere(subdivisions=3, radius=10.0)
    data = MeshData(np.asarray(ico.vertices), np.asarray(ico.faces))
    pts = np_rng.uniform(-15, 15, size=(300, 3))
    r = np.linalg.norm(pts, axis=1)
    keep = np.abs(r - 10.0) > 0.5  # the mesh deviates from the sphere by < 0.1 mm
    got = np.array([point_inside(data, p) for p in pts[keep]])
    assert np.array_equal(got, r[keep] < 10.0)
