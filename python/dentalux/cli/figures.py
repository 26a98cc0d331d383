"""``dentalux figures --out DIR``: the paper's figures (the main job of ``make demo``)."""

from __future__ import annotations

import typer

from dentalux.figures import FIGURES, QUALITIES, make_figures
from dentalux.output_paths import check_out_dir


def figures_command(
    out: str = typer.Option(
        "figures", "--out", help="output folder (its figure files are replaced)"),
    quality: str = typer.Option("preview", help=f"{' | '.join(QUALITIES)}"),
    only: str = typer.Option(None, help=f"comma-separated subset of {','.join(FIGURES)}"),
) -> None:
    """Render Fig. 2-5 of the paper, a crown-vs-natural-tooth figure and a vpm/volpath crop."""
    subset = None
    if only is not None:  # --only '' names nothing: refused, not read as "all of them"
        subset = [s.strip() for s in only.split(",") if s.strip()]
        if not subset:
            raise ValueError(f"--only = {only!r}: names no figure: allowed a comma-separated "
                             f"subset of {','.join(FIGURES)} (leave --only out for all)")
        bad = [s for s in subset if s not in FIGURES]
        if bad:
            raise ValueError(f"--only = {only!r}: unknown figure {bad[0]!r}: allowed "
                             f"{','.join(FIGURES)}")
    # the figures are regenerated in place, so an existing folder is expected
    out = check_out_dir(out, "--out", overwrite=True)
    report = make_figures(out, quality=quality, only=subset)
    print(f"figures written to {out.resolve()}:")
    for path in sorted(out.glob("*.png")):
        print(f"  {path}")
    crown = report["figures"].get("crown")
    if crown:
        print(f"crown vs natural incisor: ΔE00 = {crown[0]['delta_e00']:.2f} "
              f"({crown[0]['verdict']})")


def register(app: typer.Typer) -> None:
    app.command("figures")(figures_command)
