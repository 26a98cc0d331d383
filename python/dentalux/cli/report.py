"""``dentalux report``: one self-contained HTML report of one or more materials at a
thickness, or of a design result (``--design design.json``, from ``dentalux design --json``)."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

import typer

from dentalux.cli import measure_options as mo
from dentalux.cli.measure_options import DEFAULTS


def _command() -> str | None:
    """The command line, for the report's inputs (only when run as the console script)."""
    if Path(sys.argv[0]).name != "dentalux":
        return None
    return shlex.join(["dentalux", *sys.argv[1:]])


def report_command(
    materials: list[str] = typer.Argument(None, help="materials: library names or TOML files "
                                          "(as for `dentalux shade`); none with --design"),
    thickness: float = typer.Option(None, help="disc thickness [mm] (not with --design)"),
    out: Path = typer.Option(..., "--out", help="the report, an .html file (replaced if it "
                             "exists)"),
    against: str = typer.Option(None, help="reference material (name or TOML) for ΔE00/ΔTP00"),
    instrument: str = typer.Option(None, help="instrument preset, TOML file or 'infinite' "
                                   "(default: that of `dentalux shade`)"),
    match: str = typer.Option(None, help="the nearest tabs of a shade guide (as `shade "
                              "--match`)"),
    bands: mo.Bands = DEFAULTS["bands"],
    backing_black: mo.BackingBlack = None,
    backing_white: mo.BackingWhite = None,
    contact: mo.Contact = None,
    photons: mo.Photons = DEFAULTS["photons"],
    solver: mo.Solver = DEFAULTS["solver"],
    seed: mo.Seed = DEFAULTS["seed"],
    estimator: mo.Estimator = DEFAULTS["estimator"],
    observer: mo.Observer = DEFAULTS["observer"],
    illuminant: mo.Illuminant = DEFAULTS["illuminant"],
    threads: mo.Threads = None,
    tp_thicknesses: str = typer.Option(None, help="comma-separated thicknesses [mm] of the "
                                       "TP-vs-thickness chart (default 0.25-2 x --thickness)"),
    figure: Path = typer.Option(None, help="an image (.png/.jpg) to embed"),
    render: Path = typer.Option(None, help="a `dentalux render --out` folder: its image and "
                                "the CIELAB of its regions"),
    design: Path = typer.Option(None, help="a design result (`dentalux design --json > "
                                "FILE.json`): its designs against its target, instead of "
                                "materials"),
) -> None:
    """One HTML file: a summary in plain words with colour swatches, then the numbers (each
    with its ±), charts and provenance."""
    from dentalux import report

    if design is not None:
        if materials or thickness is not None or against or match or tp_thicknesses \
                or instrument or backing_black is not None or backing_white is not None \
                or contact is not None:
            raise ValueError("--design: give the design file alone (its materials, "
                             "thicknesses, target and instrument are in it), without "
                             "materials, --thickness, --against, --match, --tp-thicknesses, "
                             "--instrument, --backing-* or --contact")
        report.check_out(out)
        report.read_design(design)  # refuse a bad file before any photon is traced
        path = report.write_design(out, design, figure=figure, render=render,
                                   command=_command(), bands=mo.bands(bands),
                                   photons=photons, seed=seed, solver=solver,
                                   estimator=estimator, observer=observer,
                                   illuminant=illuminant, threads=threads)
        typer.echo(f"wrote {path}")
        return
    if not materials or thickness is None:
        raise ValueError("report: give materials and --thickness, or --design FILE.json")

    ts = None
    if tp_thicknesses is not None:
        try:
            ts = [float(x) for x in tp_thicknesses.split(",") if x.strip()]
        except ValueError:
            raise ValueError(f"--tp-thicknesses = {tp_thicknesses!r}: comma-separated "
                             "thicknesses [mm]") from None
    report.check_out(out)  # refuse a bad --out before any photon is traced
    path = report.write(out, materials, thickness, against=against, instrument=instrument,
                        match=match, tp_thicknesses=ts, figure=figure, render=render,
                        command=_command(), bands=mo.bands(bands),
                        backing_black=backing_black, backing_white=backing_white,
                        contact=contact, photons=photons, seed=seed, solver=solver,
                        estimator=estimator,
                        observer=observer, illuminant=illuminant, threads=threads)
    typer.echo(f"wrote {path}")


def register(app: typer.Typer) -> None:
    app.command("report")(report_command)
