"""``dentalux demo``: the slab simulation of the paper's Table 1 biomaterial at 540 nm."""

from __future__ import annotations

import typer

from dentalux import materials
from dentalux.cli.slab import print_result_table
from dentalux.slab import Layer, simulate


def demo_command(photons: int = typer.Option(1_000_000, help="photons")) -> None:
    """Slab simulation of the paper's Table 1 disc (0.5 mm) at 540 nm.

    Uses the coefficients fitted from the disc's measured TT and TR (material
    biomaterial-table1); Table 1 measured TT 0.6016, TR 0.3243 at 540 nm.
    """
    v = materials.get("biomaterial-table1").at(540.0)
    layer = Layer(mua=v.mua, mus=v.mus, g=v.g, n=v.n, thickness=0.5, fd=v.fd)
    print(f"biomaterial-table1 at 540 nm: mua {v.mua:.4f} /mm, mus {v.mus:.3f} /mm, "
          f"g {v.g:g}, n {v.n:g}, thickness 0.5 mm")
    result = simulate([layer], n_photons=photons, seed=1, progress=None)
    print_result_table(result, "Table 1 disc, 540 nm (measured: TT 0.6016, TR 0.3243)")


def register(app: typer.Typer) -> None:
    app.command("demo")(demo_command)
