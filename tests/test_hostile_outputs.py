"""Issue 18, part 3, items 1, 2 and 7: output paths are checked before any work, outputs
are written atomically (a full disk or an interrupt leaves nothing under the final names),
and every JSON written is standard JSON. The render tests use a stand-in for the core."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import numpy as np
import pytest
from dentalux import _core
from dentalux.cli import main
from dentalux.output_paths import TMP_PREFIX, atomic_file, check_out_dir, check_out_file
from dentalux.testing import bands_from_band

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell.toml"
TABLE1 = ROOT / "python" / "dentalux" / "data" / "table1.csv"
RENDER = ["--spp", "1", "--photons", "10", "--bands", "450,540,605", "--resolution", "4x3"]
SLAB = ["slab", "--mua", "1", "--mus", "9", "--g", "0.75", "--thickness", "0.2",
        "--photons", "2000", "--json"]


class FakeCore:
    """``_core.render_band`` stand-in: an image filled with the band's nm."""

    def __init__(self, value=None):
        self.calls = 0
        self.value = value

    def __call__(self, scene_json, settings_json, progress=None):
        self.calls += 1
        scene, settings = json.loads(scene_json), json.loads(settings_json)
        h, w = scene["camera"]["height"], scene["camera"]["width"]
        v = float(settings["band"]) if self.value is None else self.value
        return np.full((h, w), v, dtype=np.float32), {"photons_emitted": 10}


@pytest.fixture
def core(monkeypatch):
    fake = FakeCore()
    monkeypatch.setattr(_core, "render_bands", bands_from_band(fake), raising=False)
    return fake


def run(capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert "Traceback" not in err and "panicked" not in err
    return exc.value.code, out, err


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in Path(folder).rglob(f"{TMP_PREFIX}*"))


# ---------------------------------------------------------------------------------------
# 1. Output paths


@pytest.fixture
def a_file(tmp_path):
    f = tmp_path / "exists.txt"
    f.write_text("keep me")
    return f


@pytest.mark.parametrize("kind,message", [
    ("file", "exists and is not a folder"),
    ("dev", "refusing to write under"),
    ("proc", "refusing to write under"),
    ("sys", "refusing to write under"),
    ("under_file", "is a file, not a folder"),
    ("empty", "an empty path"),
    ("nonempty", "the folder is not empty"),
])
def test_render_out_refused_before_rendering(core, capsys, tmp_path, a_file, kind, message):
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "mine.txt").write_text("x")
    out = {"file": a_file, "dev": "/dev/null", "proc": "/proc/self/fd",
           "sys": "/sys/kernel/x", "under_file": a_file / "sub", "empty": "",
           "nonempty": tmp_path / "full"}[kind]
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        before = sorted(p.name for p in tmp_path.iterdir())
        code, _, err = run(capsys, ["render", CORNELL, "--out", out, *RENDER])
        after = sorted(p.name for p in tmp_path.iterdir())
    finally:
        os.chdir(cwd)
    assert code == 2 and "--out" in err and message in err, err
    assert core.calls == 0, "refused only after rendering"
    assert before == after and a_file.read_text() == "keep me"
    assert sorted(p.name for p in (tmp_path / "full").iterdir()) == ["mine.txt"]


def test_render_overwrite_replaces_and_reports(core, capsys, tmp_path):
    out = tmp_path / "o"
    assert run(capsys, ["render", CORNELL, "--out", out, *RENDER])[0] == 0
    (out / "note.txt").write_text("mine")
    code, _, err = run(capsys, ["render", CORNELL, "--out", out, *RENDER])
    assert code == 2 and "--overwrite" in err
    code, text, _ = run(capsys, ["render", CORNELL, "--out", out, *RENDER, "--overwrite"])
    assert code == 0 and f"wrote {out}" in text
    doc = json.loads((out / "render.json").read_text())
    # the summary names the final files, not the staging folder
    assert doc["files"]["radiance"] == str(out / "radiance.npy")
    assert TMP_PREFIX not in json.dumps(doc)
    assert (out / "note.txt").read_text() == "mine" and leftovers(tmp_path) == []
    assert oct(os.stat(out / "radiance.npy").st_mode & 0o777) != oct(0o600)


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_out_in_folder_without_write_permission(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(ValueError, match="no permission"):
            check_out_dir(ro / "o", "--out")
        with pytest.raises(ValueError, match="no permission"):
            check_out_file(ro / "p.npz", "--profiles", (".npz",))
    finally:
        ro.chmod(0o700)


def test_permission_check_uses_access(monkeypatch, tmp_path):
    """Where the tests run as root, simulate the missing permission."""
    monkeypatch.setattr(os, "access", lambda *a, **k: False)
    with pytest.raises(ValueError, match="--out = .*no permission to write"):
        check_out_dir(tmp_path / "o", "--out")


@pytest.mark.parametrize("value,message", [
    ("DIR", "is a folder"),
    ("p.txt", "must end in .npz"),
    ("/dev/null", "refusing to write under"),
    ("", "an empty path"),
    ("FILE/p.npz", "is a file, not a folder"),
])
def test_slab_profiles_path(capsys, tmp_path, a_file, value, message):
    (tmp_path / "DIR").mkdir()
    arg = {"DIR": tmp_path / "DIR", "p.txt": tmp_path / "p.txt",
           "FILE/p.npz": a_file / "p.npz"}.get(value, value)
    code, _, err = run(capsys, [*SLAB, "--profiles", arg])
    assert code == 2 and "--profiles" in err and message in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["DIR", "exists.txt"]
    assert list((tmp_path / "DIR").iterdir()) == []


def test_slab_profiles_written_where_asked(capsys, tmp_path):
    code, out, _ = run(capsys, [*SLAB, "--profiles", tmp_path / "p.npz"])
    assert code == 0 and json.loads(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.npz"]
    assert set(np.load(tmp_path / "p.npz")) >= {"radial_reflectance", "r_edges_mm"}


@pytest.mark.parametrize("value,message", [
    ("/proc/self/mem", "refusing to write under"),
    ("DIR", "is a folder"),
    ("out.txt", "must end in .toml"),
])
def test_fit_out_refused_before_fitting(capsys, tmp_path, monkeypatch, value, message):
    import dentalux.cli.fit as fit_cli

    def never(*a, **k):
        raise AssertionError("fitted before the output path was checked")

    monkeypatch.setattr(fit_cli, "fit_table", never)
    (tmp_path / "DIR").mkdir()
    arg = {"DIR": tmp_path / "DIR", "out.txt": tmp_path / "out.txt"}.get(value, value)
    code, _, err = run(capsys, ["fit", "--table", TABLE1, "--model", "telegrapher",
                                "--out", arg])
    assert code == 2 and "--out" in err and message in err, err
    assert not (tmp_path / "out.txt").exists()


def test_materials_plot_out_folder_refused(capsys, tmp_path):
    code, _, err = run(capsys, ["materials", "plot", "dentin", "--out", tmp_path])
    assert code == 2 and "is a folder" in err
    assert list(tmp_path.iterdir()) == []
    code, _, err = run(capsys, ["materials", "plot", "dentin", "--out", tmp_path / "x.txt"])
    assert code == 2 and ".png" in err and list(tmp_path.iterdir()) == []


def test_tooth_and_plot_out_refused(capsys, tmp_path, a_file):
    for argv in (["tooth", "incisor", "--out", a_file, "--resolution", "0.5"],
                 ["tooth", "molar", "--out", "/proc/self", "--resolution", "0.5"],
                 ["plot", "spd", "--out", a_file],
                 ["plot", "spd", "--out", "/sys/x"]):
        code, _, err = run(capsys, argv)
        assert code == 2 and "--out" in err, (argv, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["exists.txt"]


# ---------------------------------------------------------------------------------------
# 2. Atomic outputs: a full disk, an error or Ctrl-C while writing


def _full_disk(real):
    """A writer that writes a few bytes, as a disk that fills up would, then fails."""
    def write(path, *args, **kwargs):
        Path(path if isinstance(path, (str, os.PathLike)) else path.name).write_bytes(b"\x93NU")
        raise OSError(errno.ENOSPC, "No space left on device")
    return write


def test_render_on_a_full_disk_leaves_nothing(core, capsys, tmp_path, monkeypatch):
    import dentalux.outputs as outputs

    monkeypatch.setattr(outputs.np, "save", _full_disk(np.save))
    out = tmp_path / "new"
    code, _, err = run(capsys, ["render", CORNELL, "--out", out, *RENDER])
    assert code == 2 and "no space left" in err and "nothing was written" in err, err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_rerender_on_a_full_disk_keeps_the_old_outputs(core, capsys, tmp_path, monkeypatch):
    import dentalux.outputs as outputs

    out = tmp_path / "o"
    assert run(capsys, ["render", CORNELL, "--out", out, *RENDER])[0] == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(outputs.np, "save", _full_disk(np.save))
    code, _, err = run(capsys, ["render", CORNELL, "--out", out, *RENDER, "--overwrite",
                                "--bands", "460,550,600"])
    assert code == 2 and "earlier files are unchanged" in err, err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert leftovers(tmp_path) == []


def test_render_interrupted_while_writing(core, capsys, tmp_path, monkeypatch):
    import dentalux.outputs as outputs

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(outputs, "write_previews", interrupted)
    code, _, err = run(capsys, ["render", CORNELL, "--out", tmp_path / "o", *RENDER])
    assert code == 130
    assert list(tmp_path.iterdir()) == []


def test_profiles_on_a_full_disk(capsys, tmp_path, monkeypatch):
    import dentalux.cli.slab as slab_cli

    monkeypatch.setattr(slab_cli.np, "savez", _full_disk(np.savez))
    code, _, err = run(capsys, [*SLAB, "--profiles", tmp_path / "p.npz"])
    assert code == 2 and "--profiles" in err and "no space left" in err
    assert list(tmp_path.iterdir()) == []


def test_fit_toml_on_a_full_disk(capsys, tmp_path, monkeypatch):
    import dentalux.cli.fit as fit_cli

    def full(results, path, *a, **k):
        Path(path).write_text("")  # the 0-byte TOML of the probe
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(fit_cli, "write_spectrum_toml", full)
    out = tmp_path / "m.toml"
    code, _, err = run(capsys, ["fit", "--table", TABLE1, "--model", "telegrapher",
                                "--out", out])
    assert code == 2 and "no space left" in err and not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_atomic_file_keeps_the_old_file_on_error(tmp_path):
    f = tmp_path / "a.npz"
    f.write_bytes(b"old")
    with pytest.raises(RuntimeError), atomic_file(f) as tmp:
        tmp.write_bytes(b"half")
        raise RuntimeError("boom")
    assert f.read_bytes() == b"old" and sorted(p.name for p in tmp_path.iterdir()) == ["a.npz"]
    with atomic_file(f) as tmp:
        assert tmp.suffix == ".npz" and tmp.parent == tmp_path
        tmp.write_bytes(b"new")
    assert f.read_bytes() == b"new" and sorted(p.name for p in tmp_path.iterdir()) == ["a.npz"]


# ---------------------------------------------------------------------------------------
# 7. Standard JSON


def test_render_json_is_standard_json(core, capsys, tmp_path, monkeypatch):
    """A NaN in the stats (as the core may report for an empty map) becomes null."""
    real = core.__call__

    def with_nan(scene_json, settings_json, progress=None):
        image, stats = real(scene_json, settings_json, progress)
        return image, dict(stats, radius_mean=float("nan"), ratio=float("inf"))

    monkeypatch.setattr(_core, "render_bands", bands_from_band(with_nan), raising=False)
    code, out, _ = run(capsys, ["render", CORNELL, "--out", tmp_path / "o", *RENDER, "--json"])
    assert code == 0
    strict = {"parse_constant": lambda c: pytest.fail(f"non-standard JSON constant {c}")}
    printed = json.loads(out, **strict)
    written = json.loads((tmp_path / "o" / "render.json").read_text(), **strict)
    assert written["stats"][0]["radius_mean"] is None and printed["stats"][0]["ratio"] is None
    colour = tmp_path / "o" / "colour.json"
    if colour.exists():
        json.loads(colour.read_text(), **strict)


def test_non_finite_film_is_refused(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(_core, "render_bands", bands_from_band(FakeCore(value=float("inf"))),
                        raising=False)
    code, _, err = run(capsys, ["render", CORNELL, "--out", tmp_path / "o", *RENDER])
    assert code == 2 and "non-finite" in err and "radiance" in err
    assert list(tmp_path.iterdir()) == []


def test_light_radiance_that_overflows_with_the_real_core(capsys, tmp_path):
    """The probe's light of radiance 1e300: the real core's film is inf; refused, nothing
    written, no Infinity in any JSON."""
    import tomli_w
    from dentalux.scene.load import read_toml

    d = read_toml(CORNELL)
    d["lights"][0]["radiance"] = 1e300
    scene = tmp_path / "hot.toml"
    scene.write_text(tomli_w.dumps(d))
    code, _, err = run(capsys, ["render", scene, "--out", tmp_path / "o", "--integrator",
                                "path", "--spp", "1", "--bands", "540", "--resolution", "4x3",
                                "--threads", "1"])
    assert code == 2 and "non-finite" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hot.toml"]


def test_figures_out_checked_before_rendering(capsys, tmp_path, a_file, monkeypatch):
    import dentalux.cli.figures as figures_cli

    monkeypatch.setattr(figures_cli, "make_figures", lambda *a, **k: pytest.fail("ran"))
    for out in ("", "/dev/shm/x", a_file):
        code, _, err = run(capsys, ["figures", "--out", out, "--only", "fig2"])
        assert code == 2 and "--out" in err, err
