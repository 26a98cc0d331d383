"""Where the commands may write, and how: checked before any work starts, written atomically.

- :func:`check_out_file` / :func:`check_out_dir` refuse, before a run starts, an output
  path that is empty, under ``/dev``, ``/proc`` or ``/sys``, a folder where a file is meant
  (or the reverse), below a file, in a folder without write permission, or a file with the
  wrong suffix (nothing is appended to a name: ``--profiles p.txt`` is refused, never
  turned into ``p.txt.npz``). An existing file given as a *file* output is replaced (the
  usual ``-o FILE`` convention); an existing non-empty *folder* output is refused unless
  ``overwrite`` is set (``--overwrite``).
- :func:`atomic_file` and :func:`staged_dir` write to temporary names in the target folder
  and rename only when every file is complete, so a failed run (full disk, an error,
  Ctrl-C) leaves nothing under the final names; :class:`OutputError` says what was left.

docs/limits.md documents the rules.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
from pathlib import Path

#: folders no output may go into (devices and kernel interfaces)
FORBIDDEN_ROOTS = ("/dev", "/proc", "/sys")
#: prefix of the temporary files and folders a run writes before renaming them
TMP_PREFIX = ".dentalux-partial-"


def _umask_mode(mode: int) -> int:
    """``mode`` less this process's umask (mkstemp and mkdtemp create 0600 and 0700)."""
    mask = os.umask(0)
    os.umask(mask)
    return mode & ~mask


class OutputError(ValueError):
    """An output that cannot be written; the message names the option and the path."""


def _raw(path) -> str:
    if path is None:
        raise OutputError("output path is missing")
    text = os.fspath(path)
    if not isinstance(text, str):
        text = os.fsdecode(text)
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as exc:
        # a name that is not UTF-8 cannot be recorded in the JSON that lists the outputs
        bad = os.fsencode(text[exc.start:exc.end])
        raise OutputError(f"output path {os.fsencode(text)!r}: not a UTF-8 name (byte "
                          f"0x{bad[0]:02x}); give a UTF-8 name") from None
    return text


def _forbidden(p: Path) -> bool:
    for q in (p, p.resolve()):
        s = str(q)
        if any(s == r or s.startswith(r + "/") for r in FORBIDDEN_ROOTS):
            return True
    return False


def _check_parent(p: Path, field: str) -> None:
    """The nearest existing ancestor of ``p`` must be a writable folder."""
    parent = p.parent if str(p.parent) else Path(".")
    anc = parent
    while not anc.exists() and anc != anc.parent:
        if anc.is_symlink():  # a dangling link
            raise OutputError(f"{field} = '{p}': {anc} is a broken symbolic link")
        anc = anc.parent
    if not anc.is_dir():
        raise OutputError(f"{field} = '{p}': {anc} is a file, not a folder")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise OutputError(f"{field} = '{p}': no permission to write in {anc}")


def check_out_file(path, field: str, suffixes: tuple[str, ...]) -> Path:
    """A file the command will write: its name must end in one of ``suffixes``."""
    text = _raw(path)
    if not text.strip():
        raise OutputError(f"{field} = {text!r}: an empty path; give a file name ending in "
                          f"{' or '.join(suffixes)}")
    p = Path(text)
    if _forbidden(p):
        raise OutputError(f"{field} = '{p}': refusing to write under "
                          f"{', '.join(FORBIDDEN_ROOTS)}")
    if text.endswith(os.sep) or p.is_dir():
        raise OutputError(f"{field} = '{p}': is a folder; give a file name ending in "
                          f"{' or '.join(suffixes)}")
    if p.suffix.lower() not in suffixes:
        raise OutputError(f"{field} = '{p}': the file name must end in "
                          f"{' or '.join(suffixes)}")
    if p.exists() and not p.is_file():
        raise OutputError(f"{field} = '{p}': exists and is not a regular file")
    if p.is_file() and not os.access(p, os.W_OK):
        raise OutputError(f"{field} = '{p}': exists and is not writable")
    _check_parent(p, field)
    return p


def check_out_dir(path, field: str, overwrite: bool = False) -> Path:
    """A folder the command will create or fill: refused when it is a file, or exists
    with files in it unless ``overwrite``."""
    text = _raw(path)
    if not text.strip():
        raise OutputError(f"{field} = {text!r}: an empty path; give a folder (e.g. "
                          f"{field} out)")
    p = Path(text)
    if _forbidden(p):
        raise OutputError(f"{field} = '{p}': refusing to write under "
                          f"{', '.join(FORBIDDEN_ROOTS)}")
    if p.exists() and not p.is_dir():
        raise OutputError(f"{field} = '{p}': exists and is not a folder")
    if p.is_dir():
        if not os.access(p, os.W_OK | os.X_OK):
            raise OutputError(f"{field} = '{p}': no permission to write in it")
        if any(not e.name.startswith(TMP_PREFIX) for e in p.iterdir()) and not overwrite:
            raise OutputError(f"{field} = '{p}': the folder is not empty; choose a new or "
                              "empty folder, or add --overwrite to replace its files")
    else:
        _check_parent(p, field)
    return p


def _describe(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.errno == errno.ENOSPC:
        return "no space left on the device"
    if isinstance(exc, OSError):
        return exc.strerror or str(exc)
    return str(exc) or type(exc).__name__


@contextlib.contextmanager
def atomic_file(path, field: str = "output"):
    """Yield a temporary path beside ``path`` (same suffix, so writers add nothing); rename
    it to ``path`` when the block finishes, delete it when the block fails. An OSError
    becomes :class:`OutputError` saying that nothing was written under ``path``."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=TMP_PREFIX, suffix=p.suffix, dir=p.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        os.chmod(tmp, _umask_mode(0o666))
        yield tmp
        os.replace(tmp, p)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"{field} = '{p}': cannot write it ({_describe(exc)}); nothing "
                          "was written under that name") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextlib.contextmanager
def staged_dir(out, field: str = "--out"):
    """Yield a temporary folder in which to write a command's files; when the block
    finishes, move them into ``out`` (a new folder is renamed in one step; into an existing
    one each file is renamed, a file named ``render.json`` last). On failure the temporary
    folder is removed and ``out`` is left as it was."""
    out = Path(out)
    new = not out.exists()
    if new:
        out.parent.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=TMP_PREFIX + out.name + "-", dir=out.parent))
    else:
        stage = Path(tempfile.mkdtemp(prefix=TMP_PREFIX, dir=out))
    try:
        if new:
            os.chmod(stage, _umask_mode(0o777))
        yield stage
        _rebase_json_files(stage, out)
        for f in stage.iterdir():
            if f.is_file() and not f.is_symlink():
                os.chmod(f, _umask_mode(0o666))
        if new:
            os.rename(stage, out)
        else:
            names = sorted((e.name for e in stage.iterdir()), key=lambda n: n == "render.json")
            for name in names:
                target = out / name
                if target.is_dir() and not target.is_symlink():
                    shutil.rmtree(target)
                os.replace(stage / name, target)
            stage.rmdir()
    except OSError as exc:
        shutil.rmtree(stage, ignore_errors=True)
        if new and out.exists() and not any(out.iterdir()):
            out.rmdir()
        raise OutputError(f"{field} = '{out}': cannot write the outputs ({_describe(exc)}); "
                          f"nothing was written under {out}"
                          + ("" if new else " (its earlier files are unchanged)")) from None
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise


def _rebase_json_files(stage: Path, out: Path, max_bytes: int = 16 << 20) -> None:
    """Rewrite the JSON files written in ``stage`` (colour.json, tooth.json, ...) so that the
    paths they record point under ``out``, where the files finally are, not into the
    temporary folder that is gone once the block ends."""
    import json

    from dentalux.strict_json import dumps_strict

    for f in stage.iterdir():
        if f.suffix != ".json" or not f.is_file() or f.is_symlink() \
                or f.stat().st_size > max_bytes:
            continue
        text = f.read_text(encoding="utf-8")
        if str(stage) not in text and json.dumps(str(stage))[1:-1] not in text:
            continue
        f.write_text(dumps_strict(rebase(json.loads(text), stage, out), indent=2),
                     encoding="utf-8")


def rebase(obj, old: Path, new: Path):
    """Copy of ``obj`` (dicts, lists, strings) with path strings under ``old`` moved to
    ``new``: the paths a summary records while writing into a staging folder."""
    o, n = str(old), str(new)
    if isinstance(obj, str):
        return n + obj[len(o):] if obj == o or obj.startswith(o + os.sep) else obj
    if isinstance(obj, dict):
        return {k: rebase(v, old, new) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return type(obj)(rebase(v, old, new) for v in obj)
    return obj
