"""``dentalux scene check FILE [--dump]``: validate a scene and print what it resolves to."""

from __future__ import annotations

from pathlib import Path

import typer

from dentalux.cli.render import parse_bands
from dentalux.scene.load import load_scene
from dentalux.scene.resolve import to_plain
from dentalux.strict_json import dumps_checked

scene_app = typer.Typer(no_args_is_help=True, help="Scene files: validation and inspection.")


@scene_app.command("check")
def check_command(
    scene_file: Path = typer.Argument(..., help="scene file (TOML)"),
    dump: bool = typer.Option(False, "--dump", help="print the resolved scene JSON per band"),
    bands: str = typer.Option(None, help="bands for --dump [nm] (default: the scene's)"),
    as_json: bool = typer.Option(False, "--json", help="print the summary as JSON"),
    allow_outside_paths: bool = typer.Option(
        False, "--allow-outside-paths",
        help="let the scene read files outside its folder"),
) -> None:
    """Validate SCENE_FILE (exit code 2 with the key path on error) and summarise it."""
    from dentalux.render import plan

    scene = load_scene(scene_file, allow_outside_paths=allow_outside_paths)
    # the checks `dentalux render` makes before it starts (bands, settings, ceilings,
    # memory): check never calls valid what render refuses
    band_list = plan(scene, bands=parse_bands(bands))["bands"]
    summary = dict(scene.summary(), files_read=scene.files_read())
    if dump:
        print(dumps_checked({
            "summary": summary,
            "scene": scene.description,
            "resolved": {f"{wl:g}": scene.resolve(wl) for wl in band_list},
        }, "scene check --dump", indent=1, default=to_plain))
        return
    if as_json:
        print(dumps_checked(summary, "scene check"))
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"{scene_file}: valid")
    table.add_column("key")
    table.add_column("value")
    for key, value in summary.items():
        shown = ", ".join(map(str, value)) if isinstance(value, list) else str(value)
        table.add_row(key, shown)
    Console().print(table)


def register(app: typer.Typer) -> None:
    app.add_typer(scene_app, name="scene")
