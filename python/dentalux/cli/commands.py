"""The ``dentalux`` command tree: each subcommand lives in its own module here and is
registered below. Imported by :func:`dentalux.cli.main` inside its interrupt handler, so a
Ctrl-C during start-up (these imports pull in colour-science and matplotlib) exits quietly."""

from __future__ import annotations

import typer

from dentalux.cli import demo, slab
from dentalux.cli import design as design_cli
from dentalux.cli import figures as figures_cli
from dentalux.cli import fit as fit_cli
from dentalux.cli import guides as guides_cli
from dentalux.cli import instruments as instruments_cli
from dentalux.cli import materials as materials_cli
from dentalux.cli import plot as plot_cli
from dentalux.cli import render as render_cli
from dentalux.cli import report as report_cli
from dentalux.cli import scene as scene_cli
from dentalux.cli import shade as shade_cli
from dentalux.cli import tooth as tooth_cli
from dentalux.cli import version as version_cli

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Spectral Monte Carlo rendering of teeth and dental materials (mm, 1/mm, nm).",
)
slab.register(app)
demo.register(app)
figures_cli.register(app)
materials_cli.register(app)
tooth_cli.register(app)
shade_cli.register(app)
instruments_cli.register(app)
plot_cli.register(app)
fit_cli.register(app)
render_cli.register(app)
scene_cli.register(app)
version_cli.register(app)
report_cli.register(app)
design_cli.register(app)
guides_cli.register(app)
