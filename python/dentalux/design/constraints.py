"""The design's input rules: layers with thickness ranges, the total range, their checks."""

from __future__ import annotations

import math
import re

MAX_LAYERS = 3
MAX_MM = 10.0  # no dental restoration layer is thicker; a guard against unit slips (um)
VENEER = (0.3, 0.8)  # the veneer and crown total ranges [mm]
CROWN = (1.0, 2.0)
_RANGE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*-\s*"
                    r"([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*$")


def parse_range(text: str, name: str) -> tuple[float, float]:
    """``MIN-MAX`` [mm] -> (lo, hi), or a ValueError naming ``name``."""
    m = _RANGE.match(str(text))
    if not m:
        raise ValueError(f"{name} = {text!r}: expected MIN-MAX in mm, e.g. 0.3-0.8")
    return check_range((float(m.group(1)), float(m.group(2))), name)


def check_range(rng, name: str) -> tuple[float, float]:
    """(lo, hi) with 0 < lo < hi <= MAX_MM, or a ValueError naming ``name``."""
    try:
        lo, hi = (float(x) for x in rng)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {rng!r}: expected (min, max) in mm") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"{name} = {rng!r}: must be finite numbers [mm]")
    if lo > hi:
        raise ValueError(f"{name} = {lo:g}-{hi:g} mm is inverted: allowed min < max")
    if lo == hi:
        raise ValueError(f"{name} = {lo:g}-{hi:g} mm is empty (min = max): allowed min < max; "
                         "a layer of fixed thickness is a cement or substrate layer")
    if lo <= 0 or hi > MAX_MM:
        raise ValueError(f"{name} = {lo:g}-{hi:g} mm is out of range: allowed "
                         f"0 < min < max <= {MAX_MM:g} mm")
    return lo, hi


def parse_layer(text: str, index: int = 0) -> tuple[str, tuple[float, float]]:
    """``MATERIAL:MIN-MAX`` -> (material, (lo, hi))."""
    material, sep, rng = str(text).rpartition(":")
    if not sep or not material.strip():
        raise ValueError(f"layer[{index}] = {text!r}: expected MATERIAL:MIN-MAX, e.g. "
                         "enamel:0.3-0.8")
    return material.strip(), parse_range(rng, f"layer[{index}] thickness range")


def check_layers(layers) -> list[tuple[object, tuple[float, float]]]:
    """1 to 3 layers, each (material, (lo, hi)) or a ``MATERIAL:MIN-MAX`` string."""
    if layers is None or isinstance(layers, (str, bytes)) or not hasattr(layers, "__iter__"):
        raise ValueError(f"layers = {layers!r}: expected a list of (material, (min, max)) or "
                         "MATERIAL:MIN-MAX")
    out = []
    for i, item in enumerate(layers):
        if isinstance(item, str):
            out.append(parse_layer(item, i))
            continue
        try:
            material, rng = item
        except (TypeError, ValueError):
            raise ValueError(f"layer[{i}] = {item!r}: expected (material, (min, max))") from None
        out.append((material, check_range(rng, f"layer[{i}] thickness range")))
    if not out:
        raise ValueError("layers: at least one layer is needed (allowed 1 to 3)")
    if len(out) > MAX_LAYERS:
        raise ValueError(f"layers: {len(out)} given, allowed 1 to {MAX_LAYERS} layers")
    return out


def check_total(total, ranges) -> tuple[float, float] | None:
    """The total-thickness range, reachable by the layer ranges, or a ValueError."""
    if total is None:
        return None
    if isinstance(total, str):
        total = parse_range(total, "total")
    else:
        total = check_range(total, "total")
    lo = sum(r[0] for r in ranges)
    hi = sum(r[1] for r in ranges)
    if total[1] < lo or total[0] > hi:
        raise ValueError(f"total = {total[0]:g}-{total[1]:g} mm cannot be met by the layer "
                         f"ranges (their sum spans {lo:g}-{hi:g} mm): allowed a total range "
                         f"that overlaps {lo:g}-{hi:g} mm")
    return total


def parse_fixed_layers(texts) -> list[tuple[str, float]]:
    """``["MATERIAL:MM", ...]`` (``dentalux shade --layer``) -> [(material, thickness)], top
    to bottom; 1 to 3 layers, each 0 < MM <= MAX_MM."""
    if isinstance(texts, str):
        texts = [texts]
    out = []
    for i, text in enumerate(texts or []):
        material, sep, mm = str(text).rpartition(":")
        try:
            t = float(mm)
        except ValueError:
            t = math.nan
        if not sep or not material.strip():
            raise ValueError(f"layer[{i}] = {text!r}: expected MATERIAL:THICKNESS, e.g. "
                             "enamel:0.5")
        if not (math.isfinite(t) and 0 < t <= MAX_MM):
            raise ValueError(f"layer[{i}] thickness = {mm!r} is out of range: allowed "
                             f"0 < thickness <= {MAX_MM:g} mm")
        out.append((material.strip(), t))
    if not out:
        raise ValueError("layer: at least one MATERIAL:THICKNESS is needed (allowed 1 to 3)")
    if len(out) > MAX_LAYERS:
        raise ValueError(f"layer: {len(out)} given, allowed 1 to {MAX_LAYERS} layers")
    return out


def parse_cement(cement) -> tuple | None:
    """``MATERIAL:MM`` or (material, mm) -> (material, mm) with the thickness checked, or
    None for no cement. The material is returned as given (a name, file or Material)."""
    if cement is None:
        return None
    if isinstance(cement, str):
        mat, sep, mm = cement.rpartition(":")
        try:
            cement = (mat, float(mm))
        except ValueError:
            sep = ""
        if not sep or not mat:
            raise ValueError(f"cement = {cement!r}: expected MATERIAL:MM")
    try:
        mat, mm = cement
        mm = float(mm)
    except (TypeError, ValueError):
        raise ValueError(f"cement = {cement!r}: expected (material, thickness [mm])") from None
    if not (math.isfinite(mm) and 0 < mm <= MAX_MM):
        raise ValueError(f"cement thickness = {mm!r} is out of range: allowed "
                         f"(0, {MAX_MM:g}] mm")
    return mat, mm
