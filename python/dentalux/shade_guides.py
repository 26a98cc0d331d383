"""Shade guides: the CIELAB of each tab of a guide, as far as published values were found.

The table is ``data/shade_guides.csv`` (one row per tab: guide, tab, L, a, b, the instrument
and geometry of the measurement, citation, doi, status, notes). A tab whose L*, a*, b* were
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
"""

from __future__ import annotations

import csv
import difflib
import math
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

    def source(self) -> dict:
        """Where the values came from, for a JSON report."""
        return {"guide": self.guide, "tab": self.tab, "status": self.status,
                "citation": self.citation, "doi": self.doi, "instrument": self.instrument,
                "geometry": self.geometry, "notes": self.notes}


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
                      notes=(row.get("notes") or "").strip())
            out.setdefault(tab.guide, {})[tab.tab] = tab
    return out


def guides() -> list[str]:
    """Every guide name in the table."""
    return list(_table())


def _guide(guide: str) -> dict[str, Tab]:
    table = _table()
    if not isinstance(guide, str) or guide not in table:
        near = difflib.get_close_matches(str(guide), table, n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise ValueError(f"shade guide {guide!r} is unknown{hint}: allowed {', '.join(table)}")
    return table[guide]


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
            f"docs/literature-dental.md){also}. Give the tab's measured values as "
            "lab:L,a,b instead")
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
                         "(data/shade_guides.csv; see docs/literature-dental.md)")
    ref = np.asarray(lab_value, dtype=float)
    if ref.shape != (3,) or not np.all(np.isfinite(ref)):
        raise ValueError(f"lab = {lab_value!r}: expected three finite numbers L*, a*, b*")
    de = np.asarray(delta_e00(np.array([t.lab for t in rows]), ref[None, :]), dtype=float)
    order = np.argsort(de, kind="stable")[:n]
    return [(rows[i].tab, float(de[i])) for i in order]
