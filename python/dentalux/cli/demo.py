"""``dentalux demo``: the main job that ``make demo`` runs."""

from __future__ import annotations

import typer

from dentalux.cli.slab import print_result_table
from dentalux.slab import Layer, simulate


def demo_command(photons: int = typer.Option(1_000_000, help="photons")) -> None:
    """Slab simulation of a 0.5 mm disc like the paper's Table 1 biomaterial at 540 nm."""
    # placeholder coefficients until the inversion is wired in
    layer = Layer(mua=0.2, mus=6.0, g=0.75, n=1.54, thickness=0.5)
    print_result_table(simulate([layer], n_photons=photons, seed=1, progress=None), "demo")


def register(app: typer.Typer) -> None:
    app.command("demo")(demo_command)
