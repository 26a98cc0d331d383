"""Progress bars for long native calls (rich, on stderr, only when a person is watching)."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console


def _interactive() -> bool:
    return sys.stderr.isatty()


@contextmanager
def bar(total: int, description: str,
        enabled: bool | None | Callable = None) -> Iterator[Callable | None]:
    """Yield a callback ``cb(done)`` that advances a progress bar to ``done`` of ``total``.

    Yields ``None`` (no bar) when disabled or when stderr is not a terminal, so batch jobs and
    CI logs stay clean. ``enabled`` may also be the caller's own callable
    ``progress(done, total)``: it is called instead of a bar, and an exception it raises
    stops the computation and propagates to the caller.
    """
    if callable(enabled):
        user = enabled

        def forward(done: int) -> None:
            user(done, total)

        yield forward
        return
    if enabled is None:
        enabled = _interactive()
    if not enabled:
        yield None
        return
    # rich only when a bar is drawn: it takes about 50 ms to import
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

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


@contextmanager
def stages(description: str, enabled: bool | None = None,
           console: Console | None = None) -> Iterator[Callable[[str], None]]:
    """A spinner with the elapsed time for work whose total is not known in units (e.g. a
    tooth's meshes), on stderr when a person is watching. Yields ``step(text)``, which names
    the stage now running."""
    if enabled is None:
        enabled = _interactive()
    if not enabled:
        yield lambda text: None
        return
    from rich.console import Console
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    columns = (SpinnerColumn(), TextColumn("[bold]{task.description}"), TimeElapsedColumn())
    console = console or Console(stderr=True)
    with Progress(*columns, transient=True, console=console) as prog:
        task = prog.add_task(description, total=None)

        def step(text: str) -> None:
            prog.update(task, description=f"{description}: {text}")

        yield step
