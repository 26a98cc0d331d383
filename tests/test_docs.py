"""The documentation against the code: the command-line reference page covers every command
and option of the typer app, and the tutorials run as written.

The tutorials (docs/tutorials/*.md) are executed block by block: each fenced ``bash`` block's
``dentalux ...`` lines run as commands, each ``python`` block runs in one namespace per page
(as in a notebook), all in a temporary folder. Blocks with another info string (``text``,
``console``, ``toml``) are shown only. They run from a folder that sees the repository's
``scenes/``, as from its root. To keep `make test` short the photon counts written in
the pages are cut by PHOTON_CUT here; everything else runs as written. The full site build
(links, nav, API reference) is `make docs`, a prerequisite of `make test`."""

from __future__ import annotations

import re
import shlex
import subprocess
from pathlib import Path

import pytest
from cli_run import DENTALUX
from dentalux.cli import reference

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
TUTORIALS = sorted((DOCS / "tutorials").glob("*.md"))
PHOTON_CUT = 5

FENCE = re.compile(r"^```(\w+)[^\n]*\n(.*?)^```", re.S | re.M)


def _app_tree():
    """(path, command) for every command of the typer app, read from click's ``commands``
    mapping (independently of dentalux.cli.reference.walk)."""
    root = reference.root_command()
    todo = [(("dentalux",), root)]
    while todo:
        path, cmd = todo.pop()
        yield path, cmd
        for name, sub in getattr(cmd, "commands", {}).items():
            if not getattr(sub, "hidden", False):
                todo.append(((*path, name), sub))


def test_cli_reference_has_every_command_and_option():
    page = reference.markdown()
    sections = re.split(r"^#+ `(dentalux[^`]*)`\n", page, flags=re.M)
    by_path = dict(zip(sections[1::2], sections[2::2], strict=True))
    seen = 0
    for path, cmd in _app_tree():
        name = " ".join(path)
        assert name in by_path, f"command {name!r} missing from the command-line reference"
        body = by_path[name]
        for param in cmd.params:
            if getattr(param, "hidden", False):
                continue
            if getattr(param, "param_type_name", "") == "option":
                for flag in (*param.opts, *param.secondary_opts):
                    assert f"`{flag}`" in body, f"{name}: option {flag} missing from the reference"
            else:
                assert f"`{param.name.upper()}`" in body, f"{name}: argument {param.name} missing"
            seen += 1
    assert seen > 100  # the whole tree was walked, not just the root


def test_cli_reference_page_is_generated():
    page = (DOCS / "reference" / "cli.md").read_text()
    assert reference.MARKER in page
    assert "docs/hooks/cli_reference.py" in (ROOT / "mkdocs.yml").read_text()


def test_every_page_is_in_the_nav():
    nav = (ROOT / "mkdocs.yml").read_text()
    for page in DOCS.rglob("*.md"):
        rel = page.relative_to(DOCS).as_posix()
        assert rel in nav, f"docs/{rel} is not in mkdocs.yml's nav"


def _cut_photons(text: str) -> str:
    def cut(m: re.Match) -> str:
        n = int(m.group(2).replace("_", ""))
        return f"{m.group(1)}{max(n // PHOTON_CUT, 1000)}"

    return re.sub(r"(--photons[ =]|photons=)([\d_]+)", cut, text)


def _blocks(page: Path) -> list[tuple[str, str]]:
    return [(m.group(1), m.group(2)) for m in FENCE.finditer(page.read_text())]


@pytest.mark.parametrize("page", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_tutorial_runs(page, tmp_path, monkeypatch):
    blocks = [(lang, code) for lang, code in _blocks(page) if lang in ("bash", "python")]
    assert blocks, f"{page.name}: no runnable blocks"
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scenes").symlink_to(ROOT / "scenes")  # as from the repository's root
    namespace: dict = {"__name__": "__main__"}  # each page runs as a script would
    for lang, code in blocks:
        code = _cut_photons(code)
        if lang == "python":
            exec(compile(code, f"{page.name}", "exec"), namespace)  # noqa: S102
            continue
        for line in code.replace("\\\n", " ").splitlines():
            line = line.split(" #")[0].strip()
            if not line:
                continue
            args = shlex.split(line)
            assert args[0] == "dentalux", f"{page.name}: only dentalux commands run: {line}"
            r = subprocess.run([DENTALUX, *args[1:]], capture_output=True, text=True,
                               timeout=300)
            assert r.returncode == 0, f"{page.name}: `{line}` failed:\n{r.stderr[-2000:]}"


def test_make_test_builds_the_docs_strictly():
    """`make test` runs `make docs`, which fails on warnings: --strict, and not --quiet (that
    drops the warnings --strict counts, so a broken link would pass)."""
    make = (ROOT / "Makefile").read_text()
    test_rule = re.search(r"^test:(.*)$", make, re.M).group(1).split()
    assert "docs" in test_rule
    docs_recipe = re.search(r"^docs:.*\n((?:\t.*\n)+)", make, re.M).group(1)
    assert "mkdocs build --strict" in docs_recipe and "--quiet" not in docs_recipe
