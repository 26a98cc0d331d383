"""``dentalux design``: which thickness of each material matches a target tooth (issue 19)."""

from __future__ import annotations

import typer
from rich.console import Console
from rich.table import Table

from dentalux import instrument as instruments
from dentalux.cli import measure_options
from dentalux.strict_json import dumps_checked


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
    target_instrument: str = typer.Option(None, help="instrument that read the target "
                                          "(preset or TOML file; default: --instrument)"),
    target_tp: float = typer.Option(None, help="translucency target TP00"),
    bands: measure_options.Bands = measure_options.DEFAULTS["bands"],
    photons: int = typer.Option(
        None, help="photons per band and run (default: dentalux.design.search's)"),
    verify_photons: int = typer.Option(None, help="photons for the verification (default "
                                       "--photons)"),
    precision: measure_options.Precision = None,
    designs: int = typer.Option(3, help="how many designs to report"),
    nodes: int = typer.Option(None, help="fast-model nodes per layer (default 6/4/3)"),
    seed: int = typer.Option(1, help="random seed"),
    threads: int = typer.Option(None, help="worker threads (default: all cores)"),
    plot: str = typer.Option(None, help="write the ΔE00 plane of a two-layer design (PNG)"),
    render: str = typer.Option(None, help="render the best design's crown beside a natural "
                               "incisor into folder DIR (its files are replaced) and print the "
                               "rendered ΔE00 beside the predicted one"),
    render_quality: str = typer.Option("draft", help="with --render: draft | preview | paper"),
    render_repeats: int = typer.Option(1, help="with --render: independent renders averaged "
                                       "(from 2 on their spread is the error)"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """Rank layer thicknesses by ΔE00 to a target, verified by the full Monte Carlo."""
    # the design package pulls in scipy's interpolation: imported here, not at start-up
    from dentalux.design import optimise, search
    from dentalux.design import targets as design_targets

    t_inst, d_inst = design_targets.resolve_instrument(target_instrument, instrument)
    photons = search.DEFAULT_PHOTONS if photons is None else photons
    if render is not None:  # refuse a bad folder or substrate before the search
        from dentalux.design import render as design_render

        design_render.check(render, substrate, render_quality, render_repeats)
    if plot is not None:
        from dentalux.design.plot import check_path

        check_path(plot, len(layer))
    if t_inst != d_inst:  # read a stack target through its own instrument
        target = design_targets.parse(target, read=design_targets.read_through(
            target_instrument, bands=measure_options.bands(bands), photons=verify_photons
            or photons, seed=seed + 2, threads=threads), instrument=t_inst)
    res = optimise(target, layer, total=total, substrate=substrate, cement=cement,
                   instrument=instrument, bands=measure_options.bands(bands), target_tp=target_tp,
                   photons=photons, verify_photons=verify_photons, seed=seed,
                   designs=designs, nodes=nodes, threads=threads,
                   progress=False if as_json else None, precision=precision)
    res.target = design_targets.parse(res.target, instrument=t_inst)
    note = design_targets.differs_note(res.target, d_inst)
    if plot is not None:
        from dentalux.design.plot import plane

        plane(res, plot)
    rendered = None
    if render is not None:
        rendered = design_render.render_design(res, render, quality=render_quality,
                                               repeats=render_repeats, seed=seed,
                                               threads=threads,
                                               progress=False if as_json else None)
    if as_json:
        out = res.to_json()
        if rendered is not None:
            out["render"] = _render_json(rendered)
        print(dumps_checked(out, "design"))
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
    if note:
        console.print(f"note: {note}")
    console.print(f"search {res.search_seconds:.1f} s, verification {res.verify_seconds:.1f} s")
    if plot:
        console.print(f"plot: {plot}")
    if rendered is not None:
        r, p = rendered["rendered"], rendered["predicted"]
        console.print(f"ΔE00 crown vs natural incisor, design 1: rendered {r['delta_e00']:.2f} ± "
                      f"{r['delta_e00_stderr']:.2f}, predicted {p['delta_e00']:.2f} ± "
                      f"{p['delta_e00_stderr']:.2f} (rendered L*a*b* crown "
                      + " ".join(f"{x:.1f}" for x in r["lab"]["crown"]) + ", natural "
                      + " ".join(f"{x:.1f}" for x in r["lab"]["natural"])
                      + f"; {rendered['seconds']:.0f} s)")
        console.print(f"render: {rendered['files']['annotated_png']}, "
                      f"{rendered['files']['render_json']}")


def _render_json(report: dict) -> dict:
    """The ``render`` key of ``--json``: the comparison and the files (render.json in DIR
    holds the rest: settings, regions, white tile, timings)."""
    keys = ("rendered", "predicted", "rendered_minus_predicted", "crown", "files", "seconds")
    return {k: report[k] for k in keys}


def register(app: typer.Typer) -> None:
    app.command("design")(design_command)
