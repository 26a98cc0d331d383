"""``dentalux plot``: figures (matplotlib), saved as PNG and SVG."""

from __future__ import annotations

import typer

from dentalux.output_paths import check_out_dir, rebase, staged_dir
from dentalux.strict_json import dumps_checked

# figure name -> the function of dentalux.plots that draws it (imported when drawn:
# matplotlib and colour-science are slow to import)
FIGURES = {"spd": "fig2_spd"}


def plot_command(
    figure: str = typer.Argument(..., help="which figure: spd (the paper's Fig. 2)"),
    out: str = typer.Option(
        ".", help="output folder (its files of the figure's names are replaced)"),
    as_json: bool = typer.Option(False, "--json", help="print the written paths as JSON"),
) -> None:
    """Draw a figure and write it as PNG and SVG into --out."""
    if figure not in FIGURES:
        raise ValueError(f"figure = {figure!r}: allowed {', '.join(FIGURES)}")
    from dentalux import plots

    out = check_out_dir(out, "--out", overwrite=True)
    with staged_dir(out, "--out") as stage:
        paths = rebase(getattr(plots, FIGURES[figure])(stage), stage, out)
    print(dumps_checked(paths, "plot") if as_json else "\n".join(paths.values()))


def register(app: typer.Typer) -> None:
    app.command("plot")(plot_command)
