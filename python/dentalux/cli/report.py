"""``dentalux report``: one self-contained HTML shade report of one or more materials."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

import typer

from dentalux import dental


def _command() -> str | None:
    """The command line, for the report's inputs (only when run as the console script)."""
    if Path(sys.argv[0]).name != "dentalux":
        return None
    return shlex.join(["dentalux", *sys.argv[1:]])


def report_command(
    materials: list[str] = typer.Argument(..., help="materials: library names or TOML files "
                                          "(as for `dentalux shade`)"),
    thickness: float = typer.Option(..., help="disc thickness [mm]"),
    out: Path = typer.Option(..., "--out", help="the report, an .html file (replaced if it "
                             "exists)"),
    against: str = typer.Option(None, help="reference material (name or TOML) for ΔE00/ΔTP00"),
    instrument: str = typer.Option(None, help="instrument preset, TOML file or 'infinite' "
                                   "(default: that of `dentalux shade`)"),
    match: str = typer.Option(None, help="the nearest tabs of a shade guide (as `shade "
                              "--match`)"),
    bands: str = typer.Option("full", help="'full' (380-780 nm/10 nm), 'full:STEP', 'paper' "
                              "or a comma-separated nm list"),
    backing_black: float = typer.Option(None, help="black backing reflectance in [0, 1] "
                                        "(default: the instrument's, else 0)"),
    backing_white: float = typer.Option(None, help="white backing reflectance in [0, 1] "
                                        "(default: the instrument's, else 0.9)"),
    contact: float = typer.Option(None, help="optical contact: coupling medium index (>= 1); "
                                  "default the instrument's (an air gap)"),
    photons: int = typer.Option(dental.DEFAULT_PHOTONS, help="photons per band and run"),
    seed: int = typer.Option(1, help="random seed"),
    estimator: str = typer.Option("weighted", help="weighted | analog"),
    observer: str = typer.Option("2", help="'2' (CIE 1931) or '10' (CIE 1964)"),
    illuminant: str = typer.Option("D65", help="illuminant (colour-science name)"),
    threads: int = typer.Option(None, help="worker threads (default: all cores)"),
    tp_thicknesses: str = typer.Option(None, help="comma-separated thicknesses [mm] of the "
                                       "TP-vs-thickness chart (default 0.25-2 x --thickness)"),
    figure: Path = typer.Option(None, help="an image (.png/.jpg) to embed"),
    render: Path = typer.Option(None, help="a `dentalux render --out` folder: its image and "
                                "the CIELAB of its regions"),
) -> None:
    """One HTML file: the `shade --json` numbers, ΔE00 verdict, charts and provenance."""
    from dentalux import report
    from dentalux.cli.shade import _bands

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
                        command=_command(), bands=_bands(bands),
                        backing_black=backing_black, backing_white=backing_white,
                        contact=contact, photons=photons, seed=seed, estimator=estimator,
                        observer=observer, illuminant=illuminant, threads=threads)
    typer.echo(f"wrote {path}")


def register(app: typer.Typer) -> None:
    app.command("report")(report_command)
