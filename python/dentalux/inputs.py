"""One home for the rules every user input file obeys, and the readers that enforce them.

Each reader of a user's file (instrument and material TOML, the measurement, substrate and
guide CSV tables, ``colour.json``) goes through these functions, so that one rule holds for
all of them (docs/limits.md):

- **text**: a file is read as UTF-8; a leading byte-order mark is dropped; any other encoding
  (Latin-1, UTF-16) or binary data (a NUL byte) is refused naming the file and the byte; a
  file larger than :data:`MAX_TEXT_BYTES` is refused before it is read;
- **structure**: tables and arrays nest at most :data:`MAX_DEPTH` deep (a parser's own
  recursion is never the error a user sees); an array holds at most :data:`MAX_ITEMS`
  values; a CSV field is at most :data:`MAX_CSV_FIELD` characters and every row has as many
  fields as the header, and a header names each column once;
- **values** (:func:`number`, :func:`integer`, :func:`text`, :func:`wavelengths`): strict
  types (no ``true`` for a number, no ``"4.0"`` for a number, no 3.5 for an integer), finite,
  inside a stated range; wavelength arrays strictly increasing (sorted, no duplicates) inside
  :data:`WAVELENGTH_RANGE_NM`; unknown keys refused (:func:`known_keys`).

Every error is a ``ValueError`` (exit code 2 from the command line) whose message starts
with the file (or ``what`` the caller names) and the key path, and states what is allowed.
"""

from __future__ import annotations

import csv
import json
import math
import sys
from numbers import Integral, Real
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

#: the largest text input (TOML, CSV, JSON) a command reads [bytes]
MAX_TEXT_BYTES = 64 * 1024 * 1024
#: tables and arrays nested deeper than this are refused (the deepest the formats need is 4)
MAX_DEPTH = 32
#: values in one array of an input file (a spectrum every 0.1 nm over 360-830 nm has 4 701)
MAX_ITEMS = 100_000
#: characters in one CSV field (Python's csv module's own limit, now with the file named)
MAX_CSV_FIELD = 131_072
#: the wavelengths an input spectrum may name [nm]: ultraviolet to mid-infrared; the colour
#: range (360-830 nm) lies well inside, and a value beyond is a typo or a unit mistake
WAVELENGTH_RANGE_NM = (100.0, 10_000.0)

_BOM = b"\xef\xbb\xbf"


# --- text ---------------------------------------------------------------------------------


def read_text(path, what: str = "file", max_bytes: int = MAX_TEXT_BYTES) -> str:
    """The text of ``path`` as UTF-8 (a BOM dropped); ``what`` names the kind of file
    ('instrument file', 'measurement table') in errors; larger than ``max_bytes`` is
    refused before it is read."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{what} {str(p)!r} not found")
    if not p.is_file():
        raise ValueError(f"{what} {str(p)!r}: not a regular file")
    size = p.stat().st_size
    if size > max_bytes:
        raise ValueError(f"{what} {p}: {size:,} bytes is too large: allowed at most "
                         f"{max_bytes:,} bytes")
    data = p.read_bytes()
    return decode(data, f"{what} {p}")


def decode(data: bytes, where: str) -> str:
    """``data`` as UTF-8 text, or a ValueError naming ``where``, the byte and the encoding."""
    if data.startswith(_BOM):
        data = data[len(_BOM):]
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise ValueError(f"{where}: UTF-16 text; save it as UTF-8")
    nul = data.find(b"\x00")
    if nul >= 0:
        raise ValueError(f"{where}: binary data (a NUL byte at offset {nul}), not UTF-8 text")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise ValueError(f"{where}: not UTF-8 text (byte 0x{data[exc.start]:02x} on line "
                         f"{line}; Latin-1 or another encoding?): save it as UTF-8") from None


# --- structure ----------------------------------------------------------------------------


def check_depth(doc, where: str, max_depth: int = MAX_DEPTH) -> None:
    """Refuse tables or arrays nested deeper than ``max_depth``, or arrays longer than
    :data:`MAX_ITEMS` (iteratively: a deep document cannot exhaust the stack here)."""
    stack = [(doc, 0, "")]
    while stack:
        node, depth, key = stack.pop()
        if isinstance(node, dict | list):
            if depth >= max_depth:
                raise ValueError(f"{where}: {key or 'the document'} nests tables or arrays "
                                 f"more than {max_depth} deep: allowed at most {max_depth}")
            items = node.items() if isinstance(node, dict) else enumerate(node)
            if isinstance(node, list) and len(node) > MAX_ITEMS:
                raise ValueError(f"{where}: {key} has {len(node):,} values: allowed at most "
                                 f"{MAX_ITEMS:,}")
            for k, v in items:
                if isinstance(v, dict | list):
                    sub = f"{key}[{k}]" if isinstance(node, list) else (
                        f"{key}.{k}" if key else str(k))
                    stack.append((v, depth + 1, sub))


def read_toml(path, what: str = "file") -> dict:
    """A TOML file read by the rules above: UTF-8, bounded size and depth; a syntax error
    names the file."""
    text = read_text(path, what)
    where = f"{what} {path}"
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{where}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ValueError(f"{where}: tables or arrays nested too deeply: allowed at most "
                         f"{MAX_DEPTH}") from None
    check_depth(doc, where)
    return doc


def loads_json(text: str, where: str) -> object:
    """Standard JSON (RFC 8259: no NaN or Infinity) with bounded depth."""
    def constant(name):
        raise ValueError(f"{where}: {name} is not a JSON number (RFC 8259)")

    try:
        doc = json.loads(text, parse_constant=constant)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where}: not valid JSON ({exc})") from None
    except RecursionError:
        raise ValueError(f"{where}: arrays or objects nested too deeply: allowed at most "
                         f"{MAX_DEPTH}") from None
    check_depth(doc, where)
    return doc


def read_json(path, what: str = "file") -> object:
    """A JSON file read by the rules above."""
    return loads_json(read_text(path, what), f"{what} {path}")


def read_csv(path, what: str = "table", comments: bool = False) -> tuple[list[str],
                                                                          list[dict]]:
    """A CSV file's header and rows (dicts keyed by the stripped header) by the rules
    above; every row must have as many fields as the header. ``comments``: lines starting
    with ``#`` and blank lines are skipped. Row numbers in errors are file line numbers."""
    text = read_text(path, what)
    where = f"{what} {path}"
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines(keepends=True))
             if not (comments and (line.lstrip().startswith("#") or not line.strip()))]
    return parse_csv(lines, where)


def parse_csv(lines: list[tuple[int, str]], where: str) -> tuple[list[str], list[dict]]:
    """Numbered lines -> header and rows (see :func:`read_csv`). One reader runs over all the
    lines, so a quoted field may span several; a row's number is the line it ends on."""
    old = csv.field_size_limit()
    csv.field_size_limit(MAX_CSV_FIELD)
    at = [0]

    def numbered():
        for lineno, line in lines:
            at[0] = lineno
            yield line

    reader = csv.reader(numbered())
    try:
        header: list[str] | None = None
        rows = []
        while True:
            try:
                fields = next(reader)
            except StopIteration:
                break
            except csv.Error as exc:
                raise ValueError(f"{where}: line {at[0]}: {exc} (a field may hold at most "
                                 f"{MAX_CSV_FIELD:,} characters)") from None
            lineno = at[0]
            if any(len(f) > MAX_CSV_FIELD for f in fields):
                raise ValueError(f"{where}: line {lineno}: a field longer than "
                                 f"{MAX_CSV_FIELD:,} characters")
            if header is None:
                if not fields or not any(f.strip() for f in fields):
                    continue
                header = [f.strip() for f in fields]
                _check_unique(header, where, lineno)
                continue
            if not fields:
                continue
            if len(fields) != len(header):
                short = header[len(fields):] if len(fields) < len(header) else []
                detail = (f"missing {', '.join(short)}" if short
                          else f"{len(fields) - len(header)} field(s) more than the header")
                raise ValueError(f"{where}: line {lineno} has {len(fields)} field(s) but the "
                                 f"header has {len(header)} ({detail})")
            rows.append({"_line": lineno, **dict(zip(header, fields, strict=True))})
    finally:
        csv.field_size_limit(old)
    if header is None:
        raise ValueError(f"{where}: empty (no header line)")
    return header, rows


def _check_unique(header: list[str], where: str, lineno: int) -> None:
    """A column named twice would be read from one of its copies, the other ignored."""
    seen = set()
    for name in header:
        if name and name in seen:
            raise ValueError(f"{where}: line {lineno}: column {name!r} appears twice in the "
                             "header: each column once")
        seen.add(name)


# --- values -------------------------------------------------------------------------------


def _range_text(lo, hi, lo_open, hi_open, unit) -> str:
    if lo is None and hi is None:
        return "a finite number" + (f" [{unit}]" if unit else "")
    left = "(" if lo_open or lo is None else "["
    right = ")" if hi_open or hi is None else "]"
    lo_t = "-inf" if lo is None else f"{lo:g}"
    hi_t = "inf" if hi is None else f"{hi:g}"
    return f"{left}{lo_t}, {hi_t}{right}" + (f" {unit}" if unit else "")


def number(value, key: str, lo: float | None = None, hi: float | None = None,
           lo_open: bool = False, hi_open: bool = False, unit: str = "") -> float:
    """``value`` as a finite float inside the range, strictly typed: a bool, a string or
    None is refused. ``key`` is the file and key path (or argument) named in errors."""
    allowed = _range_text(lo, hi, lo_open, hi_open, unit)
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"{key} = {value!r}: must be a number (not "
                         f"{type(value).__name__}): allowed {allowed}")
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"{key} = {value!r}: must be a finite number: allowed {allowed}")
    if (lo is not None and (x <= lo if lo_open else x < lo)) or \
            (hi is not None and (x >= hi if hi_open else x > hi)):
        raise ValueError(f"{key} = {value!r} is out of range: allowed {allowed}")
    return x


def integer(value, key: str, lo: int | None = None, hi: int | None = None,
            unit: str = "") -> int:
    """``value`` as an int inside [lo, hi]: a bool, a string or a float that is not a whole
    number is refused (never truncated)."""
    lo_t = "-inf" if lo is None else f"{lo:,}"
    hi_t = "inf" if hi is None else f"{hi:,}"
    allowed = f"{lo_t} ... {hi_t}" + (f" {unit}" if unit else "")
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"{key} = {value!r}: must be an integer (not "
                         f"{type(value).__name__}): allowed {allowed}")
    if isinstance(value, Integral):
        n = int(value)
    else:
        x = float(value)
        if not (math.isfinite(x) and x == int(x)):
            raise ValueError(f"{key} = {value!r}: must be a whole number (it would be "
                             f"truncated): allowed {allowed}")
        n = int(x)
    if (lo is not None and n < lo) or (hi is not None and n > hi):
        raise ValueError(f"{key} = {value!r} is out of range: allowed {allowed}")
    return n


def text(value, key: str) -> str:
    """A string (not a number or a table)."""
    if not isinstance(value, str):
        raise ValueError(f"{key} = {value!r}: must be a string, got {type(value).__name__}")
    return value


def table(value, key: str) -> dict:
    """A table (dict)."""
    if not isinstance(value, dict):
        raise ValueError(f"{key} = {value!r}: must be a table, got {type(value).__name__}")
    return value


def known_keys(tbl: dict, allowed, key: str) -> None:
    """Refuse a key of ``tbl`` that is not in ``allowed``."""
    unknown = sorted(str(k) for k in set(tbl) - set(allowed))
    if unknown:
        raise ValueError(f"{key}: unknown key {unknown[0]!r}: allowed "
                         f"{', '.join(sorted(allowed))}")


def numbers(values, key: str, lo: float | None = None, hi: float | None = None,
            lo_open: bool = False, hi_open: bool = False, unit: str = "",
            min_len: int = 1) -> list[float]:
    """A non-empty list of strict numbers in range (each error names ``key[i]``)."""
    if isinstance(values, str | bytes | dict) or not hasattr(values, "__len__"):
        raise ValueError(f"{key} = {values!r}: must be a list of numbers")
    if len(values) < min_len or len(values) > MAX_ITEMS:
        raise ValueError(f"{key}: {len(values)} values: allowed {min_len} ... {MAX_ITEMS:,}")
    return [number(v, f"{key}[{i}]", lo, hi, lo_open, hi_open, unit)
            for i, v in enumerate(values)]


def wavelengths(values, key: str) -> list[float]:
    """A list of wavelengths [nm]: strict numbers in :data:`WAVELENGTH_RANGE_NM`, strictly
    increasing (sorted, each once)."""
    lo, hi = WAVELENGTH_RANGE_NM
    out = numbers(values, key, lo, hi, unit="nm")
    for i in range(1, len(out)):
        if out[i] <= out[i - 1]:
            what = "repeats" if out[i] == out[i - 1] else "is below"
            raise ValueError(f"{key}[{i}] = {out[i]:g} nm {what} the value before it "
                             f"({out[i - 1]:g} nm): wavelengths must be strictly increasing "
                             "(sorted, each once)")
    return out


def cell(row: dict, column: str, where: str, lo: float | None = None,
         hi: float | None = None, lo_open: bool = False, unit: str = "") -> float:
    """One numeric CSV cell of a row from :func:`read_csv`, finite and in range."""
    key = f"{where}: line {row.get('_line', '?')}: {column}"
    raw = row.get(column)
    if raw is None or str(raw).strip() == "":
        raise ValueError(f"{key} is empty: needs a number")
    try:
        x = float(str(raw).strip())
    except ValueError:
        raise ValueError(f"{key} = {raw!r} is not a number") from None
    return number(x, key, lo, hi, lo_open, unit=unit)
