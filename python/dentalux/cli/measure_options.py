"""The options of the commands that simulate an instrument's reading of a specimen
(`shade`, `report`): each written once here, with the default of
:func:`dentalux.dental.metrics` for the same argument."""

from __future__ import annotations

import inspect
import math
from typing import Annotated

import typer

from dentalux import dental, limits
from dentalux.reading.engine import MAX_TILT_DEG
from dentalux.spectra import full_bands

DEFAULTS = {name: p.default for name, p in inspect.signature(dental.metrics).parameters.items()}

Bands = Annotated[str, typer.Option(help="'full' (380-780 nm/10 nm), 'full:STEP', 'paper' or a "
                                         "comma-separated nm list")]
BackingBlack = Annotated[float, typer.Option(help="black backing reflectance in [0, 1] "
                                                  "(default: the instrument's; 0 for 'infinite')")]
BackingWhite = Annotated[float, typer.Option(help="white backing reflectance in [0, 1] "
                                                  "(default: the instrument's; 0.9 for "
                                                  "'infinite')")]
Contact = Annotated[float, typer.Option(help="optical contact: coupling medium index (>= 1); "
                                             "default the instrument's (an air gap)")]
Photons = Annotated[int, typer.Option(help="photons per band and run")]
Precision = Annotated[float, typer.Option(help="target standard error of the reading in ΔE00 "
                                               "units (over black and white); chooses the "
                                               "photons instead of --photons")]
Seed = Annotated[int, typer.Option(help="random seed")]
Solver = Annotated[str, typer.Option(help="monte-carlo (slab walks) | layered (deterministic "
                                          "transport solver; --photons are then the budget "
                                          "of the walk that corrects for the specimen's rim; "
                                          "a beam within "
                                          f"{MAX_TILT_DEG:g} deg of the normal, as d/8's, is "
                                          "read as normal) | auto (layered where the beam is "
                                          f"within {MAX_TILT_DEG:g} deg of the normal)")]
Estimator = Annotated[str, typer.Option(help="weighted | analog")]
Observer = Annotated[str, typer.Option(help="'2' (CIE 1931) or '10' (CIE 1964)")]
Illuminant = Annotated[str, typer.Option(help="illuminant (colour-science name)")]
Threads = Annotated[int, typer.Option(help="worker threads (default: all cores)")]


def bands(spec: str):
    """The bands ``--bands`` names: 'full', 'paper', a 380-780 nm sweep or a list [nm]."""
    if spec in ("full", "paper"):
        return spec
    if spec.startswith("full:"):  # full:STEP, a 380-780 nm sweep every STEP nm
        try:
            step = float(spec[5:])
        except ValueError:
            step = math.nan
        if not (math.isfinite(step) and step > 0):
            raise ValueError(f"--bands = {spec!r}: full:STEP needs a step > 0 [nm]")
        # the count before the array: full:0.0001 is 4 million bands, refused here
        limits.check_band_count(int(round(400.0 / step)) + 1, f"--bands = {spec!r}")
        return full_bands(step=step)
    try:
        out = [float(x) for x in spec.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"--bands = {spec!r}: 'full', 'paper' or comma-separated nm") from None
    limits.check_band_count(len(out), "--bands")
    return out
