"""An instrument's white calibration reference: the tile a reading is divided by.

A real spectrophotometer reports (specimen's signal) / (its white tile's signal) × (the tile's
certified reflectance factor), both signals read through the same tip. dentalux otherwise
divides by an ideal, non-penetrating Lambertian white (:mod:`dentalux.instrument`). A
``[instruments.NAME.white_reference]`` table makes the tile a slab of its own that is read
through the same window (:mod:`dentalux.reading.white_reference`; docs/instruments.md,
"A white reference tile"):

- ``material``: a library material or a TOML file (relative to the instrument file), or the
  coefficients ``mua_per_mm``, ``mus_per_mm``, ``g`` (and optionally ``fd``) and ``n``,
  constant in wavelength;
- ``thickness_mm``; ``reflectance``: the certified reflectance factor, a number or
  ``{wavelength_nm = [...], reflectance = [...]}``;
- optionally ``backing`` (what lies under the tile; default the instrument's black backing),
  ``diameter_mm`` (default: wider than anything the window reaches) and ``provenance``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from dentalux import inputs, materials

#: the keys of the table; ``material`` or the four coefficients (``fd`` optional)
COEFFICIENTS = ("mua_per_mm", "mus_per_mm", "g", "n")
KEYS = ("material", *COEFFICIENTS, "fd", "thickness_mm", "reflectance", "backing",
        "diameter_mm", "provenance")
#: a tile's thickness [mm]: a film to a block (nothing a tip is calibrated on is thicker)
THICKNESS_RANGE_MM = (1e-6, 1e3)


@dataclass(frozen=True)
class WhiteReference:
    """A calibration tile: a slab (a material or constant coefficients) of ``thickness_mm``
    with a certified reflectance factor (a number or (wavelengths, values)); ``backing``
    None is the instrument's black backing, ``diameter_mm`` None an unbounded tile."""

    thickness_mm: float
    reflectance: float | tuple
    material: str | None = None
    coefficients: tuple | None = None  # (mua, mus, g, fd, n), constant in wavelength
    backing: float | tuple | None = None
    diameter_mm: float | None = None
    provenance: dict = field(default_factory=dict, compare=False)
    resolved: object = field(default=None, compare=False, repr=False)  # the Material

    def to_json(self) -> dict:
        def spectrum(v):
            return {"wavelength_nm": list(v[0]), "reflectance": list(v[1])} \
                if isinstance(v, tuple) else v

        out = {"thickness_mm": self.thickness_mm, "reflectance": spectrum(self.reflectance),
               "backing": spectrum(self.backing), "diameter_mm": self.diameter_mm}
        if self.material is not None:
            out["material"] = self.material
        else:
            out.update(zip(("mua_per_mm", "mus_per_mm", "g", "fd", "n"), self.coefficients,
                           strict=True))
        return out

    def layers(self, wl) -> list:
        """One single-layer stack per band [nm] (:class:`dentalux.slab.Layer`)."""
        from dentalux.slab import Layer

        if self.coefficients is not None:
            mua, mus, g, fd, n = self.coefficients
            return [[Layer(mua=mua, mus=mus, g=g, n=n, thickness=self.thickness_mm, fd=fd)]
                    for _ in wl]
        from dentalux.reading.engine import stacks

        return stacks([(self.resolved, self.thickness_mm)], wl)


def _material(value, key: str, base: Path | None):
    """A library material name or a TOML file (relative to ``base``) -> (the name or the
    file's resolved path, Material): two files of one name in two folders stay apart."""
    text = inputs.text(value, key)
    if text.endswith(".toml"):
        path = Path(text)
        if not path.is_absolute() and base is not None:
            path = base / path
        if not path.is_file():
            raise ValueError(f"{key} = {text!r}: material file not found ({path})")
        text = str(path.resolve())
    try:
        return text, materials.get(text)
    except (ValueError, FileNotFoundError) as exc:
        raise ValueError(f"{key}: {exc}") from None


def parse(table, key: str, base: Path | None = None) -> WhiteReference:
    """A ``white_reference`` table -> WhiteReference, or a ValueError naming the key path
    ``key`` and the allowed range."""
    from dentalux.instrument import DIAMETER_RANGE_MM, _backing

    if isinstance(table, WhiteReference):
        return table
    inputs.table(table, key)
    inputs.known_keys(table, KEYS, key)
    given = [k for k in COEFFICIENTS if k in table]
    if ("material" in table) == bool(given) or (given and len(given) < len(COEFFICIENTS)):
        raise ValueError(f"{key}: give either material = NAME (a library material or a TOML "
                         f"file) or all of {', '.join(COEFFICIENTS)} (fd optional), not both")
    for k in ("thickness_mm", "reflectance"):
        if k not in table:
            raise ValueError(f"{key} needs {k!r}")
    lo, hi = THICKNESS_RANGE_MM
    thickness = inputs.number(table["thickness_mm"], f"{key}.thickness_mm", lo, hi, unit="mm")
    refl = table["reflectance"]
    if isinstance(refl, dict):
        refl = _backing(f"{key}.reflectance", refl)
        if min(refl[1]) <= 0:
            raise ValueError(f"{key}.reflectance: every value must lie in (0, 1] (a tile "
                             "reading 0 cannot calibrate)")
    else:
        refl = inputs.number(refl, f"{key}.reflectance", 0.0, 1.0, lo_open=True)
    material = resolved = coefficients = None
    if "material" in table:
        material, resolved = _material(table["material"], f"{key}.material", base)
    else:
        c = {k: table[k] for k in COEFFICIENTS}
        coefficients = (
            inputs.number(c["mua_per_mm"], f"{key}.mua_per_mm", 0.0, materials.MAX_COEFFICIENT,
                          unit="1/mm"),
            inputs.number(c["mus_per_mm"], f"{key}.mus_per_mm", 0.0, materials.MAX_COEFFICIENT,
                          unit="1/mm"),
            inputs.number(c["g"], f"{key}.g", -1.0, 1.0, lo_open=True, hi_open=True),
            inputs.number(table.get("fd", 0.0), f"{key}.fd", 0.0, 1.0),
            inputs.number(c["n"], f"{key}.n", 1.0, materials.MAX_INDEX))
    if "fd" in table and material is not None:
        raise ValueError(f"{key}.fd: only with the coefficients (a material has its own fd)")
    backing = None if "backing" not in table else _backing(f"{key}.backing", table["backing"])
    diameter = None
    if "diameter_mm" in table:
        lo, hi = DIAMETER_RANGE_MM
        diameter = inputs.number(table["diameter_mm"], f"{key}.diameter_mm", lo, hi, unit="mm")
    provenance = dict(inputs.table(table.get("provenance", {}), f"{key}.provenance"))
    for k, v in provenance.items():
        inputs.text(v, f"{key}.provenance.{k}")
    return WhiteReference(thickness_mm=thickness, reflectance=refl, material=material,
                          coefficients=coefficients, backing=backing, diameter_mm=diameter,
                          provenance=provenance, resolved=resolved)


def instrument_for(inst):
    """The instrument that reads ``inst``'s tile: the same window, geometry, contact and
    backings, the tile's own diameter (None: unbounded) and no tile of its own."""
    from dataclasses import replace

    tile = inst.white_reference
    try:
        return replace(inst, white_reference=None, specimen_diameter_mm=tile.diameter_mm)
    except ValueError as exc:
        raise ValueError(f"white_reference.diameter_mm = {tile.diameter_mm:g} mm does not fit "
                         f"the instrument: {exc}") from None
