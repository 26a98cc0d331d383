"""Procedural teeth: closed, oriented, nested meshes with the target dimensions and enamel
thickness profile; the mesh checks themselves; OBJ round trip; CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from dentalux import teeth
from dentalux.cli import main
from dentalux.teeth import mesh
from dentalux.teeth.sdf import Grid

trimesh = pytest.importorskip("trimesh")


@pytest.fixture(scope="module")
def incisor():
    tooth = teeth.incisor()
    return tooth, tooth.check()


@pytest.fixture(scope="module")
def molar():
    tooth = teeth.molar()
    return tooth, tooth.check()


def _sphere(radius=2.0, center=(0.0, 0.0, 0.0), h=0.2):
    c = np.asarray(center)
    grid = Grid.around(c - radius, c + radius, h)
    x, y, z = grid.points()
    f = np.sqrt((x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2) - radius
    return mesh.extract(f, grid)


@pytest.mark.parametrize("which", ["incisor", "molar"])
def test_meshes_closed_oriented_and_agree_with_trimesh(which, request):
    tooth, stats = request.getfixturevalue(which)
    for part in ("enamel", "dentin"):
        s = stats[part]
        assert s["closed"] and s["oriented"] and s["volume_mm3"] > 0
        assert s["euler_characteristic"] == 2  # one genus-0 surface
        v, f = getattr(tooth, part)
        tm = trimesh.Trimesh(v, f, process=False)
        assert tm.is_watertight and tm.is_winding_consistent
        assert tm.volume == pytest.approx(s["volume_mm3"], rel=1e-9)
        assert len(tm.split(only_watertight=False)) == 1
    # nested: dentin strictly inside enamel, surfaces disjoint
    assert stats["nesting"]["edge_triangle_crossings"] == 0
    assert stats["nesting"]["min_winding_number"] > 0.99
    assert stats["dentin"]["volume_mm3"] < stats["enamel"]["volume_mm3"]
    # modest size for rendering
    assert stats["triangles_total"] <= 100_000


def test_incisor_dimensions(incisor):
    _, stats = incisor
    d = stats["dimensions"]
    assert d["crown_width_mm"] == pytest.approx(8.7, abs=0.15)  # Orozco-Varo 2015: 8.71
    assert d["crown_length_mm"] == pytest.approx(10.2, abs=0.15)  # Orozco-Varo 2015: 10.23
    assert d["crown_thickness_mm"] == pytest.approx(7.0, abs=0.3)
    assert d["root_length_mm"] == pytest.approx(13.0, abs=0.3)


def test_molar_dimensions(molar):
    _, stats = molar
    d = stats["dimensions"]
    assert d["crown_width_mm"] == pytest.approx(10.0, abs=0.2)
    assert d["crown_thickness_mm"] == pytest.approx(11.0, abs=0.2)
    assert d["crown_length_mm"] == pytest.approx(7.5, abs=0.2)
    assert d["root_length_mm"] == pytest.approx(13.0, abs=0.3)


def test_incisor_enamel_thickness_profile(incisor):
    tooth, stats = incisor
    v, t = tooth.enamel_thickness()
    h = tooth.resolution
    edge = (v[:, 2] > stats["dimensions"]["crown_length_mm"] - 0.2) & (np.abs(v[:, 0]) < 3.0)
    cej = (v[:, 2] > 0.0) & (v[:, 2] < 0.5)
    assert np.median(t[edge]) > 1.5  # thick, enamel-only incisal edge
    assert np.median(t[cej]) < 0.15 + h / 3  # ~0 at the CEJ (distance bound: +h/3)
    assert 1.0 <= stats["enamel_thickness_mm"]["crown_max"] <= 2.5 + h / 3
    prof = [p["median_mm"] for p in stats["enamel_thickness_mm"]["labial_profile"]]
    assert all(b >= a - 0.05 for a, b in zip(prof[:5], prof[1:5], strict=False))  # grows
    assert prof[0] < 0.2 and 0.6 < prof[5] < 1.2


def test_molar_enamel_thickest_at_cusps(molar):
    tooth, stats = molar
    v, t = tooth.enamel_thickness()
    h = tooth.resolution
    tips = v[:, 2] > stats["dimensions"]["crown_length_mm"] - 0.4
    cej = (v[:, 2] > 0.0) & (v[:, 2] < 0.5)
    assert np.median(t[tips]) > 2.0
    assert np.median(t[cej]) < 0.15 + h / 3
    assert stats["enamel_thickness_mm"]["crown_max"] <= 2.5 + h / 3


def test_mesh_checks_can_fail():
    v, f = _sphere()
    assert mesh.edge_check(f)["closed"] and mesh.edge_check(f)["oriented"]
    assert mesh.signed_volume(v, f) == pytest.approx(4 / 3 * math.pi * 8, rel=0.02)
    assert not mesh.edge_check(f[1:])["closed"]  # a hole
    flipped = f.copy()
    flipped[0] = flipped[0, ::-1]
    assert not mesh.edge_check(flipped)["oriented"]  # one face turned over
    assert mesh.signed_volume(v, f[:, ::-1]) < 0  # inward normals
    vn = mesh.vertex_normals(v, f)
    np.testing.assert_allclose(np.linalg.norm(vn, axis=1), 1.0, rtol=1e-9)
    assert np.min(np.einsum("ij,ij->i", vn, v / np.linalg.norm(v, axis=1)[:, None])) > 0.98
    w = mesh.winding_number(np.array([[0.0, 0, 0], [1.5, 0, 0], [2.5, 0, 0], [0, 0, 5]]), v, f)
    np.testing.assert_allclose(w, [1, 1, 0, 0], atol=1e-6)
    small = _sphere(1.0)
    assert mesh.intersects(small, (v, f)) == 0  # nested, disjoint
    shifted = _sphere(2.0, center=(1.5, 0.0, 0.0))
    assert mesh.intersects(shifted, (v, f)) > 0  # overlapping spheres cross


def test_check_rejects_crossing_shells(incisor):
    tooth, _ = incisor
    v, f = tooth.dentin
    bad = teeth.Tooth("bad", enamel=tooth.enamel, dentin=(v * 1.05, f), resolution=0.2)
    with pytest.raises(teeth.MeshError):
        bad.check()


def test_obj_round_trip(tmp_path, incisor):
    tooth, stats = incisor
    v, f = tooth.enamel
    p = mesh.write_obj(tmp_path / "e.obj", v, f, comment="test\nsecond line")
    v2, f2 = mesh.read_obj(p)
    np.testing.assert_array_equal(f2, f)
    np.testing.assert_allclose(v2, v, atol=1e-6)
    tm = trimesh.load(p, process=False)  # an independent OBJ reader
    assert tm.volume == pytest.approx(stats["enamel"]["volume_mm3"], rel=1e-6)
    with pytest.raises(FileNotFoundError):
        mesh.read_obj(tmp_path / "missing.obj")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nf 1 2 x\n")
    with pytest.raises(ValueError, match="bad.obj:2"):
        mesh.read_obj(tmp_path / "bad.obj")


def test_bad_parameters():
    with pytest.raises(ValueError, match="resolution"):
        teeth.incisor(resolution=0.0)
    with pytest.raises(ValueError, match="root_layer_mm"):
        teeth.molar(root_layer_mm=-1.0)


def test_cli_writes_obj_and_json(tmp_path, capsys):
    out = tmp_path / "inc"
    try:
        main(["tooth", "incisor", "--out", str(out), "--resolution", "0.4", "--json"])
    except SystemExit as exc:
        assert not exc.code
    doc = json.loads(capsys.readouterr().out)
    assert doc["dimensions"]["crown_width_mm"] == pytest.approx(8.7, abs=0.3)
    assert doc["boundaries"]["dentin.obj"] == {"inside": "dentin", "outside": "enamel"}
    saved = json.loads((out / "tooth.json").read_text())
    assert saved["enamel"]["triangles"] == doc["enamel"]["triangles"]
    assert (out / "dentin.obj").read_text().count("\nvn ") > 0  # smooth-shading normals
    v, f = mesh.read_obj(out / "dentin.obj")
    assert len(f) == doc["dentin"]["triangles"] and mesh.edge_check(f)["oriented"]


def test_from_obj_and_render_contract_shapes(tmp_path, incisor):
    tooth, _ = incisor
    tooth.write(tmp_path, stats={"dimensions": {}})
    again = teeth.Tooth.from_obj(tmp_path / "enamel.obj", tmp_path / "dentin.obj")
    np.testing.assert_allclose(again.dentin[0], tooth.dentin[0], atol=1e-6)
    outer, inner = again.shapes(enamel=1, dentin=2, outside=0)
    assert outer["boundary"] == {"kind": "dielectric", "inside": 1, "outside": 0}
    assert inner["boundary"] == {"kind": "dielectric", "inside": 2, "outside": 1}
    assert len(inner["triangles"]) == len(tooth.dentin[1])
