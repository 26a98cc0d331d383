"""``dentalux slab``: what a spectrophotometer measures on a layered disc.

Lengths in mm, coefficients in 1/mm. ``--json`` prints one object with the contract keys of
issue 2; ``--profiles FILE.npz`` also writes the radial profiles R(r), T(r) [1/mm^2] and the
exit-angle histograms (fractions of the incident power per bin).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from dentalux import limits
from dentalux.output_paths import atomic_file, check_out_file
from dentalux.slab import SCALARS, Layer, simulate
from dentalux.strict_json import dumps_checked


def _parse_layer(spec: str, index: int) -> Layer:
    """``mua,mus,g,n,thickness[,fd]`` -> Layer (1/mm, 1/mm, -, -, mm, -)."""
    parts = spec.split(",")
    if len(parts) not in (5, 6):
        raise ValueError(
            f"--layer[{index}] = {spec!r}: expected five numbers mua,mus,g,n,thickness "
            "(and optionally fd)"
        )
    try:
        values = [float(p) for p in parts]
    except ValueError as exc:
        raise ValueError(f"--layer[{index}] = {spec!r}: {exc}") from None
    mua, mus, g, n, d = values[:5]
    fd = values[5] if len(values) == 6 else 0.0
    return Layer(mua=mua, mus=mus, g=g, n=n, thickness=d, fd=fd)


def _check_profile_options(radial_bins: int, radial_max: float, angle_bins: int) -> None:
    limits.check_count(radial_bins, "--radial-bins", limits.MAX_RADIAL_BINS)
    if not radial_max > 0 or radial_max == float("inf"):
        raise ValueError(f"--radial-max = {radial_max} is out of range: allowed (0, inf) mm")
    limits.check_count(angle_bins, "--angle-bins", limits.MAX_ANGLE_BINS)


def write_profiles(path: Path, result, radial_max: float, angle_bins: int) -> None:
    """Save R(r), T(r) [1/mm^2] with ring edges [mm] and the exit-angle histograms with
    their edges [deg] to an ``.npz`` file."""
    bins = len(result.radial_reflectance)
    np.savez(
        path,
        r_edges_mm=np.linspace(0.0, radial_max, bins + 1),
        radial_reflectance=np.asarray(result.radial_reflectance),
        radial_transmittance=np.asarray(result.radial_transmittance),
        angle_edges_deg=np.linspace(0.0, 90.0, angle_bins + 1),
        angular_reflectance=np.asarray(result.angular_reflectance),
        angular_transmittance=np.asarray(result.angular_transmittance),
    )


def print_result_table(result, title: str) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=title)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("std. error", justify="right")
    for key in SCALARS:
        table.add_row(key.replace("_", " "), f"{getattr(result, key):.5f}",
                      f"{result.stderr[key]:.5f}")
    for i, a in enumerate(result.absorbed_per_layer):
        table.add_row(f"absorbed in layer {i}", f"{a:.5f}", "")
    Console().print(table)
    Console().print(
        f"{result.photons} photons in {result.seconds:.2f} s "
        f"({result.photons_per_second:,.0f} photons/s on {result.threads} threads)"
    )


def slab_command(
    mua: float = typer.Option(None, help="absorption coefficient [1/mm]"),
    mus: float = typer.Option(None, help="scattering coefficient [1/mm]"),
    g: float = typer.Option(0.0, help="HG anisotropy, in (-1, 1)"),
    n: float = typer.Option(1.0, help="refractive index of the layer (>= 1)"),
    thickness: float = typer.Option(None, help="layer thickness [mm]"),
    fd: float = typer.Option(0.0, help="isotropic fraction of eq. 10, in [0, 1]"),
    layer: list[str] = typer.Option(
        None, help="mua,mus,g,n,thickness[,fd] of one layer, top to bottom (repeatable)"
    ),
    n_above: float = typer.Option(1.0, help="refractive index above the slab"),
    n_below: float = typer.Option(1.0, help="refractive index below the slab"),
    incidence: str = typer.Option("normal", help="normal | diffuse | angle:DEG"),
    estimator: str = typer.Option("analog", help="analog | weighted"),
    photons: int = typer.Option(
        1_000_000, help=f"photons to launch (1 ... {limits.MAX_SLAB_PHOTONS:.0e})"),
    seed: int = typer.Option(1, help="random seed"),
    threads: int = typer.Option(
        None, help=f"worker threads, 1 ... {limits.THREADS_PER_CORE} x the logical cores "
                   "(default: all cores)"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
    profiles: str = typer.Option(
        None, help="write R(r), T(r) and exit-angle histograms to this .npz file (replaced "
                   "if it exists)"
    ),
    radial_bins: int = typer.Option(
        100, help=f"rings of the radial profiles (1 ... {limits.MAX_RADIAL_BINS:,})"),
    radial_max: float = typer.Option(10.0, help="outer radius of the radial profiles [mm]"),
    angle_bins: int = typer.Option(
        18, help=f"exit-angle bins over [0, 90) degrees (1 ... {limits.MAX_ANGLE_BINS:,})"),
) -> None:
    """Simulate a layered slab: reflectance, transmittance and absorption with errors."""
    _check_profile_options(radial_bins, radial_max, angle_bins)
    limits.check_slab(photons, threads, radial_bins if profiles else None,
                      angle_bins if profiles else None, prefix="--", seed=seed)
    if profiles is not None:
        profiles = check_out_file(profiles, "--profiles", (".npz",))
    if layer:
        if any(v is not None for v in (mua, mus, thickness)):
            raise ValueError("give either --layer (repeatable) or --mua/--mus/--thickness")
        layers = [_parse_layer(s, i) for i, s in enumerate(layer)]
    else:
        missing = [k for k, v in (("mua", mua), ("mus", mus), ("thickness", thickness))
                   if v is None]
        if missing:
            raise ValueError(f"missing --{', --'.join(missing)} (or give --layer)")
        layers = [Layer(mua=mua, mus=mus, g=g, n=n, thickness=thickness, fd=fd)]
    result = simulate(layers, n_photons=photons, seed=seed, n_above=n_above, n_below=n_below,
                      incidence=incidence, estimator=estimator, threads=threads,
                      radial=(radial_bins, radial_max) if profiles else None,
                      angular_bins=angle_bins if profiles else None,
                      progress=None if not as_json else False)
    if profiles:
        with atomic_file(profiles, "--profiles") as tmp:
            write_profiles(tmp, result, radial_max, angle_bins)
    if as_json:
        d = result.to_dict()
        for k in ("radial_reflectance", "radial_transmittance", "angular_reflectance",
                  "angular_transmittance"):
            d.pop(k)
        print(dumps_checked(d, "slab"))
    else:
        print_result_table(result, "slab")
        if profiles:
            print(f"wrote {profiles}")


def register(app: typer.Typer) -> None:
    app.command("slab")(slab_command)
