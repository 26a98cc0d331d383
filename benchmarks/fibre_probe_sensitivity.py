"""How far the natural incisor's reading through the ``fibre-probe`` preset moves when each
assumed number of the preset changes over its plausible range (docs/instruments.md, "Several
fibres"): the labial middle third (enamel 0.9 / dentin 2.9 / enamel 0.6 mm), substrate none,
colour over the white backing, 5 bands as ``instruments validate``, layered solver (no
noise). Prints one line per variant: L*, a*, b* and the CPU-seconds of the reading."""

from __future__ import annotations

import math
import time

from dentalux import dental, instrument

STACK = [("enamel", 0.9), ("dentin", 2.9), ("enamel", 0.6)]
BANDS = [450.0, 500.0, 550.0, 600.0, 650.0]
# the preset's assumed layout: source diameter, receiver diameter, ring radius [mm], NA
PRESET = {"source": 1.0, "receiver": 0.5, "radius": 1.0, "na": 0.5, "count": 6}


def layout(source, receiver, radius, na, count) -> dict:
    """A central source and ``count`` receivers evenly on a ring of ``radius``."""
    fibres = [{"x_mm": 0.0, "y_mm": 0.0, "diameter_mm": source, "role": "source"}]
    for i in range(count):
        a = 2 * math.pi * i / count
        fibres.append({"x_mm": radius * math.cos(a), "y_mm": radius * math.sin(a),
                       "diameter_mm": receiver, "role": "receiver",
                       "numerical_aperture": na})
    return {"tip_diameter_mm": 5.0, "fibres": fibres}


def read(label: str, inst) -> None:
    start = time.process_time()
    lab = dental.read(STACK, instrument=inst, bands=BANDS).lab_white
    print(f"{label:<40} L* {lab.L:6.1f}  a* {lab.a:5.1f}  b* {lab.b:6.1f}  "
          f"({time.process_time() - start:.1f} CPU-s)")


def main() -> None:
    base = instrument.get("fibre-probe")
    read("preset", base)
    variants = [("radius", [0.8, 1.25, 1.5, 2.0]), ("source", [0.6, 1.5]),
                ("receiver", [0.3, 0.7]), ("na", [0.22, 0.37, 0.66]), ("count", [3, 12])]
    for key, values in variants:
        for v in values:
            changes = {**PRESET, key: v}
            if key == "count" and v == 12:
                changes["receiver"] = 0.45  # twelve 0.5 mm fibres do not fit the 1 mm ring
            read(f"{key} = {v:g}" + (" (receivers 0.45 mm)" if key == "count" and v == 12
                                     else ""), base.override(fibres=layout(**changes)))
    tile = {k: v for k, v in base.white_reference.to_json().items() if v is not None}
    for mus in (5.0, 100.0):
        read(f"tile mus = {mus:g} /mm", base.override(white_reference={**tile,
                                                                      "mus_per_mm": mus}))
    read("tile n = 1.5, reflectance 0.90", base.override(
        white_reference={**tile, "n": 1.5, "reflectance": 0.90}))
    read("no tile (a fraction of the power)", instrument.Instrument(
        name="fibre-probe+custom", geometry=base.geometry, backing_black=base.backing_black,
        backing_white=base.backing_white, fibres=base.fibres))


if __name__ == "__main__":
    main()
