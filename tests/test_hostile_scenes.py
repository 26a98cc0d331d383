"""Issue 18, part 3, items 10 and 11: hostile scene files, and what a scene may read.

Every refusal is a SceneError (a ValueError) that names the key and the file as the scene
gives it, never the resolved absolute path."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from dentalux import _core
from dentalux.cli import main
from dentalux.scene.load import load_scene, read_toml, scene_from_dict
from dentalux.scene.schema import SceneError
from dentalux.testing import bands_from_band

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell.toml"

CUBE_OBJ = "".join(f"v {x} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1)) + """\
f 1 3 4
f 1 4 2
f 5 6 8
f 5 8 7
f 1 2 6
f 1 6 5
f 3 7 8
f 3 8 4
f 1 5 7
f 1 7 3
f 2 4 8
f 2 8 6
"""


def png(path: Path, size=(4, 4)) -> Path:
    from PIL import Image

    Image.new("L", size, 128).save(path)
    return path


def with_mesh(name: str) -> dict:
    d = read_toml(CORNELL)
    d["shapes"].append({"type": "mesh", "file": name, "surface": "white"})
    return d


def with_image(name: str) -> dict:
    d = read_toml(CORNELL)
    d["surfaces"]["tex"] = {"type": "image", "file": name}
    return d


@pytest.fixture
def folder(tmp_path):
    scene = tmp_path / "scene"
    scene.mkdir()
    (scene / "cube.obj").write_text(CUBE_OBJ)
    png(scene / "t.png")
    (tmp_path / "outside.obj").write_text(CUBE_OBJ)
    png(tmp_path / "outside.png")
    return scene


def refused(d, base, match, **kw):
    with pytest.raises(SceneError, match=match) as exc:
        scene_from_dict(d, base_dir=base, **kw)
    assert str(base.resolve()) not in str(exc.value)
    return str(exc.value)


# ---------------------------------------------------------------------------------------
# 11. What a scene may read


def test_files_inside_the_folder_are_read(folder):
    sc = scene_from_dict(with_mesh("cube.obj"), base_dir=folder)
    read = sc.files_read()
    assert [r["file"] for r in read] == ["cube.obj"] and len(read[0]["sha256"]) == 64
    sc = scene_from_dict(with_image("t.png"), base_dir=folder)
    assert [r["key"] for r in sc.files_read()] == ["surfaces.tex.file"]


@pytest.mark.parametrize("name", ["../outside.obj", "ABS"])
def test_mesh_outside_the_folder_needs_permission(folder, name):
    if name == "ABS":
        name = str(folder.parent / "outside.obj")
    msg = refused(with_mesh(name), folder, r"shapes\[\d+\]\.file = .*--allow-outside-paths")
    assert ("absolute" in msg) == name.startswith("/")
    sc = scene_from_dict(with_mesh(name), base_dir=folder, allow_outside_paths=True)
    assert sc.files_read()[0]["file"] == name


def test_symlink_out_of_the_folder(folder):
    (folder / "link.obj").symlink_to(folder.parent / "outside.obj")
    refused(with_mesh("link.obj"), folder, r"'link\.obj': leaves the scene's folder")
    # a link inside the folder to a file without a mesh suffix (the probe's /etc/hostname)
    (folder.parent / "hostname").write_text("box\n")
    (folder / "host.obj").symlink_to(folder.parent / "hostname")
    refused(with_mesh("host.obj"), folder, "leaves the scene's folder")
    refused(with_mesh("host.obj"), folder, "without a mesh suffix", allow_outside_paths=True)


def test_image_files_need_suffix_and_signature(folder):
    (folder / "shadow").write_text("root:x:0:0\n")
    refused(with_image("shadow"), folder, r"surfaces\.tex\.file = 'shadow': unsupported image")
    (folder / "passwd.png").write_text("root:x:0:0\n")
    refused(with_image("passwd.png"), folder, "not a PNG file")
    refused(with_image("/proc/self/cmdline"), folder, "unsupported image file",
            allow_outside_paths=True)
    refused(with_image("/etc/passwd.png"), folder, "absolute path")


def test_not_a_regular_file(folder):
    os.mkfifo(folder / "fifo.obj")
    (folder / "dir.png").mkdir()
    refused(with_mesh("fifo.obj"), folder, "not a regular file")
    refused(with_image("dir.png"), folder, "not a regular file")


def test_missing_file_does_not_reveal_paths(folder):
    msg = refused(with_mesh("nope.obj"), folder, r"'nope\.obj': file not found")
    assert "/" not in msg.split("'nope.obj'")[1]


def test_render_json_lists_the_files_read(folder, capsys, monkeypatch, tmp_path):
    def fake(scene_json, settings_json, progress=None):
        cam = json.loads(scene_json)["camera"]
        return np.ones((cam["height"], cam["width"]), np.float32), {}

    monkeypatch.setattr(_core, "render_bands", bands_from_band(fake), raising=False)
    import tomli_w

    d = with_mesh("cube.obj")
    (folder / "s.toml").write_text(tomli_w.dumps(d))
    with pytest.raises(SystemExit) as exc:
        main(["render", str(folder / "s.toml"), "--out", str(tmp_path / "o"), "--spp", "1",
              "--bands", "540", "--resolution", "4x3"])
    assert exc.value.code == 0
    doc = json.loads((tmp_path / "o" / "render.json").read_text())
    assert [r["file"] for r in doc["files_read"]] == ["cube.obj"]
    d["shapes"][-1]["file"] = "../outside.obj"
    (folder / "s.toml").write_text(tomli_w.dumps(d))
    argv = ["render", str(folder / "s.toml"), "--out", str(tmp_path / "p"), "--spp", "1",
            "--bands", "540", "--resolution", "4x3"]
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2 and "--allow-outside-paths" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main([*argv, "--allow-outside-paths"])
    assert exc.value.code == 0


# ---------------------------------------------------------------------------------------
# 10. Hostile scenes


def test_deeply_nested_toml(tmp_path):
    f = tmp_path / "deep.toml"
    f.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(SceneError, match="nested too deeply"):
        load_scene(f)
    with pytest.raises(SystemExit) as exc:
        main(["scene", "check", str(f)])
    assert exc.value.code == 2


def test_garbage_obj(folder):
    (folder / "garbage.obj").write_bytes(bytes(range(256)) * 64)
    refused(with_mesh("garbage.obj"), folder, r"'garbage\.obj': not an OBJ file")
    (folder / "latin.obj").write_bytes(b"v 0 0 0\n# \xe9\xff\xfe caf\xe9\n" * 10)
    refused(with_mesh("latin.obj"), folder, "not UTF-8")
    (folder / "fake.ply").write_text("not a ply\n")
    refused(with_mesh("fake.ply"), folder, "not a PLY file")


def test_nan_vertex(folder):
    (folder / "nan.obj").write_text(CUBE_OBJ.replace("v 0 0 0", "v nan 0 0", 1))
    refused(with_mesh("nan.obj"), folder, r"'nan\.obj': vertex 1 is not finite")


def _glass(*shapes, lights=None) -> dict:
    d = read_toml(CORNELL)
    d["media"] = {"glass": {"mua": 0.0, "mus": 0.0, "n": 1.5},
                  "resin": {"mua": 0.01, "mus": 1.0, "n": 1.5}}
    d["shapes"] = d["shapes"][:1] + list(shapes)
    if lights is not None:
        d["lights"] = lights
    return d


def _cyl(x, radius=50.0, height=20.0, inside="glass", outside="air"):
    return {"type": "cylinder", "center": [x, 100.0, 200.0], "axis": [0.0, 1.0, 0.0],
            "radius": radius, "height": height, "inside": inside, "outside": outside}


def test_crossing_dielectric_boundaries(tmp_path):
    with pytest.raises(SceneError, match=r"shapes\[1\] and shapes\[2\].*overlap in part"):
        scene_from_dict(_glass(_cyl(200.0), _cyl(260.0, inside="resin")), base_dir=tmp_path)
    # apart, touching along a line, and nested are all fine
    scene_from_dict(_glass(_cyl(200.0), _cyl(320.0, inside="resin")), base_dir=tmp_path)
    scene_from_dict(_glass(_cyl(200.0), _cyl(300.0, inside="resin")), base_dir=tmp_path)
    scene_from_dict(_glass(_cyl(200.0), _cyl(200.0, radius=10, height=5, inside="resin",
                                             outside="glass")), base_dir=tmp_path)
    stacked = _cyl(200.0, inside="resin")
    stacked["center"] = [200.0, 120.0, 200.0]  # standing on the first disc's top face
    scene_from_dict(_glass(_cyl(200.0), stacked), base_dir=tmp_path)


def test_point_light_inside_a_disc(tmp_path):
    light = {"type": "point", "position": [200.0, 110.0, 200.0], "intensity": 1.0}
    with pytest.raises(SceneError, match=r"lights\[0\]: lies inside shapes\[1\]"):
        scene_from_dict(_glass(_cyl(200.0), lights=[light]), base_dir=tmp_path)
    light["position"] = [200.0, 300.0, 200.0]
    scene_from_dict(_glass(_cyl(200.0), lights=[light]), base_dir=tmp_path)


def test_obj_references_are_not_followed(folder, monkeypatch):
    """An OBJ's ``mtllib`` is not opened: a scene reads only the files it lists in
    ``files_read`` (trimesh, given the path, would read the material file beside it)."""
    import builtins

    import trimesh

    (folder / "inner.mtl").write_text("newmtl x\nKd 1 0 0\n")
    (folder / "refs.obj").write_text("mtllib inner.mtl\nusemtl x\nvt 0 0\n" + CUBE_OBJ)
    opened = []
    real_open = builtins.open

    def spy(file, *a, **k):
        opened.append(str(file))
        return real_open(file, *a, **k)

    monkeypatch.setattr(builtins, "open", spy)
    trimesh.load(folder / "refs.obj", force="mesh", process=False)
    assert any("inner.mtl" in o for o in opened)  # the spy sees what trimesh opens
    opened.clear()
    sc = scene_from_dict(with_mesh("refs.obj"), base_dir=folder)
    monkeypatch.undo()
    assert [r["file"] for r in sc.files_read()] == ["refs.obj"]
    assert not any("inner.mtl" in o for o in opened), opened
