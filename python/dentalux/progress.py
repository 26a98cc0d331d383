"""Progress bars for long native calls (rich, on stderr, only when a person is watching)."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)


def _interactive() -> bool:
    return sys.stderr.isatty()


@contextmanager
def bar(total: int, description: str, enabled: bool | None = None) -> Iterator[Callable | None]:
    """Yield a callback ``cb(done)`` that advances a progress bar to ``done`` of ``total``.

    Yields ``None`` (no bar) when disabled or when stderr is not a terminal, so batch jobs and
    CI logs stay clean.
    """
    if enabled is None:
        enabled = _interactive()
    if not enabled:
        yield None
        return
    columns = (
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    with Progress(*columns, transient=True) as prog:
        task = prog.add_task(description, total=total)

        def update(done: int) -> None:
            prog.update(task, completed=done)

        yield update
        prog.update(task, completed=total)
