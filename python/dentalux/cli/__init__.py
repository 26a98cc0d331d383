"""The ``dentalux`` command line: :func:`main` runs the command tree of
:mod:`dentalux.cli.commands`; bad input exits with code 2 and a message naming the field,
Ctrl-C with 130."""

from __future__ import annotations

import sys


class UserError(Exception):
    """An input problem reported to the user as `error: ...` with exit code 2."""


def main(argv: list[str] | None = None) -> None:
    """Console entry point."""
    try:
        from dentalux.cli.commands import app

        app(args=argv, prog_name="dentalux")
    except (ValueError, TypeError, OSError, UserError, KeyError) as exc:
        msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"error: {msg}", file=sys.stderr)
        sys.exit(2)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
