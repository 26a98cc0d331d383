"""``dentalux instruments``: the instrument presets a reading can name."""

from __future__ import annotations

import typer
from rich.console import Console
from rich.table import Table

from dentalux import instrument
from dentalux.strict_json import dumps_checked

app = typer.Typer(help="Instrument presets: lit spot, window, geometry, backings, contact.",
                  no_args_is_help=True)


@app.command("list")
def list_command(as_json: bool = typer.Option(False, "--json", help="print JSON")) -> None:
    """Every preset with its geometry and diameters."""
    presets = instrument.presets()
    if as_json:
        print(dumps_checked({n: i.to_json() for n, i in presets.items()}, "instruments list"))
        return
    table = Table(title=f"instruments (default for `dentalux shade`: {instrument.DEFAULT})")
    for col in ("name", "geometry", "lit [mm]", "viewed [mm]", "backings b / w", "contact"):
        table.add_column(col)
    for name, inst in presets.items():
        j = inst.to_json()
        table.add_row(name, j["geometry"], str(j["illuminated_diameter_mm"]),
                      str(j["viewed_diameter_mm"]),
                      f"{j['backing_black']} / {j['backing_white']}",
                      "air" if j["contact_index"] is None else str(j["contact_index"]))
    Console().print(table)


@app.command("show")
def show_command(name: str = typer.Argument(..., help="preset name or TOML file"),
                 as_json: bool = typer.Option(False, "--json", help="print JSON")) -> None:
    """One instrument with the source of every number."""
    inst = instrument.get(name)
    if as_json:
        print(dumps_checked({**inst.to_json(), "description": inst.description,
                             "provenance": inst.provenance}, "instruments show"))
        return
    console = Console()
    console.print(f"[bold]{inst.name}[/bold]: {inst.description}")
    for key, value in inst.to_json().items():
        source = inst.provenance.get(key.replace("specular", "geometry"), "")
        console.print(f"  {key} = {value}" + (f"\n      {source}" if source else ""))


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="instruments")
