"""What the wheel relies on, checked in the checkout (tests/wheel_smoke.sh checks the wheel
itself): the version's one home, and the scenes inside the package."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

import dentalux
from dentalux.scene.builtin import SCENE_FILES, scene_file

ROOT = Path(__file__).resolve().parents[1]


def test_version_is_pyprojects():
    from dentalux.cli import main

    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert dentalux.__version__ == version
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and out.getvalue().strip() == f"dentalux {version}"


def test_scenes_ship_in_the_package_and_the_checkout_links_them():
    folder = Path(dentalux.__file__).parent / "scenes"
    assert sorted(p.stem for p in folder.glob("*.toml")) == sorted(SCENE_FILES)
    for name in SCENE_FILES:
        path = scene_file(name)
        assert path.parent == folder and path.is_file()
        assert (ROOT / "scenes" / f"{name}.toml").resolve() == path.resolve()
        dentalux.load_scene(path)  # loads as it is
    with pytest.raises(ValueError, match="allowed cornell, discs"):
        scene_file("nope")
