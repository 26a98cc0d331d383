"""``dentalux design``: which thickness of each material matches a target tooth (issue 19)."""

from __future__ import annotations

import json

import typer
from rich.console import Console
from rich.table import Table

from dentalux import instrument as instruments
from dentalux.design import optimise, search


def _bands(spec: str):
    from dentalux.cli.shade import _bands as shade_bands

    return shade_bands(spec)


def design_command(
    target: str = typer.Option(..., help="lab:L,a,b | GUIDE:TAB (e.g. vita-classical:A2) | "
                               "stack:MATERIAL:MM/MATERIAL:MM/..."),
    layer: list[str] = typer.Option(..., help="MATERIAL:MIN-MAX [mm], top to bottom; "
                                    "repeat for 1 to 3 layers"),
    total: str = typer.Option(None, help="total restoration thickness MIN-MAX [mm] "
                              "(veneer 0.3-0.8, crown 1.0-2.0)"),
    substrate: str = typer.Option("dentin", help="none | dentin | stump | zirconia | metal | "
                                  "reflectance:R | reflectance:FILE.csv"),
    cement: str = typer.Option(None, help="cement layer MATERIAL:MM between restoration "
                               "and substrate"),
    instrument: str = typer.Option(instruments.DEFAULT, help="instrument preset or TOML file"),
    target_tp: float = typer.Option(None, help="translucency target TP00"),
    bands: str = typer.Option("full", help="'full', 'full:STEP', 'paper' or nm list"),
    photons: int = typer.Option(search.DEFAULT_PHOTONS, help="photons per band and run"),
    verify_photons: int = typer.Option(None, help="photons for the verification (default "
                                       "--photons)"),
    designs: int = typer.Option(3, help="how many designs to report"),
    nodes: int = typer.Option(None, help="fast-model nodes per layer (default 6/4/3)"),
    seed: int = typer.Option(1, help="random seed"),
    threads: int = typer.Option(None, help="worker threads (default: all cores)"),
    plot: str = typer.Option(None, help="write the ΔE00 plane of a two-layer design (PNG)"),
    render: str = typer.Option(None, help="render the designed crown (not implemented)"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """Rank layer thicknesses by ΔE00 to a target, verified by the full Monte Carlo."""
    if render is not None:
        raise ValueError("--render: rendering the designed crown is not implemented yet "
                         "(docs/design.md); drop --render")
    if plot is not None:
        from dentalux.design.plot import check_path

        check_path(plot, len(layer))
    res = optimise(target, layer, total=total, substrate=substrate, cement=cement,
                   instrument=instrument, bands=_bands(bands), target_tp=target_tp,
                   photons=photons, verify_photons=verify_photons, seed=seed,
                   designs=designs, nodes=nodes, threads=threads,
                   progress=False if as_json else None)
    if plot is not None:
        from dentalux.design.plot import plane

        plane(res, plot)
    if as_json:
        print(json.dumps(res.to_json(), allow_nan=False))
        return
    t = res.target
    table = Table(title=f"designs for L*a*b* {t.lab[0]:.2f} {t.lab[1]:.2f} {t.lab[2]:.2f}"
                  + (f", TP00 {t.tp00:.2f}" if t.tp00 is not None else "")
                  + f" on {res.substrate}, read by {res.instrument['name']}")
    table.add_column("mm (top to bottom)")
    table.add_column("L*a*b*", justify="right")
    table.add_column("ΔE00 ± s.e.", justify="right")
    table.add_column("verdict")
    table.add_column("ΔE00 per 0.1 mm", justify="right")
    table.add_column("verified")
    for d in res.designs:
        table.add_row(" / ".join(f"{x:.2f}" for x in d["thickness_mm"]),
                      " ".join(f"{x:.1f}" for x in d["lab"]),
                      f"{d['delta_e00']:.2f} ± {d['delta_e00_stderr']:.2f}", d["verdict"],
                      " ".join(f"{x:.2f}" for x in d["sensitivity"]),
                      "yes" if d["verified"] else "NO")
    console = Console()
    console.print(table)
    console.print(f"search {res.search_seconds:.1f} s, verification {res.verify_seconds:.1f} s")
    if plot:
        console.print(f"plot: {plot}")


def register(app: typer.Typer) -> None:
    app.command("design")(design_command)
