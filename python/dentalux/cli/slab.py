"""``dentalux slab``: what a spectrophotometer measures on a layered disc."""

from __future__ import annotations

import json

import typer
from rich.console import Console
from rich.table import Table

from dentalux.slab import SCALARS, Layer, simulate


def _parse_layer(spec: str, index: int) -> Layer:
    parts = spec.split(",")
    if len(parts) != 5:
        raise ValueError(
            f"--layer[{index}] = {spec!r}: expected five numbers mua,mus,g,n,thickness"
        )
    try:
        mua, mus, g, n, d = (float(p) for p in parts)
    except ValueError as exc:
        raise ValueError(f"--layer[{index}] = {spec!r}: {exc}") from None
    return Layer(mua=mua, mus=mus, g=g, n=n, thickness=d)


def print_result_table(result, title: str) -> None:
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
        None, help="mua,mus,g,n,thickness of one layer, top to bottom (repeatable)"
    ),
    n_above: float = typer.Option(1.0, help="refractive index above the slab"),
    n_below: float = typer.Option(1.0, help="refractive index below the slab"),
    incidence: str = typer.Option("normal", help="normal | diffuse | angle:DEG"),
    estimator: str = typer.Option("analog", help="analog | weighted"),
    photons: int = typer.Option(1_000_000, help="photons to launch"),
    seed: int = typer.Option(1, help="random seed"),
    threads: int = typer.Option(None, help="worker threads (default: all cores)"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """Simulate a layered slab: reflectance, transmittance and absorption with errors."""
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
                      progress=None if not as_json else False)
    if as_json:
        d = result.to_dict()
        for k in ("radial_reflectance", "radial_transmittance", "angular_reflectance",
                  "angular_transmittance"):
            d.pop(k)
        print(json.dumps(d))
    else:
        print_result_table(result, "slab")


def register(app: typer.Typer) -> None:
    app.command("slab")(slab_command)
