"""Regenerate the ``bioform`` rows of ``shade_guides.csv`` from the published Bioform table.

Source: O'Brien WJ, Groh CL, Boenke KM, "A one-dimensional color order system for dental
shade guides", Dent Mater 1989;5(6):371-374. The paper itself was not read; the numbers below
are its table as transcribed in the R package munsellinterpol 3.3-2 (CRAN, file
``inst/extdata/dental.txt``, whose header names the University of Michigan Biomaterials
Properties Database as its copy). The University of Michigan Dental Library page "Colors of
Dental Shade Guides" (stored opening, 14 of the 24 rows) gives the same numbers for every
row it shows. Only the numbers are taken (facts), no code of the package.

What the sources say about the measurement: 24 tabs of a master Bioform guide; a dual-beam
spectrophotometer with an integrating sphere and a beam-reducing accessory (UMich page),
named as a Beckman ACTA CIII, 410-700 nm at 10 nm (munsellinterpol's vignette); tristimulus
values for CIE standard illuminant C and "the CIE standard observer function". The observer
is taken as the CIE 1931 2° one: recomputing L*a*b* from the published xyY with the 2° white
of C reproduces the published a* and b* within 0.06, the 10° white misses a* by about 1.

The table's L*a*b* are for illuminant C. Every reading in dentalux is CIELAB for D65/2° by
default, so the guide's values are DERIVED: published x, y, Y -> XYZ (C) -> Bradford
(von Kries) adaptation from the C white (CIE 15: x 0.31006, y 0.31616) to the D65/2° white
that dentalux computes (``dentalux.color.system("D65", "2").white_xy``, the white of every
reading) -> CIELAB, rounded to 2 decimals. A chromatic adaptation only approximates the
spectra read under D65 (the spectra were not published); read the values as ±0.5 ΔE00 or so.
The published C values and the Munsell notation travel in each row's notes.

Run: ``PYTHONPATH=python .venv/bin/python python/dentalux/data/make_bioform_guide.py``.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

GUIDE = "bioform"

# tab, Y, x, y (illuminant C, 2°), L*, a*, b* (illuminant C), Munsell HV/C: the source's
# rows in the source's order (increasing Y), as printed
SOURCE = (
    ("B-96", 37.05, 0.3610, 0.3641, 67.34, 1.31, 19.93, "1.9Y 6.55/2.9"),
    ("B-84", 37.98, 0.3663, 0.3653, 68.01, 2.74, 21.21, "0.9Y 6.65/3.2"),
    ("B-85", 38.24, 0.3811, 0.3794, 68.23, 2.91, 27.38, "1.8Y 6.65/4.1"),
    ("B-81", 38.82, 0.3588, 0.3616, 68.65, 1.43, 19.24, "1.5Y 6.60/2.8"),
    ("B-95", 41.22, 0.3502, 0.3570, 70.36, 0.03, 17.07, "2.6Y 6.85/2.4"),
    ("B-94", 42.30, 0.3548, 0.3627, 71.11, -0.32, 19.48, "3.0Y 6.95/2.7"),
    ("B-69", 42.49, 0.3545, 0.3614, 71.24, 0.03, 19.11, "2.6Y 6.95/2.6"),
    ("B-83", 43.25, 0.3693, 0.3701, 71.52, 2.25, 23.94, "1.3Y 7.00/3.6"),
    ("B-77", 44.09, 0.3572, 0.3628, 72.32, 0.50, 20.16, "2.3Y 7.05/2.8"),
    ("B-93", 45.01, 0.3526, 0.3584, 72.93, 0.40, 18.34, "2.2Y 7.15/2.6"),
    ("B-67", 46.26, 0.3614, 0.3681, 73.74, 0.14, 22.66, "2.5Y 7.20/3.2"),
    ("B-55", 47.10, 0.3558, 0.3639, 74.28, -0.39, 20.69, "2.9Y 7.30/2.9"),
    ("B-56", 47.80, 0.3581, 0.3633, 74.73, 0.66, 21.00, "2.0Y 7.30/2.9"),
    ("B-92", 48.67, 0.3429, 0.3514, 75.28, -0.66, 15.27, "3.0Y 7.35/2.0"),
    ("B-65", 49.14, 0.3606, 0.3629, 75.57, 1.73, 21.48, "1.1Y 7.30/3.1"),
    ("B-54", 49.15, 0.3532, 0.3589, 75.58, 0.46, 19.13, "2.0Y 7.40/2.7"),
    ("B-53", 49.39, 0.3499, 0.3559, 75.72, 0.33, 17.76, "2.1Y 7.40/2.5"),
    ("B-91", 49.57, 0.3406, 0.3484, 75.84, -0.42, 14.14, "2.4Y 7.45/1.9"),
    ("B-62", 49.92, 0.3454, 0.3539, 76.05, -0.64, 16.53, "3.1Y 7.45/2.3"),
    ("B-63", 50.00, 0.3548, 0.3594, 76.10, 0.87, 19.64, "1.7Y 7.45/2.8"),
    ("B-52", 50.42, 0.3451, 0.3553, 76.36, -1.28, 16.94, "3.6Y 7.50/2.1"),
    ("B-66", 51.21, 0.3534, 0.3615, 76.84, -0.42, 20.18, "2.8Y 7.55/2.8"),
    ("B-51", 55.24, 0.3432, 0.3525, 79.21, -0.99, 16.31, "3.2Y 7.80/2.2"),
    ("B-59", 55.72, 0.3407, 0.3502, 79.49, -1.10, 15.26, "3.5Y 7.80/2.0"),
)
# rows the UMich page's stored opening shows (same numbers, another order)
UMICH_ROWS = ("B-59", "B-51", "B-91", "B-62", "B-66", "B-52", "B-53", "B-92", "B-63", "B-54",
              "B-65", "B-93", "B-55", "B-69")

C_WHITE_XY = (0.31006, 0.31616)  # CIE 15, illuminant C, 1931 2° observer

CITATION = ("O'Brien WJ, Groh CL, Boenke KM. A one-dimensional color order system for dental "
            "shade guides. Dent Mater 1989;5(6):371-374 (paper not read: its table as "
            "transcribed in the R package munsellinterpol 3.3-2, inst/extdata/dental.txt, "
            "which names the University of Michigan Biomaterials Properties Database)")
DOI = "10.1016/0109-5641(89)90102-4"
INSTRUMENT = ("Beckman ACTA CIII dual-beam spectrophotometer with integrating sphere and "
              "beam-reducing accessory (410-700 nm at 10 nm)")
GEOMETRY = ("integrating sphere (sphere geometry, specular component and port size not "
            "stated in what was read)")
NOT_STATED = "not stated in what was read"


def derive(Y: float, x: float, y: float) -> np.ndarray:
    """CIELAB for D65/2° from the published xyY under illuminant C (module doc)."""
    import colour
    from dentalux.color import system

    d65 = system("D65", "2").white_xy
    xyz = colour.xyY_to_XYZ([x, y, Y / 100.0])
    xyz_d65 = colour.adaptation.chromatic_adaptation_VonKries(
        xyz, colour.xy_to_XYZ(C_WHITE_XY), colour.xy_to_XYZ(d65), transform="Bradford")
    return np.asarray(colour.XYZ_to_Lab(xyz_d65, d65))


def rows() -> list[dict]:
    out = []
    for tab, Y, x, y, L, a, b, munsell in SOURCE:
        lab = derive(Y, x, y)
        seen = ("; the same numbers on the UMich Dental Library page 'Colors of Dental Shade "
                "Guides'" if tab in UMICH_ROWS else "")
        extra = ""
        if tab == "B-83":
            # the one row whose published L* disagrees with its own Y by more than rounding
            extra = ("; its published L* 71.52 is 0.20 below the L* of its own Y 43.25 "
                     "(71.72 under C), which munsellinterpol's vignette takes for a "
                     "transcription error; the derived value follows Y")
        out.append({
            "guide": GUIDE, "tab": tab,
            "L": f"{lab[0]:.2f}", "a": f"{lab[1]:.2f}", "b": f"{lab[2]:.2f}",
            "illuminant": "D65", "observer": "2",
            "instrument": INSTRUMENT, "geometry": GEOMETRY, "window_mm": "",
            "backing": NOT_STATED, "region": NOT_STATED,
            "citation": CITATION, "doi": DOI, "status": "derived",
            "notes": (f"derived here from the published Y {Y:.2f}, x {x:.4f}, y {y:.4f} "
                      "(illuminant C, 1931 2° observer): Bradford adaptation from C "
                      "(x 0.31006, y 0.31616) to dentalux's computed D65/2° white, then "
                      f"CIELAB. Transcribed as published (illuminant C): L* {L:.2f}, "
                      f"a* {a:.2f}, b* {b:.2f}; Munsell {munsell}{seen}{extra}"),
        })
    return out


def main(path: Path = Path(__file__).with_name("shade_guides.csv")) -> None:
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        fields = list(reader.fieldnames or [])
        kept = [r for r in reader if r["guide"] != GUIDE]
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)  # csv's CRLF, as the file has
        w.writeheader()
        w.writerows(kept + rows())


if __name__ == "__main__":
    main()
