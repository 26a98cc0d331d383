"""``dentalux --version``: the installed package's version (pyproject.toml is its one home)."""

from __future__ import annotations

import typer


def _show(value: bool) -> None:
    if value:
        from dentalux import __version__

        typer.echo(f"dentalux {__version__}")
        raise typer.Exit()


def register(app: typer.Typer) -> None:
    @app.callback()
    def _root(version: bool = typer.Option(False, "--version", callback=_show, is_eager=True,
                                           help="print the version and exit")) -> None:
        pass
