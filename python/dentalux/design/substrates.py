"""What lies under a restoration, and the layered specimen that the Monte Carlo reads.

A design's specimen is, top to bottom: the restoration's layers, an optional cement layer,
the substrate's layers; it lies on the instrument's black and white backings, or, for an
opaque core, on the core itself (both backings replaced by the core's reflectance, so the
readings over "black" and "white" are the same and TP is 0).

Substrates (``--substrate NAME``); every number is assumed (no source was read for it):

- ``none``: nothing under the restoration: the restoration alone on the instrument's
  backings, as a disc is measured, or an incisal edge with nothing behind it.
- ``dentin``: natural dentin, the library's ``dentin`` material, 2.0 mm thick (assumed: the
  labial dentin left between a prepared incisor's surface and its pulp, of the order of
  2 mm), on the instrument's backings.
- ``stump``: a discoloured (darker) dentin stump: the library's ``dentin`` with its
  absorption μa multiplied by 4 at every wavelength (assumed: a stand-in for a non-vital or
  stained tooth, darker in L* by several units at 2 mm; no measured discoloured-dentin
  coefficients were found), 2.0 mm thick, on the instrument's backings.
- ``zirconia``: an opaque zirconia core as a Lambertian backing of reflectance 0.75 at all
  wavelengths (assumed: a white, opaque 3Y-TZP core, L* about 89; no core spectrum was read;
  translucent zirconias are not opaque and should be a layer instead).
- ``metal``: a cast metal core or post (NiCr, CoCr) as a Lambertian backing of reflectance
  0.30 at all wavelengths (assumed: a grey, L* about 62; a real metal is specular, not
  Lambertian, and a gold alloy is yellow; no spectrum was read).
- ``reflectance:R`` (R in [0, 1]) or ``reflectance:FILE.csv`` (columns wavelength_nm,
  reflectance): a given opaque backing, e.g. a measured stump or core spectrum.

A cement layer ``cement=(MATERIAL, MM)`` (``--cement MATERIAL:MM``) lies between the
restoration and the substrate; the library has no cement material, so it is the user's
TOML (or any library material).
"""

from __future__ import annotations

import math
from pathlib import Path

from dentalux import inputs

SUBSTRATE_DENTIN_MM = 2.0
STUMP_MUA_FACTOR = 4.0
CORES = {"zirconia": 0.75, "metal": 0.30}
NAMES = ("none", "dentin", "stump", "zirconia", "metal", "reflectance:R",
         "reflectance:FILE.csv")
PROVENANCE = {
    "none": "nothing under the restoration: the instrument's own backings",
    "dentin": f"assumed: library 'dentin', {SUBSTRATE_DENTIN_MM:g} mm (labial dentin of a "
              "prepared incisor, of the order of 2 mm), on the instrument's backings",
    "stump": f"assumed: library 'dentin' with mua x {STUMP_MUA_FACTOR:g} (a darker, "
             f"discoloured stump), {SUBSTRATE_DENTIN_MM:g} mm, on the instrument's backings",
    "zirconia": "assumed: opaque white zirconia core, Lambertian reflectance 0.75 flat",
    "metal": "assumed: cast metal core, grey Lambertian reflectance 0.30 flat (a real "
             "metal is specular)",
}


def _reflectance_file(path: Path) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A substrate's reflectance CSV (columns wavelength_nm, reflectance) by the rules of
    dentalux.inputs: UTF-8, every row complete, wavelengths strictly increasing and finite,
    reflectances in [0, 1]."""
    if not path.is_file():
        raise ValueError(f"substrate reflectance file {str(path)!r} not found")
    what = "substrate reflectance file"
    header, rows = inputs.read_csv(path, what)
    where = f"{what} {path}"
    missing = [c for c in ("wavelength_nm", "reflectance") if c not in header]
    if missing:
        raise ValueError(f"{where}: missing column(s) {', '.join(missing)} (needs "
                         "wavelength_nm, reflectance)")
    if not rows:
        raise ValueError(f"{where}: no data rows")
    wl = [inputs.cell(row, "wavelength_nm", where) for row in rows]
    r = [inputs.cell(row, "reflectance", where) for row in rows]
    for row, x in zip(rows, r, strict=True):
        if not 0.0 <= x <= 1.0:
            raise ValueError(f"{where}: line {row['_line']}: reflectance = {x:g}: reflectance "
                             "must lie in [0, 1]")
    inputs.wavelengths(wl, f"{where}: wavelength_nm")
    return tuple(wl), tuple(r)


def _core(substrate: str):
    """The opaque backing of a substrate (a number or (wavelengths, values)), or None."""
    if substrate in CORES:
        return CORES[substrate]
    if substrate.startswith("reflectance:"):
        value = substrate.split(":", 1)[1]
        if value.endswith(".csv"):
            return _reflectance_file(Path(value))
        try:
            r = float(value)
        except ValueError:
            r = math.nan
        if not (0.0 <= r <= 1.0):
            raise ValueError(f"substrate = {substrate!r}: reflectance:R needs R in [0, 1] or "
                             "a CSV file (wavelength_nm, reflectance)")
        return r
    return None


def check(substrate) -> str:
    """A substrate name, or a ValueError naming the allowed ones."""
    if not isinstance(substrate, str) or not (
            substrate in ("none", "dentin", "stump") or substrate in CORES
            or substrate.startswith("reflectance:")):
        raise ValueError(f"substrate = {substrate!r} is unknown: allowed {', '.join(NAMES)}")
    _core(substrate)
    return substrate


def layers(substrate: str) -> list[tuple]:
    """The substrate's own layers [(material, thickness)], top to bottom."""
    check(substrate)
    if substrate == "dentin":
        return [("dentin", SUBSTRATE_DENTIN_MM)]
    if substrate == "stump":
        from dentalux import materials

        dark = materials.get("dentin").scaled(
            mua_factor=STUMP_MUA_FACTOR, note="design substrate 'stump': discoloured dentin")
        return [(dark, SUBSTRATE_DENTIN_MM)]
    return []


def specimen(layers_, substrate: str = "dentin", cement=None) -> list[tuple]:
    """The specimen [(material, thickness)] the Monte Carlo reads: the restoration's
    ``layers_`` [(material, thickness)] top to bottom, then ``cement`` (material, mm) if
    given, then the substrate's layers. Read it with the backing override of
    :func:`backings` (an opaque core replaces the instrument's backings)."""
    out = [tuple(item) for item in layers_]
    if cement is not None:
        out.append(tuple(cement))
    return out + layers(substrate)


def backings(substrate: str = "dentin") -> dict:
    """Keyword arguments for :func:`dentalux.dental.read`: ``backing_black`` and
    ``backing_white`` set to an opaque core's reflectance, or {} (the instrument's)."""
    core = _core(check(substrate))
    return {} if core is None else {"backing_black": core, "backing_white": core}


def describe(substrate: str) -> str:
    """One line on what the substrate is (for reports)."""
    check(substrate)
    if substrate.startswith("reflectance:"):
        return f"given opaque Lambertian backing {substrate.split(':', 1)[1]}"
    return PROVENANCE[substrate]
