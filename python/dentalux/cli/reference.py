"""The command-line reference as Markdown, generated from the typer app itself (the click
command tree that ``dentalux`` runs), so the documentation cannot drift from the commands.

The docs build calls :func:`markdown` (docs/hooks/cli_reference.py) and puts the result in
place of the ``<!-- cli-reference -->`` marker of docs/reference/cli.md;
tests/test_docs.py checks that every command and option of the app is in it."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

MARKER = "<!-- cli-reference -->"

# typer >= 0.20 carries its own copy of click (typer._click), so the command tree is read by
# duck typing (a group has list_commands; a parameter names its kind) rather than isinstance.
Command = Any


def _is_group(cmd: Command) -> bool:
    return hasattr(cmd, "list_commands")


def _is_option(param: Any) -> bool:
    return getattr(param, "param_type_name", "") == "option"


def _is_argument(param: Any) -> bool:
    return getattr(param, "param_type_name", "") == "argument"


def _context(cmd: Command, info_name: str) -> Any:
    return cmd.context_class(cmd, info_name=info_name)


def root_command() -> Command:
    """The click command behind ``dentalux`` (typer builds it from the app)."""
    import typer

    from dentalux.cli.commands import app

    return typer.main.get_command(app)


def walk(
    cmd: Command, path: tuple[str, ...] = ("dentalux",)
) -> Iterator[tuple[tuple[str, ...], Command]]:
    """Every command of the tree, depth first, in the order ``--help`` lists them, with its
    full path (``("dentalux", "materials", "list")``). Hidden commands are left out."""
    yield path, cmd
    if _is_group(cmd):
        ctx = _context(cmd, path[-1])
        for name in cmd.list_commands(ctx):
            sub = cmd.get_command(ctx, name)
            if sub is None or getattr(sub, "hidden", False):
                continue
            yield from walk(sub, (*path, name))


def _cell(text: object) -> str:
    """One Markdown table cell: no newlines, no bare pipes."""
    return " ".join(str(text).split()).replace("|", "\\|")


def _default(param: Any) -> str:
    if _is_option(param) and getattr(param, "is_flag", False) and not param.secondary_opts:
        return ""
    value = param.default
    if value is None or callable(value) or value == () or value == []:
        return ""
    if isinstance(value, (list, tuple)):
        value = ",".join(str(v) for v in value)
    return f"`{value}`"


def option_names(param: Any) -> list[str]:
    """The spellings a user types: ``--flag``, ``-f``, ``--no-flag``; an argument's name."""
    if _is_option(param):
        return [*param.opts, *param.secondary_opts]
    return [_arg_name(param)]


def _arg_name(param: Any) -> str:
    """A positional argument's name as the usage line shows it (``MATERIAL``)."""
    return str(getattr(param, "metavar", None) or param.name).upper()


def _type_name(param: Any, ctx: Any) -> str:
    """The value's type as ``--help`` shows it (``float``, ``str``, ``int``)."""
    bare = getattr(param, "bare_type", None)
    if callable(bare):
        return str(bare())
    kind = getattr(param, "type", None)
    return str(getattr(kind, "name", kind or ""))


def _help_text(cmd: Command) -> str:
    text = (cmd.help or cmd.short_help or "").strip()
    # typer's \b (keep this paragraph's line breaks) and rich markup are for the terminal
    return text.replace("\b\n", "").replace("\b", "")


def command_markdown(path: tuple[str, ...], cmd: Command) -> str:
    """One command's section: heading, help, usage, arguments and options."""
    ctx = _context(cmd, " ".join(path))
    depth = min(len(path) + 1, 6)
    out = [f"{'#' * depth} `{' '.join(path)}`", ""]
    help_text = _help_text(cmd)
    if help_text:
        out += [help_text, ""]
    pieces = " ".join(cmd.collect_usage_pieces(ctx))
    out += ["```text", f"{' '.join(path)} {pieces}".rstrip(), "```", ""]
    args = [p for p in cmd.params if _is_argument(p)]
    opts = [p for p in cmd.params if _is_option(p) and not p.hidden]
    if args:
        out += ["| argument | type | required | help |", "|---|---|---|---|"]
        for p in args:
            help_ = getattr(p, "help", None) or ""
            out.append(
                f"| `{_arg_name(p)}` | {_cell(_type_name(p, ctx))} | "
                f"{'yes' if p.required else 'no'} | {_cell(help_)} |"
            )
        out.append("")
    if opts:
        out += ["| option | type | default | help |", "|---|---|---|---|"]
        for p in opts:
            names = ", ".join(f"`{n}`" for n in option_names(p))
            kind = "flag" if getattr(p, "is_flag", False) else _cell(_type_name(p, ctx))
            out.append(f"| {names} | {kind} | {_cell(_default(p))} | {_cell(p.help or '')} |")
        out.append("")
    if _is_group(cmd):
        subs = list(cmd.list_commands(ctx))
        if subs:
            out += ["Commands: " + ", ".join(f"`{name}`" for name in subs) + ".", ""]
    return "\n".join(out)


def markdown(root: Command | None = None) -> str:
    """The whole reference: one section per command, every option in a table."""
    root = root_command() if root is None else root
    return "\n".join(command_markdown(path, cmd) for path, cmd in walk(root))
