"""Regenerate ``colour_weights.json``: the integration weights of the colour systems a
reading uses by default, so that a reading needs no import of colour-science (about 0.3 s of
every command-line reading, benchmarks/reading_time.py).

Status: DERIVED. Each entry is what ``dentalux.color.ColourSystem`` computes with
colour-science from its own data (the CIE 1931 2° and CIE 1964 10° colour matching functions
and the CIE D65 illuminant, as CIE 015:2018 tabulates them), on ``dentalux.color.GRID``:
the 3 x n weights of colour-science's ``msds_to_XYZ(method='Integration')`` on unit
spectra, scaled so that a perfect diffuser reads Y = 1, and the chromaticity of that white.
tests/test_color.py recomputes every entry with the installed colour-science and requires
the same numbers, so the file cannot drift from its source.

Run: ``PYTHONPATH=python .venv/bin/python python/dentalux/data/make_colour_weights.py``.
"""

from __future__ import annotations

import json
from pathlib import Path

OUT = Path(__file__).with_name("colour_weights.json")
#: (illuminant, observer) pairs tabulated: the default reading's and the 10° observer's
SYSTEMS = (("D65", "2"), ("D65", "10"))


def entries() -> list[dict]:
    import colour
    from dentalux.color import GRID, ColourSystem

    out = []
    for illuminant, observer in SYSTEMS:
        cs = ColourSystem(illuminant, observer, GRID, tabulated=False)
        out.append({"illuminant": illuminant, "observer": cs.observer, "grid": list(GRID),
                    "weights": cs.weights.tolist(), "white_xy": cs.white_xy.tolist(),
                    "colour_science": colour.__version__})
    return out


def main() -> None:
    doc = {"about": "Integration weights of dentalux.color.ColourSystem (XYZ = weights @ "
                    "spectrum on the grid, Y = 1 for a perfect diffuser) and its white's "
                    "chromaticity. Status: derived, by make_colour_weights.py, from "
                    "colour-science's CIE colour matching functions and CIE D65 (CIE "
                    "015:2018); checked against colour-science by tests/test_color.py.",
           "systems": entries()}
    OUT.write_text(json.dumps(doc, indent=1) + "\n")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
