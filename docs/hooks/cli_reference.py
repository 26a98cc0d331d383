"""MkDocs hook: fills docs/reference/cli.md's marker with the command-line reference generated
from the typer app (dentalux.cli.reference), so the page is rebuilt from the commands at every
`make docs` and cannot drift from them."""

from __future__ import annotations


def on_page_markdown(markdown: str, page, config, files) -> str:  # noqa: ARG001 (MkDocs API)
    from dentalux.cli import reference

    if reference.MARKER not in markdown:
        return markdown
    return markdown.replace(reference.MARKER, reference.markdown())
