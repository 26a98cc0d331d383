"""Shade guides: the CIELAB of each tab of a guide, as far as published values were found.

The table is ``data/shade_guides.csv`` (one row per tab: guide, tab, L, a, b, the illuminant
and observer of L, a, b where the source states them, the instrument and geometry of the
measurement, citation, doi, status, notes). A tab whose L*, a*, b* were
not found in any readable source has empty values and status ``not-found``
(docs/literature-dental.md says what was searched); :func:`lab` refuses such a tab rather
than guess. Guide names are the table's first column; a guide name with an ``@source``
suffix (``vita-classical@sahrir2024``) is a single source's row kept apart from the guide's
own tab values.

API (plain on purpose, shared by ``dentalux design --target GUIDE:TAB`` and
``dentalux shade --match``):

- :func:`guides` -> the guide names;
- :func:`load(guide)` -> {tab: :class:`Tab`} in table order;
- :func:`lab(guide, tab)` -> (L, a, b), or a ValueError naming the tab or guide;
- :func:`nearest(lab, guide, n)` -> the n tabs with published values nearest in ΔE00.

A guide is also a lab's own (docs/fitting.md): a CSV file ``tab,L,a,b`` (or spectral
columns ``r400 ... r700``, converted under the file's illuminant and observer) with optional
``instrument, illuminant, observer, source, date`` columns, named by its path
(``FILE.csv``) or imported under a name with :func:`import_guide` (``dentalux guides
import``) into the per-user data folder (:func:`data_dir`: platformdirs' user data folder,
or ``$DENTALUX_DATA``). Built-in names cannot be taken by an imported guide.
"""

from __future__ import annotations

import csv
import difflib
import math
import os
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data" / "shade_guides.csv"


@dataclass(frozen=True)
class Tab:
    """One row of the table: the tab's CIELAB (None where not found) and where it came from."""

    guide: str
    tab: str
    lab: tuple[float, float, float] | None
    status: str
    citation: str
    doi: str
    instrument: str
    geometry: str
    notes: str
    illuminant: str = ""  # of L*, a*, b*; empty where the source does not say
    observer: str = ""

    def source(self) -> dict:
        """Where the values came from, for a JSON report."""
        return {"guide": self.guide, "tab": self.tab, "status": self.status,
                "citation": self.citation, "doi": self.doi, "instrument": self.instrument,
                "geometry": self.geometry, "illuminant": self.illuminant,
                "observer": self.observer, "notes": self.notes}


def _float(text: str) -> float | None:
    text = (text or "").strip()
    if not text:
        return None
    x = float(text)
    return x if math.isfinite(x) else None


@lru_cache(maxsize=1)
def _table() -> dict[str, dict[str, Tab]]:
    out: dict[str, dict[str, Tab]] = {}
    with open(DATA, newline="", encoding="utf-8") as fh:
        for row in csv.DictReader(fh):
            values = [_float(row.get(k, "")) for k in ("L", "a", "b")]
            lab = tuple(values) if all(v is not None for v in values) else None
            tab = Tab(guide=row["guide"].strip(), tab=row["tab"].strip(), lab=lab,
                      status=(row.get("status") or "").strip(),
                      citation=(row.get("citation") or "").strip(),
                      doi=(row.get("doi") or "").strip(),
                      instrument=(row.get("instrument") or "").strip(),
                      geometry=(row.get("geometry") or "").strip(),
                      notes=(row.get("notes") or "").strip(),
                      illuminant=(row.get("illuminant") or "").strip(),
                      observer=(row.get("observer") or "").strip())
            out.setdefault(tab.guide, {})[tab.tab] = tab
    return out


# --- a lab's own guides ---------------------------------------------------------------------

GUIDE_COLUMNS = ("tab", "L", "a", "b")
GUIDE_OPTIONAL = ("instrument", "illuminant", "observer", "source", "date")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")
_SPECTRAL = re.compile(r"^r(\d+(?:\.\d+)?)$")
IMPORT_HOW = ("measure your own guide with your instrument and import it: dentalux guides "
              "import FILE.csv --name NAME (columns tab,L,a,b[,instrument,...]; docs/fitting.md), "
              "then name NAME:TAB or FILE.csv:TAB")


def data_dir() -> Path:
    """The per-user data folder: ``$DENTALUX_DATA`` or platformdirs' user data folder."""
    env = os.environ.get("DENTALUX_DATA")
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_data_dir("dentalux", appauthor=False))


def _guides_dir() -> Path:
    return data_dir() / "guides"


def imported() -> list[str]:
    """Names of the guides imported into the user's data folder."""
    d = _guides_dir()
    return sorted(p.stem for p in d.glob("*.csv")) if d.is_dir() else []


def read_guide_file(path, guide: str | None = None) -> dict[str, Tab]:
    """A guide CSV read and checked (see module doc); errors name line and column."""
    from dentalux import inputs, readings

    p = Path(path)
    header, rows = inputs.read_csv(p, "shade guide", comments=True)
    where = f"shade guide {p}"
    if not rows:
        raise ValueError(f"{where}: empty (a header but no tabs)")
    spectral = [c for c in header if _SPECTRAL.match(c)]
    need = ["tab"] + ([] if spectral else ["L", "a", "b"])
    missing = [c for c in need if c not in header]
    if missing:
        raise ValueError(f"{where}: missing column(s) {', '.join(missing)}: a guide has "
                         "tab,L,a,b (or spectral columns r400 ... r700) and optionally "
                         f"{', '.join(GUIDE_OPTIONAL)}")
    known = {*GUIDE_COLUMNS, *GUIDE_OPTIONAL, *spectral}
    unknown = [c for c in header if c not in known]
    if unknown:
        raise ValueError(f"{where}: unknown column {unknown[0]!r}: allowed "
                         f"{', '.join(GUIDE_COLUMNS + GUIDE_OPTIONAL)}, r360 ... r780")
    wl = [readings._grid_column(c, where) for c in spectral]
    name = guide or p.stem
    out: dict[str, Tab] = {}
    seen: dict[str, int] = {}
    for row in rows:
        line = row["_line"]
        tab_name = str(row.get("tab", "")).strip()
        if not tab_name:
            raise ValueError(f"{where}: line {line}: tab is empty")
        if tab_name in seen:
            raise ValueError(f"{where}: line {line}: tab {tab_name!r} repeats line "
                             f"{seen[tab_name]}: each tab once (a duplicate tab is refused)")
        seen[tab_name] = line
        ill = str(row.get("illuminant", "") or "D65").strip() or "D65"
        obs = str(row.get("observer", "") or "2").strip() or "2"
        if spectral:
            from dentalux.color import system
            from dentalux.spectra import Reconstruction

            r = np.array([inputs.cell(row, c, where, 0.0, 1.0) for c in spectral])
            cs = system(ill, obs)
            rec = Reconstruction(wl, grid=cs.wavelengths, basis="hold")
            lab_v = tuple(float(x) for x in cs.XYZ_to_Lab(cs.grid_to_XYZ(rec(r))))
        else:
            lab_v = tuple(inputs.cell(row, c, where, *readings.LAB_RANGES[c]) for c in "Lab")
        meta = {k: str(row.get(k, "") or "").strip() for k in GUIDE_OPTIONAL}
        out[tab_name] = Tab(
            guide=name, tab=tab_name, lab=lab_v, status="measured",
            citation=meta["source"] or f"the lab's own guide ({p.name})", doi="",
            instrument=meta["instrument"], geometry="", illuminant=ill, observer=obs,
            notes=f"imported from {p.name}; illuminant {ill}, observer {obs}"
                  + (f", read {meta['date']}" if meta["date"] else ""))
    return out


def import_guide(path, name: str, replace: bool = False) -> Path:
    """Check a guide CSV and copy it into the user's data folder as ``name``."""
    from dentalux.output_paths import atomic_file

    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(f"--name = {name!r}: allowed letters, digits, '.', '_', '-' (at most "
                         "64, starting with a letter or digit)")
    if name in _table():
        raise ValueError(f"--name = {name!r} is a built-in guide: choose another name")
    read_guide_file(path, name)  # refuse a bad file before anything is written
    dest = _guides_dir() / f"{name}.csv"
    if dest.exists() and not replace:
        raise ValueError(f"guide {name!r} is already imported ({dest}): give --replace to "
                         "replace it")
    with atomic_file(dest, "guide") as tmp:
        tmp.write_bytes(Path(path).read_bytes())
    return dest


def guide_file(guide: str) -> Path | None:
    """The CSV behind an imported guide name or a FILE.csv, or None (built-in or unknown)."""
    if not isinstance(guide, str):
        return None
    if guide in imported():
        return _guides_dir() / f"{guide}.csv"
    if guide.lower().endswith(".csv"):
        p = Path(guide)
        if not p.is_file():
            raise FileNotFoundError(f"shade guide file {guide!r} not found")
        return p
    return None


def is_guide(guide: str) -> bool:
    """Whether ``guide`` names a built-in guide, an imported one or a guide file."""
    return isinstance(guide, str) and (guide in _table() or guide in imported()
                                       or guide.lower().endswith(".csv"))


def instruments_of(guide: str) -> list[str]:
    """The instruments named by the tabs of a guide (empty where none is named)."""
    return sorted({t.instrument for t in _guide(guide).values() if t.instrument})


def instrument_note(guide: str, inst, key: str = "shade_match_instrument",
                    illuminant=None, observer=None) -> dict:
    """``shade_match_instrument``: the guide's instrument against the reading's, and a note
    when they differ (or the guide names none). Given the reading's ``illuminant`` and
    ``observer``, also ``guide_illuminant`` and a note when the tabs' L*a*b* are for another
    illuminant or observer (ΔE00 across two whites means little)."""
    name = getattr(inst, "name", str(inst))
    theirs = instruments_of(guide)
    same = theirs == [name]
    if same:
        note = ""
    elif not theirs:
        note = (f"the guide names no instrument; the reading is {name}'s: tab colours "
                "read with another instrument or geometry differ from this reading's")
    else:
        note = (f"the guide was read with {', '.join(theirs)}, the reading with {name}: "
                "another instrument or geometry reads the same tab differently")
    out = {"guide": guide, "guide_instrument": theirs, "reading_instrument": name,
           "same": same, "note": note}
    if illuminant is not None:
        mine = f"{getattr(illuminant, 'value', illuminant)}/{getattr(observer, 'value', observer)}"
        lit = sorted({f"{t.illuminant}/{t.observer or '?'}" for t in _guide(guide).values()
                      if t.illuminant and t.lab is not None})
        out["guide_illuminant"] = lit
        if lit and lit != [mine]:
            out["note"] = "; ".join(x for x in (note, (
                f"the guide's L*a*b* are for {', '.join(lit)} (illuminant/observer), the "
                f"reading's for {mine}: read under the guide's illuminant and observer "
                "before comparing")) if x)
    return {key: out}


def guides() -> list[str]:
    """Every guide name: the table's, then the imported ones."""
    return list(_table()) + [g for g in imported() if g not in _table()]


def _guide(guide: str) -> dict[str, Tab]:
    table = _table()
    if isinstance(guide, str) and guide in table:
        return table[guide]
    path = guide_file(guide)
    if path is not None:
        return read_guide_file(path, guide)
    allowed = guides()
    near = difflib.get_close_matches(str(guide), allowed, n=1)
    hint = f" (did you mean {near[0]!r}?)" if near else ""
    raise ValueError(f"shade guide {guide!r} is unknown{hint}: allowed {', '.join(allowed)}, "
                     "an imported guide (dentalux guides import) or a guide FILE.csv")


def load(guide: str) -> dict[str, Tab]:
    """The tabs of ``guide`` in table order (values None where not found)."""
    return dict(_guide(guide))


def tab(guide: str, name: str) -> Tab:
    """One tab's row, or a ValueError naming the allowed tabs."""
    tabs = _guide(guide)
    if name not in tabs:
        raise ValueError(f"tab {name!r} is not in shade guide {guide!r}: allowed "
                         f"{', '.join(tabs)}")
    return tabs[name]


def lab(guide: str, name: str) -> tuple[float, float, float]:
    """(L*, a*, b*) of a tab; a ValueError when the table holds no published values for it."""
    row = tab(guide, name)
    if row.lab is None:
        others = [f"{g}:{name}" for g, tabs in _table().items()
                  if g != guide and g.split("@")[0] == guide and name in tabs
                  and tabs[name].lab is not None]
        also = (f"; the table keeps a separate single-source row {', '.join(others)} "
                "(read its notes before using it)") if others else ""
        raise ValueError(
            f"tab {guide}:{name}: no published CIELAB is in the shade-guide table "
            f"(status {row.status or 'empty'}, data/shade_guides.csv; see "
            f"docs/literature-dental.md){also}. The way forward: {IMPORT_HOW}; or give "
            "the tab's measured values as lab:L,a,b")
    return row.lab


def nearest(lab_value, guide: str, n: int = 3) -> list[tuple[str, float]]:
    """The ``n`` tabs of ``guide`` with published values nearest to ``lab_value`` in ΔE00,
    as (tab, ΔE00), nearest first; a ValueError if no tab of the guide has values."""
    from dentalux.color import delta_e00

    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"n = {n!r}: must be an integer >= 1")
    rows = [t for t in _guide(guide).values() if t.lab is not None]
    if not rows:
        raise ValueError(f"shade guide {guide!r}: no tab has published CIELAB in the table "
                         "(data/shade_guides.csv; see docs/literature-dental.md). The way "
                         f"forward: {IMPORT_HOW}")
    ref = np.asarray(lab_value, dtype=float)
    if ref.shape != (3,) or not np.all(np.isfinite(ref)):
        raise ValueError(f"lab = {lab_value!r}: expected three finite numbers L*, a*, b*")
    de = np.asarray(delta_e00(np.array([t.lab for t in rows]), ref[None, :]), dtype=float)
    order = np.argsort(de, kind="stable")[:n]
    return [(rows[i].tab, float(de[i])) for i in order]
