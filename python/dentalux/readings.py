"""Readings files: what a lab's spectrophotometer reads off its material discs.

One row per reading (docs/fitting.md):

- ``thickness_mm``: the disc's thickness [mm], > 0;
- ``backing``: ``black`` or ``white`` (the instrument's backings), a number, the backing's
  reflectance in [0, 1], or ``FILE.csv``, the backing's spectrum (columns ``wavelength_nm``,
  ``reflectance``; a relative path is taken from the readings file's folder);
- then either ``L,a,b`` (CIELAB, D65 and the 2° observer unless ``illuminant`` and
  ``observer`` columns say otherwise) or spectral reflectance columns ``r400 ... r700``:
  any subset of 360-780 nm on the 10 nm grid, reflectance as a fraction in [0, 1];
- optional ``sd_L, sd_a, sd_b`` or ``sd_r400 ...``: each reading's spread (one standard
  deviation, same units), for every column of its form or none.

When both forms are present the spectra are fitted and ``L,a,b`` are only checked for
range. Lines starting with ``#`` are comments (``shade --readings-out`` writes the
instrument, material and photons there). Every error names the file, line and column, and
nothing is fitted or written (exit code 2 from the command line).

API: :func:`load` -> :class:`Readings`; :func:`write` writes a reading from
``dentalux shade`` (:func:`dentalux.dental.shade`'s JSON) as rows of a readings file.
"""

from __future__ import annotations

import hashlib
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dentalux import inputs

#: the spectral grid a readings column may name [nm] (r360 ... r780, every 10 nm)
GRID_NM = (360.0, 780.0, 10.0)
BACKINGS = ("black", "white")
LAB_RANGES = {"L": (0.0, 100.0), "a": (-128.0, 127.0), "b": (-128.0, 127.0)}
OPTIONAL = ("illuminant", "observer")
#: what a backing spectrum must span for CIELAB-only readings [nm]
LAB_COVERAGE_NM = (400.0, 700.0)
_SPECTRAL = re.compile(r"^r(\d+(?:\.\d+)?)$")
_WHERE = "readings file"


@dataclass(frozen=True)
class BackingFile:
    """A backing given as a spectrum file: its name as the readings file writes it, and its
    wavelengths [nm] and reflectances."""

    name: str
    wavelength_nm: tuple[float, ...]
    reflectance: tuple[float, ...]

    @property
    def spectrum(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """As :func:`dentalux.dental.read` takes a backing spectrum."""
        return self.wavelength_nm, self.reflectance


@dataclass
class Reading:
    """One row: thickness [mm], backing ('black', 'white' or a reflectance), the measured
    CIELAB or spectrum (fractions at :attr:`Readings.wavelength_nm`) and their spreads."""

    line: int
    thickness_mm: float
    backing: str | float | BackingFile
    lab: tuple[float, float, float] | None = None
    spectrum: np.ndarray | None = None
    sd_lab: tuple[float, float, float] | None = None
    sd_spectrum: np.ndarray | None = None

    @property
    def backing_label(self) -> str:
        if isinstance(self.backing, BackingFile):
            return self.backing.name
        return self.backing if isinstance(self.backing, str) else f"{self.backing:g}"


@dataclass
class Readings:
    """A readings file, checked: its rows, form ('spectral' or 'lab') and sha256."""

    path: str
    rows: list[Reading]
    form: str
    wavelength_nm: list[float] = field(default_factory=list)
    illuminant: str = "D65"
    observer: str = "2"
    sha256: str = ""

    def conditions(self) -> set:
        """The distinct (thickness, backing) pairs read."""
        return {(r.thickness_mm, r.backing) for r in self.rows}


def _grid_column(col: str, where: str) -> float:
    lam = float(_SPECTRAL.match(col).group(1))
    lo, hi, step = GRID_NM
    k = (lam - lo) / step
    if not (lo <= lam <= hi) or abs(k - round(k)) > 1e-9:
        raise ValueError(f"{where}: column {col!r} is off the 10 nm grid: spectral columns are "
                         f"r{lo:.0f}, r{lo + step:.0f}, ... r{hi:.0f} (reflectance at that "
                         "wavelength [nm])")
    return lam


def _backing(row: dict, where: str, folder: Path, files: dict) -> str | float | BackingFile:
    raw = str(row.get("backing", "")).strip()
    key = f"{where}: line {row['_line']}: backing"
    if raw.lower() in BACKINGS:
        return raw.lower()
    if raw.lower().endswith(".csv"):
        if raw not in files:  # each file read once, however many rows name it
            files[raw] = backing_file(raw, folder, key)
        return files[raw]
    try:
        x = float(raw)
    except ValueError:
        raise ValueError(f"{key} = {raw!r}: allowed black, white, a reflectance in [0, 1] or "
                         "FILE.csv (a backing spectrum: wavelength_nm, reflectance)") from None
    return inputs.number(x, key, 0.0, 1.0)


def backing_file(name: str, folder: Path, key: str) -> BackingFile:
    """A backing spectrum file (``wavelength_nm``, ``reflectance``), ``name`` relative to
    ``folder``; ``key`` says where it was named, for errors."""
    path = Path(name) if Path(name).is_absolute() else folder / name
    if not path.is_file():
        raise ValueError(f"{key} = {name!r}: no such file ({path})")
    what = f"backing spectrum (named at {key})"
    header, rows = inputs.read_csv(path, what, comments=True)
    where = f"{what} {path}"
    missing = [c for c in ("wavelength_nm", "reflectance") if c not in header]
    if missing:
        raise ValueError(f"{where}: missing column(s) {', '.join(missing)}: a backing spectrum "
                         "has columns wavelength_nm, reflectance (a fraction in [0, 1])")
    if len(rows) < 2:
        raise ValueError(f"{where}: needs at least two rows (wavelength_nm, reflectance)")
    wl, refl = [], []
    for row in rows:
        w = inputs.cell(row, "wavelength_nm", where, 0.0, None, lo_open=True, unit="nm")
        if wl and w <= wl[-1]:
            raise ValueError(f"{where}: line {row['_line']}: wavelength_nm = {w:g} does not "
                             f"increase (the row before has {wl[-1]:g})")
        wl.append(w)
        refl.append(inputs.cell(row, "reflectance", where, 0.0, 1.0))
    return BackingFile(name=name, wavelength_nm=tuple(wl), reflectance=tuple(refl))


def _check_coverage(rows: list[Reading], bands: list[float], where: str) -> None:
    """A backing spectrum must span the bands read (it is not extrapolated)."""
    for r in rows:
        b = r.backing
        if isinstance(b, BackingFile) and (b.wavelength_nm[0] > bands[0]
                                           or b.wavelength_nm[-1] < bands[-1]):
            raise ValueError(f"{where}: line {r.line}: backing = {b.name!r} covers "
                             f"{b.wavelength_nm[0]:g}-{b.wavelength_nm[-1]:g} nm: it must span "
                             f"the readings' {bands[0]:g}-{bands[-1]:g} nm")


def _check_sd_sets(header: list[str], spectral: list[str], where: str) -> None:
    """Spreads come for a whole form or not at all: the fit reads sd_L, sd_a, sd_b together
    and sd_r... for every spectral column, so a partial set would be ignored unseen."""
    for form in ("Lab", spectral):
        sds = [f"sd_{c}" for c in form]
        given = [c for c in sds if c in header]
        if given and len(given) < len(sds):
            missing = [c for c in sds if c not in header]
            more = f" and {len(missing) - 3} more" if len(missing) > 3 else ""
            raise ValueError(f"{where}: column {given[0]} without {', '.join(missing[:3])}"
                             f"{more}: give the spread of every column of its form "
                             f"({sds[0]} ... {sds[-1]}) or of none")


def _uniform(rows, col: str, where: str, default: str) -> str:
    values = {str(r.get(col, "")).strip() for r in rows} - {""}
    if len(values) > 1:
        raise ValueError(f"{where}: column {col}: every reading must use the same value, "
                         f"found {', '.join(sorted(values))}")
    return values.pop() if values else default


def load(path, illuminant: str | None = None, observer: str | None = None) -> Readings:
    """Read and check a readings file (see module doc); a ValueError names row and column."""
    p = Path(path)
    header, rows = inputs.read_csv(p, _WHERE, comments=True)
    where = f"{_WHERE} {p}"
    if not rows:
        raise ValueError(f"{where}: empty (a header but no readings)")
    missing = [c for c in ("thickness_mm", "backing") if c not in header]
    spectral = [c for c in header if _SPECTRAL.match(c)]
    has_lab = all(c in header for c in "Lab")
    if not (spectral or has_lab) or any(c in header for c in "Lab"):  # L, a, b go together
        missing += [c for c in "Lab" if c not in header]
    if missing:
        raise ValueError(f"{where}: missing column(s) {', '.join(missing)}: a readings file "
                         "has thickness_mm, backing and either L,a,b or spectral columns "
                         "r400 ... r700")
    wl = [_grid_column(c, where) for c in spectral]
    order = np.argsort(wl)
    spectral = [spectral[i] for i in order]
    wl = [wl[i] for i in order]
    if len(set(wl)) != len(wl):
        raise ValueError(f"{where}: a wavelength has two spectral columns")
    for c in header:
        if c.startswith("sd_") and c[3:] not in header:
            raise ValueError(f"{where}: column {c!r} has no column {c[3:]!r} to qualify")
    _check_sd_sets(header, spectral, where)
    known = {"thickness_mm", "backing", *"Lab", *spectral, *OPTIONAL,
             *(f"sd_{c}" for c in (*"Lab", *spectral))}
    unknown = [c for c in header if c not in known]
    if unknown:
        raise ValueError(f"{where}: unknown column {unknown[0]!r}: allowed thickness_mm, "
                         "backing, L, a, b, r360 ... r780, sd_<column>, illuminant, observer")
    out = []
    files: dict = {}
    for row in rows:
        t = inputs.cell(row, "thickness_mm", where, 0.0, None, lo_open=True, unit="mm")
        r = Reading(line=row["_line"], thickness_mm=t,
                    backing=_backing(row, where, p.resolve().parent, files))
        if has_lab:
            r.lab = tuple(inputs.cell(row, c, where, *LAB_RANGES[c]) for c in "Lab")
            if all(f"sd_{c}" in header for c in "Lab"):
                r.sd_lab = tuple(inputs.cell(row, f"sd_{c}", where, 0.0) for c in "Lab")
        if spectral:
            r.spectrum = np.array([inputs.cell(row, c, where, 0.0, 1.0) for c in spectral])
            if all(f"sd_{c}" in header for c in spectral):
                r.sd_spectrum = np.array([inputs.cell(row, f"sd_{c}", where, 0.0)
                                          for c in spectral])
        out.append(r)
    _check_order(out, spectral, where)
    # a CIELAB-only fit reads LAB_COVERAGE_NM (readings_fit.LAB_BANDS beyond it are held
    # at the spectrum's ends, where the colour-matching functions are nearly zero)
    _check_coverage(out, wl or list(LAB_COVERAGE_NM), where)
    ill = illuminant or _uniform(rows, "illuminant", where, "D65")
    obs = observer or _uniform(rows, "observer", where, "2")
    from dentalux.color import system

    try:  # checked here, where the error can name the file
        system(ill, str(obs))
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    return Readings(path=str(p), rows=out, form="spectral" if spectral else "lab",
                    wavelength_nm=wl, illuminant=ill, observer=str(obs),
                    sha256=hashlib.sha256(p.read_bytes()).hexdigest())


def _check_order(rows: list[Reading], spectral: list[str], where: str) -> None:
    """A reading over white darker than over black at the same thickness is refused (two
    standard deviations of slack where spreads are given)."""
    by_t: dict[float, dict] = {}
    for r in rows:
        if isinstance(r.backing, str):
            by_t.setdefault(r.thickness_mm, {}).setdefault(r.backing, []).append(r)
    for t, group in by_t.items():
        for w in group.get("white", []):
            for b in group.get("black", []):
                if spectral:
                    sd = 2 * np.hypot(0 if w.sd_spectrum is None else w.sd_spectrum,
                                      0 if b.sd_spectrum is None else b.sd_spectrum)
                    bad = np.nonzero(w.spectrum < b.spectrum - sd)[0]
                    if bad.size:
                        c = spectral[int(bad[0])]
                        raise ValueError(
                            f"{where}: line {w.line}: column {c} = {w.spectrum[bad[0]]:g} over "
                            f"white is darker than over black ({b.spectrum[bad[0]]:g}, line "
                            f"{b.line}) at {t:g} mm: a white backing cannot darken a disc; are "
                            "the backings swapped?")
                elif w.lab is not None and b.lab is not None:
                    sd = 2 * math.hypot(0 if w.sd_lab is None else w.sd_lab[0],
                                        0 if b.sd_lab is None else b.sd_lab[0])
                    if w.lab[0] < b.lab[0] - sd:
                        raise ValueError(
                            f"{where}: line {w.line}: column L = {w.lab[0]:g} over white is "
                            f"darker than over black ({b.lab[0]:g}, line {b.line}) at {t:g} mm: "
                            "a white backing cannot darken a disc; are the backings swapped?")


# --- writing (dentalux shade --readings-out) -----------------------------------------------


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def rows_from_shade(out: dict, thickness_mm: float) -> tuple[list[str], list[list[str]]]:
    """Header and rows (over black, over white) of a readings file from ``shade --json``'s
    object: L,a,b with their standard errors and the spectra on the 10 nm grid."""
    wl = [float(w) for w in out["wavelength_nm"]]
    for w in wl:
        k = (w - GRID_NM[0]) / GRID_NM[2]
        if not (GRID_NM[0] <= w <= GRID_NM[1]) or abs(k - round(k)) > 1e-9:
            raise ValueError(f"--readings-out: band {w:g} nm is off the 10 nm grid of a readings "
                             "file (r360 ... r780): read with --bands on that grid")
    cols = [f"r{w:.0f}" for w in wl]
    header = ["thickness_mm", "backing", "L", "a", "b", "sd_L", "sd_a", "sd_b", *cols,
              *(f"sd_{c}" for c in cols)]
    rows = []
    for backing in BACKINGS:
        lab, se = out[f"lab_{backing}"], out["stderr"][f"lab_{backing}"]
        spec = out[f"reflectance_{backing}"]
        sspec = out.get(f"reflectance_{backing}_stderr") or [0.0] * len(spec)
        rows.append([_fmt(thickness_mm), backing, *map(_fmt, lab), *map(_fmt, se),
                     *(_fmt(min(max(x, 0.0), 1.0)) for x in spec), *map(_fmt, sspec)])
    return header, rows


def check_out(path) -> Path:
    """The ``--readings-out`` path, checked before anything is read."""
    from dentalux.output_paths import check_out_file

    return check_out_file(path, "--readings-out", (".csv",))


def comment_from_shade(out: dict, material, photons, seed) -> str:
    """The comment lines a written readings file starts with."""
    ins = out.get("instrument", {})
    bands = len(out.get("wavelength_nm") or []) or 1
    photons = out.get("photons", 0) // bands or photons  # the JSON's count is over all bands
    return (f"written by dentalux shade --readings-out: {material}, read with "
            f"{ins.get('name', '?')} ({photons} photons per band, "
            f"seed {seed}); sd_* are Monte Carlo standard errors\n"
            f"fit it: dentalux fit --readings FILE.csv --instrument {ins.get('name', '?')} "
            "--out MATERIAL.toml")


def write(path, out: dict, thickness_mm: float, comment: str = "") -> Path:
    """Write (or extend) a readings file with ``shade``'s reading over black and white.

    An existing file with the same header gains the two rows (so that several thicknesses
    go in one file); any other existing file is refused. Written atomically."""
    from dentalux.output_paths import atomic_file

    p = check_out(path)
    header, rows = rows_from_shade(out, thickness_mm)
    text = ""
    if p.exists():
        old = inputs.read_text(p, _WHERE)
        lines = [ln for ln in old.splitlines() if ln.strip() and not ln.startswith("#")]
        if not lines or lines[0].split(",") != header:
            raise ValueError(f"--readings-out = '{p}': the file exists with other columns (or "
                             "is not a readings file): give a new file")
        text = old if old.endswith("\n") else old + "\n"
    else:
        if comment:
            text += "".join(f"# {ln}\n" for ln in comment.splitlines())
        text += ",".join(header) + "\n"
    text += "".join(",".join(r) + "\n" for r in rows)
    with atomic_file(p, "--readings-out") as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return p
