"""``dentalux guides``: shade guides, built in and the lab's own (imported)."""

from __future__ import annotations

from pathlib import Path

import typer

from dentalux import shade_guides
from dentalux.strict_json import dumps_checked

app = typer.Typer(help="Shade guides: the built-in tables and the lab's own imported guides "
                       "(a per-user data folder; DENTALUX_DATA overrides it).",
                  no_args_is_help=True)


def _summary(name: str) -> dict:
    tabs = shade_guides.load(name)
    with_values = [t for t in tabs.values() if t.lab is not None]
    return {"name": name, "kind": "imported" if name in shade_guides.imported() and
            name not in shade_guides._table() else "built-in",
            "tabs": len(tabs), "tabs_with_values": len(with_values),
            "instrument": shade_guides.instruments_of(name)}


@app.command("list")
def list_command(as_json: bool = typer.Option(False, "--json", help="print JSON")) -> None:
    """Every guide: built-in and imported, with how many tabs have values."""
    rows = [_summary(g) for g in shade_guides.guides()]
    if as_json:
        print(dumps_checked({"guides": rows, "data_dir": str(shade_guides.data_dir())},
                            "guides list"))
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"shade guides (imported ones in {shade_guides.data_dir() / 'guides'})")
    for col in ("name", "kind", "tabs", "with L*a*b*", "instrument"):
        table.add_column(col)
    for r in rows:
        table.add_row(r["name"], r["kind"], str(r["tabs"]), str(r["tabs_with_values"]),
                      ", ".join(r["instrument"]) or "-")
    Console().print(table)


@app.command("show")
def show_command(name: str = typer.Argument(..., help="guide name or a guide FILE.csv"),
                 as_json: bool = typer.Option(False, "--json", help="print JSON")) -> None:
    """The tabs of a guide with their L*a*b* and where they came from."""
    tabs = shade_guides.load(name)
    if as_json:
        print(dumps_checked({"guide": name, "tabs": [
            {"tab": t.tab, "lab": None if t.lab is None else list(t.lab), **t.source()}
            for t in tabs.values()]}, "guides show"))
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"shade guide {name}")
    for col in ("tab", "L*", "a*", "b*", "status", "instrument", "source"):
        table.add_column(col)
    for t in tabs.values():
        vals = ["-"] * 3 if t.lab is None else [f"{x:.2f}" for x in t.lab]
        table.add_row(t.tab, *vals, t.status, t.instrument or "-", t.citation[:60])
    Console().print(table)
    if not any(t.lab for t in tabs.values()):
        Console(stderr=True).print(f"note: no tab has values; {shade_guides.IMPORT_HOW}")


@app.command("import")
def import_command(file: Path = typer.Argument(..., help="guide CSV: tab,L,a,b (or r400 ... "
                                               "r700) [,instrument,illuminant,observer,"
                                               "source,date]"),
                   name: str = typer.Option(..., "--name", help="the name to use it by"),
                   replace: bool = typer.Option(False, "--replace",
                                                help="replace an imported guide of that name"),
                   as_json: bool = typer.Option(False, "--json", help="print JSON")) -> None:
    """Check a guide CSV and keep it in the user's data folder under NAME."""
    dest = shade_guides.import_guide(file, name, replace=replace)
    summary = _summary(name)
    if as_json:
        print(dumps_checked({**summary, "file": str(dest)}, "guides import"))
        return
    from rich.console import Console

    Console().print(f"imported {summary['tabs']} tabs as {name!r} ({dest}); use --match {name} "
                    f"on shade, --target {name}:TAB on design")


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="guides")
