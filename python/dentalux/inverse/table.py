"""Spectral batches: a CSV of measurements per wavelength -> fits -> material spectrum TOML.

CSV columns: ``wavelength_nm,tt,tr,n,g,thickness_mm`` and optionally ``fd``, ``tt_err``,
``tr_err``; lines starting with ``#`` are comments. The TOML output is the shared material
spectrum format (``[materials.<name>]`` with wavelength_nm, mua, mus, g, fd, n, mua_ci,
mus_ci and a ``provenance`` table).
"""

from __future__ import annotations

import datetime as _dt
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import tomli_w

from dentalux import inputs
from dentalux.inverse.fit import fit
from dentalux.inverse.result import FitResult
from dentalux.progress import bar

REQUIRED = ("wavelength_nm", "tt", "tr", "n", "g", "thickness_mm")
OPTIONAL = ("fd", "tt_err", "tr_err")


def read_table(source) -> list[dict[str, float]]:
    """Rows of a measurement table from a CSV path, a DataFrame-like, a column mapping or rows.

    Raises FileNotFoundError for a missing file and ValueError naming a missing column or a
    cell that is not a number.
    """
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if not path.is_file():
            raise FileNotFoundError(f"measurement table {str(path)!r} not found")
        # UTF-8 (a BOM dropped), bounded fields, every row as long as the header
        _, rows = inputs.read_csv(path, "measurement table", comments=True)
        origin = str(path)
    elif hasattr(source, "to_dict"):  # pandas / polars-like DataFrame
        cols = source.to_dict("list") if callable(source.to_dict) else source.to_dict
        rows = _columns_to_rows(cols)
        origin = "dataframe"
    elif isinstance(source, Mapping):
        rows = _columns_to_rows(source)
        origin = "columns"
    elif isinstance(source, Sequence):
        rows = [dict(r) for r in source]
        origin = "rows"
    else:
        raise ValueError(f"table: expected a CSV path, a DataFrame or columns, got "
                         f"{type(source).__name__}")
    if not rows:
        raise ValueError(f"table {origin!r} has no data rows")
    out = []
    for i, row in enumerate(rows):
        line = row.get("_line")
        row = {str(k).strip(): v for k, v in row.items() if k is not None and k != "_line"}
        at = f"line {line}" if line is not None else f"row {i + 1}"
        missing = [c for c in REQUIRED if c not in row]
        if missing:
            raise ValueError(f"table {origin!r}: missing column(s) {', '.join(missing)} "
                             f"(required: {','.join(REQUIRED)}; optional: {','.join(OPTIONAL)})")
        rec = {}
        for key in REQUIRED + OPTIONAL:
            empty = key not in row or row[key] is None or (
                isinstance(row[key], str) and not row[key].strip())
            if empty and key in REQUIRED:  # was a bare KeyError: "error: thickness_mm"
                raise ValueError(f"table {origin!r} {at}: {key} is empty: needs a number")
            if empty:
                continue
            value = row[key]
            if isinstance(value, bool):
                raise ValueError(f"table {origin!r} {at}: {key} = {value!r} is not a number")
            try:
                x = float(value.strip() if isinstance(value, str) else value)
            except (TypeError, ValueError):
                raise ValueError(f"table {origin!r} {at}: {key} = {value!r} is not a "
                                 "number") from None
            if not math.isfinite(x):
                raise ValueError(f"table {origin!r} {at}: {key} = {value!r}: must be a finite "
                                 "number")
            rec[key] = x
        out.append(rec)
    return out


def check_spectrum_rows(rows: list[dict[str, float]], origin: str = "table") -> None:
    """Rows that become one material spectrum: each wavelength once, each a positive
    finite number (what the material library demands of ``wavelength_nm``)."""
    seen: dict[float, int] = {}
    for i, row in enumerate(rows):
        wl = row["wavelength_nm"]
        if not (math.isfinite(wl) and wl > 0):
            raise ValueError(f"table {origin!r} row {i + 1}: wavelength_nm = {wl!r} is out of "
                             "range: allowed a positive number of nm")
        if wl in seen:
            raise ValueError(f"table {origin!r}: rows {seen[wl] + 1} and {i + 1} are both at "
                             f"wavelength_nm = {wl:g}; a material spectrum needs each "
                             "wavelength once (average the measurements, or fit without "
                             "--out)")
        seen[wl] = i


def _columns_to_rows(cols: Mapping) -> list[dict]:
    keys = list(cols)
    lengths = {len(cols[k]) for k in keys}
    if len(lengths) != 1:
        raise ValueError("table: columns have different lengths")
    return [{k: cols[k][i] for k in keys} for i in range(lengths.pop())]


def fit_table(source, model: str = "mc", progress: bool | None = False,
              **options) -> list[FitResult]:
    """Fit every row of a measurement table (see :func:`read_table`); one result per row.

    ``options`` go to :func:`dentalux.inverse.fit` (tt_err/tr_err/fd columns override them
    per row). A progress bar is shown when ``progress`` is True (None: when interactive).
    """
    rows = read_table(source)
    results = []
    with bar(len(rows), f"fitting ({model})", progress) as cb:
        for i, row in enumerate(rows):
            kw = dict(options)
            for key in OPTIONAL:
                if key in row:
                    kw[key] = row[key]
            try:
                res = fit(tt=row["tt"], tr=row["tr"], n=row["n"], g=row["g"],
                          thickness=row["thickness_mm"], model=model,
                          wavelength_nm=row["wavelength_nm"], **kw)
            except ValueError as exc:
                raise ValueError(f"row {i + 1} (wavelength_nm = {row['wavelength_nm']}): "
                                 f"{exc}") from None
            results.append(res)
            if cb:
                cb(i + 1)
    return results


def write_spectrum_toml(results: list[FitResult], path, name: str, source: str,
                        description: str = "", notes: str = "",
                        date: str | None = None) -> dict:
    """Write fitted spectra as ``[materials.<name>]`` in the shared material TOML format.

    Returns the document written. ``source`` names the input file or reference.
    """
    if not results:
        raise ValueError("results: nothing to write")
    if any(r.wavelength_nm is None for r in results):
        raise ValueError("results: every fit needs a wavelength_nm for a spectrum file")
    order = sorted(range(len(results)), key=lambda i: results[i].wavelength_nm)
    rs = [results[i] for i in order]
    models = sorted({r.model for r in rs})
    unresolved = [r.wavelength_nm for r in rs if not r.mua_resolved]
    auto_notes = (
        f"Fitted with dentalux.inverse ({', '.join(models)}); mua_ci and mus_ci map the "
        f"measurement uncertainty (tt_err, tr_err = {rs[0].tt_err}, {rs[0].tr_err}) onto the "
        "coefficients."
    )
    if unresolved:
        auto_notes += (f" mua is not resolved at {unresolved} nm: use mua_ci's upper end as "
                       "an upper bound.")
    mat = {
        "description": description or f"fitted from {source}",
        "wavelength_nm": [float(r.wavelength_nm) for r in rs],
        "mua": [_r(r.mua) for r in rs],
        "mus": [_r(r.mus) for r in rs],
        "g": [float(r.g) for r in rs],
        "fd": [float(r.fd) for r in rs],
        "n": [float(r.n) for r in rs],
        "mua_ci": [[_r(v) for v in r.mua_ci] for r in rs],
        "mus_ci": [[_r(v) for v in r.mus_ci] for r in rs],
        "provenance": {
            "kind": "fitted",
            "source": source,
            "model": ",".join(models),
            "date": date or _dt.date.today().isoformat(),
            "notes": (notes + " " + auto_notes).strip(),
        },
    }
    doc = {"materials": {name: mat}}
    Path(path).write_bytes(tomli_w.dumps(doc).encode())
    return doc


def _r(v: float) -> float:
    """Six significant digits: more than the data carry, fewer than float noise."""
    return float(f"{v:.6g}") if math.isfinite(v) else v
