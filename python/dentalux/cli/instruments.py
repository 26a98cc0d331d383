"""``dentalux instruments``: the instrument presets a reading can name."""

from __future__ import annotations

import typer

from dentalux import instrument
from dentalux.reading import DEFAULT_SOLVER
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
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"instruments (default for `dentalux shade`: {instrument.DEFAULT})")
    for col in ("name", "class", "geometry", "lit [mm]", "viewed [mm]", "backings b / w",
                "contact"):
        table.add_column(col)
    for name, inst in presets.items():
        j = inst.to_json()
        table.add_row(name, j["class"], j["geometry"], str(j["illuminated_diameter_mm"]),
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
    from rich.console import Console

    console = Console()
    console.print(f"[bold]{inst.name}[/bold]: {inst.description}")
    for key, value in inst.to_json().items():
        source = inst.provenance.get(key.replace("specular", "geometry"), "")
        console.print(f"  {key} = {value}" + (f"\n      {source}" if source else ""))


@app.command("validate")
def validate_command(
    as_json: bool = typer.Option(False, "--json", help="print JSON"),
    photons: int = typer.Option(None, help="photons per band and run (default 4000)"),
    bands: str = typer.Option(None, help="comma-separated wavelengths [nm] (default "
                              "450,500,550,600,650)"),
    seed: int = typer.Option(1, help="random seed"),
    solver: str = typer.Option(DEFAULT_SOLVER, help="monte-carlo | layered | auto (as "
                               "`dentalux shade --solver`; layered refuses the d/8 presets)"),
) -> None:
    """The natural incisor read by every preset beside its class's published readings."""
    from dentalux import instrument_classes as ic
    from dentalux import natural_teeth

    if bands is None:
        wl = ic.BANDS
    else:
        try:
            wl = tuple(float(x) for x in bands.split(","))
        except ValueError:
            raise ValueError(f"--bands = {bands!r}: expected comma-separated wavelengths "
                             "[nm]") from None
    res = ic.validate(photons=ic.PHOTONS if photons is None else photons, bands=wl, seed=seed,
                      solver=solver)
    if as_json:
        print(dumps_checked(res, "instruments validate"))
        return
    cls = ic.classes()
    k = natural_teeth.SPREAD
    from rich.console import Console

    console = Console()
    console.print(f"[bold]natural incisor[/bold] {ic.natural_incisor_text()} (substrate none, "
                  f"over the white backing) vs the class's published mean ± {k:g} SD")
    for p in res["presets"]:
        pub = p["published"]
        ok = ic.check(p["reading"]["lab"], pub)
        console.print(f"{p['name']} ({p['class']}): "
                      + ("inside" if p["inside"] else "[bold]OUTSIDE[/bold]")
                      + f"  sources {', '.join(pub['sources'])}")
        for c, x, m, s, o in zip(("L*", "a*", "b*"), p["reading"]["lab"], pub["mean"],
                                 pub["sd"], ok, strict=True):
            console.print(f"  {c} {x:6.1f}   published {m:6.2f} ± {s:.1f}   "
                          + ("pass" if o else "FAIL"))
    for name, c in cls.items():
        if c["published"] is None:
            console.print(f"{name}: not validated: {c['no_readings']}")
        else:
            console.print(f"{name} SD: {c['published']['sd_status']}")


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="instruments")
