"""The published colour of natural teeth (data/natural_teeth.csv) as a range to check against.

The range is the box mean ± 2 SD (about 95 % of teeth for a normal spread) in L*, a*, b* of
every study row that gives a mean and an SD for the region asked for ("derived" from the
published numbers); study means without an SD must fall inside it, which the tests check. The
rows, their instruments and their status words are in the CSV; docs/literature-dental.md
says what could not be read (regional cervical/middle/incisal means were not found).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

DATA = Path(__file__).parent / "data" / "natural_teeth.csv"
SPREAD = 2.0  # standard deviations either side of the mean


def rows() -> list[dict]:
    """The CSV rows, numbers as floats (None where empty)."""
    with open(DATA, newline="") as fh:
        out = []
        for r in csv.DictReader(fh):
            for k in ("L", "a", "b"):
                r[k] = float(r[k]) if r[k].strip() else None
            out.append(r)
    return out


def reference_range(region: str = "mid-incisal") -> dict:
    """{'L': (lo, hi), 'a': ..., 'b': ..., 'sources': [ids], 'rule': text} for the rows
    whose region starts with ``region``; a ValueError when no row has a mean and an SD."""
    rs = [r for r in rows() if r["region"].startswith(region)]
    means = {r["id"].rsplit("-", 1)[0]: r for r in rs if r["statistic"] == "mean"}
    sds = {r["id"].rsplit("-", 1)[0]: r for r in rs if r["statistic"] == "sd"}
    keys = [k for k in means if k in sds and None not in (means[k]["L"], sds[k]["L"])]
    if not keys:
        regions = sorted({r["region"] for r in rows()})
        raise ValueError(f"region = {region!r}: no study with a mean and an SD; rows exist "
                         f"for {', '.join(regions)}")
    out = {"sources": [means[k]["id"] for k in keys],
           "rule": f"mean ± {SPREAD:g} SD per study, union over studies (derived)"}
    for c in ("L", "a", "b"):
        out[c] = (min(means[k][c] - SPREAD * sds[k][c] for k in keys),
                  max(means[k][c] + SPREAD * sds[k][c] for k in keys))
    return out


def inside(lab, rng: dict) -> bool:
    """Whether CIELAB ``lab`` lies inside the range box."""
    return all(rng[c][0] <= float(v) <= rng[c][1] for c, v in zip("Lab", lab, strict=True))


def chroma_hue(lab) -> tuple[float, float]:
    """C*ab and h_ab [deg] of a CIELAB triple."""
    _, a, b = (float(x) for x in lab)
    return math.hypot(a, b), math.degrees(math.atan2(b, a)) % 360.0
