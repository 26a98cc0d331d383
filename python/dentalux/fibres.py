"""A fibre-optic probe's tip: where its fibres lie, which light the specimen, which receive,
and the receivers' acceptance (docs/instruments.md, "Several fibres").

A tip is a disc of ``tip_diameter_mm`` holding round fibres, each at (``x_mm``, ``y_mm``)
from the tip's centre with its core's ``diameter_mm`` and a ``role``: ``source`` (lights the
specimen), ``receiver`` (its light goes to the spectrometer) or ``both`` (a bifurcated fibre
that does both). A receiver may name its acceptance, as ``acceptance_deg`` (the half-angle of
its cone) or ``numerical_aperture`` (NA = sin of that half-angle). The acceptance is
the cone in the medium above the specimen, air in dentalux's readings: light leaving the
specimen is read where its refracted direction in air lies within the half-angle of the
normal (a fibre's NA is its half-angle in air, n0 sin(theta) with n0 = 1; transcribed:
ies.org "acceptance half-angle", fiber-optics.info "acceptance angle").

What a reading makes of a layout (:meth:`Layout.pairs`): every source lights its disc
uniformly along the normal, its share of the power in proportion to its area (every source
fibre carries the same radiance); the receivers' signals add. Only one side of a pair can
carry a cone in the layered solver (the reciprocal form reads into a cone from a beam), so a
source's own emission cone is not modelled: it lights as a collimated beam.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dentalux import inputs

ROLES = ("source", "receiver", "both")
FIBRE_KEYS = ("x_mm", "y_mm", "diameter_mm", "role", "acceptance_deg", "numerical_aperture")
#: a fibre's diameter and the tip's [mm]: a few micrometres (a single-mode core) to a
#: 50 mm face, far past anything held against a tooth
DIAMETER_RANGE_MM = (1e-3, 50.0)
#: fibres per tip (a bundle's count; each pair of a source and a receiver is summed)
MAX_FIBRES = 256
# fibres may touch but not overlap, nor cross the tip's edge: the tolerance [mm] forgives
# the rounding of a layout written to a few decimals (touching fibres computed from angles)
TOUCH_MM = 1e-9


@dataclass(frozen=True)
class Fibre:
    """One fibre at the tip: centre [mm], core diameter [mm], role and the receiving
    half-angle [deg] in air (None: the instrument geometry's detector cone)."""

    x_mm: float
    y_mm: float
    diameter_mm: float
    role: str
    acceptance_deg: float | None = None

    @property
    def lights(self) -> bool:
        return self.role in ("source", "both")

    @property
    def receives(self) -> bool:
        return self.role in ("receiver", "both")

    def to_json(self) -> dict:
        return {"x_mm": self.x_mm, "y_mm": self.y_mm, "diameter_mm": self.diameter_mm,
                "role": self.role, "acceptance_deg": self.acceptance_deg}


@dataclass(frozen=True)
class Layout:
    """A probe's tip: its diameter [mm] and its fibres."""

    tip_diameter_mm: float
    fibres: tuple[Fibre, ...]

    @property
    def acceptance_deg(self) -> float | None:
        """The receivers' shared half-angle [deg] (None: the geometry's cone)."""
        return next(f.acceptance_deg for f in self.fibres if f.receives)

    def pairs(self) -> tuple:
        """Every (source, receiver) pair as ((0, source radius), (0, receiver radius),
        distance between their centres, the source's share of the power): the terms of the
        reading (:func:`dentalux.reading.layered.window.integrate`)."""
        sources = [f for f in self.fibres if f.lights]
        total = sum(f.diameter_mm**2 for f in sources)
        return tuple(((0.0, s.diameter_mm / 2), (0.0, r.diameter_mm / 2),
                      math.hypot(s.x_mm - r.x_mm, s.y_mm - r.y_mm), s.diameter_mm**2 / total)
                     for s in sources for r in self.fibres if r.receives)

    def to_json(self) -> dict:
        return {"tip_diameter_mm": self.tip_diameter_mm,
                "fibres": [f.to_json() for f in self.fibres]}


def _acceptance(table: dict, key: str) -> float | None:
    """The half-angle [deg] from ``acceptance_deg`` or ``numerical_aperture`` (not both)."""
    if "acceptance_deg" in table and "numerical_aperture" in table:
        raise ValueError(f"{key}: give acceptance_deg or numerical_aperture, not both")
    if "acceptance_deg" in table:
        return inputs.number(table["acceptance_deg"], f"{key}.acceptance_deg", 0.0, 90.0,
                             lo_open=True, hi_open=True, unit="deg")
    if "numerical_aperture" in table:
        na = inputs.number(table["numerical_aperture"], f"{key}.numerical_aperture", 0.0, 1.0,
                           lo_open=True, hi_open=True)
        return math.degrees(math.asin(na))
    return None


def _fibre(table, key: str, tip_radius: float) -> Fibre:
    inputs.table(table, key)
    inputs.known_keys(table, FIBRE_KEYS, key)
    for k in ("x_mm", "y_mm", "diameter_mm", "role"):
        if k not in table:
            raise ValueError(f"{key} needs {k!r}")
    lo, hi = DIAMETER_RANGE_MM
    d = inputs.number(table["diameter_mm"], f"{key}.diameter_mm", lo, hi, unit="mm")
    x = inputs.number(table["x_mm"], f"{key}.x_mm", -hi, hi, unit="mm")
    y = inputs.number(table["y_mm"], f"{key}.y_mm", -hi, hi, unit="mm")
    role = inputs.text(table["role"], f"{key}.role")
    if role not in ROLES:
        raise ValueError(f"{key}.role = {role!r}: allowed {', '.join(ROLES)}")
    acceptance = _acceptance(table, key)
    if acceptance is not None and role == "source":
        raise ValueError(f"{key}: a source fibre's emission cone is not modelled (it lights "
                         "along the normal); give acceptance_deg or numerical_aperture on "
                         "receivers only")
    reach = math.hypot(x, y) + d / 2
    if reach > tip_radius + TOUCH_MM:
        raise ValueError(f"{key}: the fibre reaches {reach:g} mm from the tip's centre, "
                         f"outside tip_diameter_mm / 2 = {tip_radius:g} mm (allowed "
                         f"hypot(x_mm, y_mm) + diameter_mm / 2 <= {tip_radius:g} mm)")
    return Fibre(x, y, d, role, acceptance)


def parse(value, key: str = "fibres") -> Layout:
    """``{"tip_diameter_mm": ..., "fibres": [table, ...]}`` (or a Layout) -> Layout, or a
    ValueError naming ``key``, the fibre's index, its field and the allowed range."""
    if isinstance(value, Layout):
        value = {"tip_diameter_mm": value.tip_diameter_mm,
                 "fibres": [{k: v for k, v in f.to_json().items() if v is not None}
                            for f in value.fibres]}
    inputs.table(value, key)
    where = key.rpartition(".fibres")[0] or key
    if "tip_diameter_mm" not in value:
        raise ValueError(f"{where}: fibres need tip_diameter_mm (the tip's diameter [mm])")
    lo, hi = DIAMETER_RANGE_MM
    tip = inputs.number(value["tip_diameter_mm"], f"{where}.tip_diameter_mm", lo, hi,
                        unit="mm")
    rows = value.get("fibres")
    if isinstance(rows, (str, bytes, dict)) or not isinstance(rows, (list, tuple)) \
            or not 1 <= len(rows) <= MAX_FIBRES:
        raise ValueError(f"{key} = {rows!r}: must be a list of 1 ... {MAX_FIBRES} fibre "
                         "tables ([[instruments.NAME.fibres]])")
    fibres = tuple(_fibre(t, f"{key}[{i}]", tip / 2) for i, t in enumerate(rows))
    for i, a in enumerate(fibres):
        for j in range(i):
            b = fibres[j]
            gap = math.hypot(a.x_mm - b.x_mm, a.y_mm - b.y_mm)
            if gap < (a.diameter_mm + b.diameter_mm) / 2 - TOUCH_MM:
                raise ValueError(
                    f"{key}[{i}] overlaps {key}[{j}]: their centres are {gap:g} mm apart, "
                    f"less than the sum of their radii {(a.diameter_mm + b.diameter_mm) / 2:g}"
                    " mm (fibres may touch, not overlap; a fibre that lights and receives "
                    "is one fibre with role = 'both')")
    if not any(f.lights for f in fibres) or not any(f.receives for f in fibres):
        raise ValueError(f"{key}: needs at least one fibre that lights (role 'source' or "
                         "'both') and one that receives ('receiver' or 'both')")
    receivers = [(i, f) for i, f in enumerate(fibres) if f.receives]
    first_i, first = receivers[0]
    for i, f in receivers[1:]:
        if f.acceptance_deg != first.acceptance_deg:
            raise ValueError(
                f"{key}[{i}].acceptance_deg = {f.acceptance_deg}: every receiver must share "
                f"one acceptance (as {key}[{first_i}], {first.acceptance_deg}): a reading "
                "solves the specimen for one detector cone")
    return Layout(tip, fibres)
