"""What a design is matched to: a CIELAB colour (and optionally a TP00), with its source.

Target strings (``dentalux design --target``):

- ``lab:L,a,b`` — explicit CIELAB values (a measured tooth, a tab the user measured);
- ``GUIDE:TAB`` — a tab of a shade guide in ``data/shade_guides.csv``
  (``vita-classical:A2``, ``vita-3d-master:2M2``); refused, naming the tab, when the table
  holds no published values for it (:func:`dentalux.shade_guides.lab`); or of a guide the
  lab imported (``dentalux guides import``), or ``FILE.csv:TAB`` of a guide file;
- ``stack:MATERIAL:MM[/MATERIAL:MM...]`` — a tooth region given as a layered specimen (top
  to bottom, e.g. ``stack:enamel:1.0/dentin:2.5``), read through the design's instrument
  as ``dental.read`` reads it: its colour over the white backing becomes the target.

``tp`` adds a translucency target (TP00, ΔE00 between the readings over black and white).
A target carries the instrument that read it (``instrument``, a preset name or file; None: the
design's own): ``dentalux design --target-instrument NAME`` says so, and the output notes when
the target and the prediction are read by different instruments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

L_RANGE = (0.0, 100.0)
AB_RANGE = (-128.0, 127.0)  # the 8-bit CIELAB encoding's range, wider than any object colour
TP_RANGE = (0.0, 100.0)


@dataclass(frozen=True)
class Target:
    """A CIELAB target (over the instrument's white backing) and an optional TP00 target."""

    lab: tuple[float, float, float]
    tp00: float | None = None
    source: dict = field(default_factory=dict, compare=False)
    lab_stderr: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tp00_stderr: float = 0.0
    #: the instrument that read the target (name); None: the design's own instrument
    instrument: str | None = None

    def to_json(self) -> dict:
        out = {"lab": list(self.lab), "source": self.source}
        if self.instrument is not None:
            out["instrument"] = self.instrument
        if any(self.lab_stderr):
            out["lab_stderr"] = list(self.lab_stderr)
        if self.tp00 is not None:
            out["tp00"] = self.tp00
            if self.tp00_stderr:
                out["tp00_stderr"] = self.tp00_stderr
        return out


def check_lab(lab, name: str = "target") -> tuple[float, float, float]:
    """Three finite numbers inside the CIELAB range, or a ValueError naming the component."""
    try:
        values = [float(x) for x in lab]
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {lab!r}: expected three numbers L*, a*, b*") from None
    if len(values) != 3:
        raise ValueError(f"{name} = {lab!r}: expected three numbers L*, a*, b*, got "
                         f"{len(values)}")
    for comp, x, (lo, hi) in zip(("L*", "a*", "b*"), values, (L_RANGE, AB_RANGE, AB_RANGE),
                                 strict=True):
        if not math.isfinite(x) or not lo <= x <= hi:
            raise ValueError(f"{name} {comp} = {x:g} is outside the CIELAB range: allowed "
                             f"[{lo:g}, {hi:g}]")
    return tuple(values)


def check_tp(tp, name: str = "target_tp") -> float | None:
    if tp is None:
        return None
    try:
        x = float(tp)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {tp!r}: expected a number (TP00)") from None
    if isinstance(tp, bool) or not math.isfinite(x) or not TP_RANGE[0] <= x <= TP_RANGE[1]:
        raise ValueError(f"{name} = {tp!r} is out of range: allowed [{TP_RANGE[0]:g}, "
                         f"{TP_RANGE[1]:g}] (TP00, a ΔE00)")
    return x


def parse_stack(text: str) -> list[tuple[str, float]]:
    """``MATERIAL:MM[/MATERIAL:MM...]`` -> [(material, thickness)], top to bottom."""
    out = []
    # layers are separated by '/', which a material's file path also holds: a layer ends
    # only where the text so far ends in ':MM' (a number), e.g. 'lab/my.toml:0.5/dentin:2'
    parts, buf = [], None
    for piece in text.split("/"):
        buf = piece if buf is None else f"{buf}/{piece}"
        try:
            float(buf.rpartition(":")[2].strip())
        except ValueError:
            continue
        if ":" in buf:
            parts.append(buf)
            buf = None
    if buf is not None and buf.strip():
        parts.append(buf)
    for i, part in enumerate(p for p in parts if p.strip()):
        material, sep, mm = part.strip().rpartition(":")
        # 'enamel:x/dentin:3' joined its first layer to a path: not a file, so that layer
        # (its text after ':' no number) is the error
        if "/" in material and not Path(material).is_file():
            bad = next((q for q in material.split("/") if q.rpartition(":")[2].strip()
                        and ":" in q), None)
            if bad is not None:
                raise ValueError(f"target stack layer {i} = {bad!r}: expected MATERIAL:MM "
                                 "with a thickness > 0 [mm]")
        try:
            t = float(mm)
        except ValueError:
            t = math.nan
        if not sep or not material or not (math.isfinite(t) and t > 0):
            raise ValueError(f"target stack layer {i} = {part!r}: expected MATERIAL:MM with "
                             "a thickness > 0 [mm]")
        out.append((material, t))
    if not out:
        raise ValueError(f"target = 'stack:{text}': give at least one MATERIAL:MM layer")
    return out


def parse(target, tp=None, read=None, instrument: str | None = None) -> Target:
    """A :class:`Target` from a target string, an (L, a, b) triple or a Target.

    ``read(stack) -> DentalMetrics`` reads a ``stack:`` target through the design's
    instrument (given by :func:`dentalux.design.optimise`) or through ``instrument``, the
    name of the instrument that read the target (kept in :attr:`Target.instrument`)."""
    tp = check_tp(tp)
    if isinstance(target, Target):
        return replace(target, lab=check_lab(target.lab),
                       tp00=tp if tp is not None else target.tp00,
                       instrument=target.instrument if instrument is None else instrument)
    return replace(_parse(target, tp, read), instrument=instrument)


def _parse(target, tp, read) -> Target:
    if not isinstance(target, str):
        return Target(check_lab(target), tp, {"kind": "lab", "status": "given"})
    text = target.strip()
    kind, sep, rest = text.partition(":")
    if ".csv:" in text.lower():  # FILE.csv:TAB, a path may hold ':' itself
        kind, sep, rest = text.rpartition(":")
    if not sep or not rest:
        raise ValueError(f"target = {target!r}: expected lab:L,a,b, GUIDE:TAB (e.g. "
                         "vita-classical:A2) or stack:MATERIAL:MM[/MATERIAL:MM...]")
    if kind == "lab":
        parts = [p for p in rest.split(",")]
        try:
            values = [float(p) for p in parts]
        except ValueError:
            raise ValueError(f"target = {target!r}: lab:L,a,b needs three numbers") from None
        return Target(check_lab(values, "target"), tp, {"kind": "lab", "status": "given"})
    if kind == "stack":
        stack = parse_stack(rest)
        if read is None:
            raise ValueError("target stack: needs an instrument to read it")
        m = read(stack)
        lab = check_lab(m.lab_white, "target (read stack)")
        source = {"kind": "stack", "status": "derived",
                  "stack": [{"material": str(mat), "thickness_mm": t} for mat, t in stack],
                  "tp00_read": m.tp00, "tp00_read_stderr": m.stderr["tp00"],
                  "notes": "read as dental.read reads it through the target's instrument "
                           "(the design's unless --target-instrument names another), "
                           "colour over its white backing; its TP00 is in tp00_read (a TP "
                           "target only when --target-tp is given)"}
        return Target(lab, tp, source, tuple(m.stderr[f"lab_white.{c}"] for c in "Lab"))
    from dentalux import shade_guides

    guide, tab = kind, rest
    if not shade_guides.is_guide(guide):
        raise ValueError(f"target = {target!r}: {guide!r} is neither lab, stack nor a shade "
                         f"guide: allowed lab:L,a,b, stack:MATERIAL:MM/..., GUIDE:TAB with "
                         f"GUIDE one of {', '.join(shade_guides.guides())}, or FILE.csv:TAB "
                         "(a guide file)")
    row = shade_guides.tab(guide, tab)  # unknown tab: ValueError naming the allowed ones
    lab = check_lab(shade_guides.lab(guide, tab), f"target {guide}:{tab}")
    return Target(lab, tp, {"kind": "shade-guide", **row.source()})


def resolve_instrument(target_instrument, design_instrument) -> tuple[str, str]:
    """(target instrument name, design instrument name); ``target_instrument`` None: the
    design's. A name that is neither a preset nor a file is refused naming the field."""
    from dentalux import instrument as instruments

    design = instruments.get(design_instrument).name
    if target_instrument is None:
        return design, design
    try:
        return instruments.get(target_instrument).name, design
    except ValueError as exc:
        raise ValueError(f"target_instrument: {exc}") from None


def read_through(target_instrument, **kwargs):
    """A ``read(stack)`` for :func:`parse` that reads a ``stack:`` target through the target's
    own instrument (``kwargs`` go to :func:`dentalux.dental.read`)."""
    from dentalux import dental

    def read(stack):
        return dental.read(stack, instrument=target_instrument, **kwargs)

    return read


def differs_note(target: Target, design_instrument: str) -> str | None:
    """The sentence the output adds when target and prediction are read by different
    instruments (None when they are read alike)."""
    if target.instrument is None or target.instrument == design_instrument:
        return None
    return (f"target read by {target.instrument}, prediction read by {design_instrument}: "
            "different instruments, so the ΔE00 compares two instruments' readings as well "
            "as two specimens")
