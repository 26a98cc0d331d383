"""A procedural maxillary first molar (frame and boundaries: :mod:`dentalux.teeth.tooth`).

Crown and root trunk: a loft of superellipse cross-sections (rounded rectangles) along z,
closed on top by an occlusal surface with four cusps (mesio-buccal, disto-buccal,
mesio-lingual, disto-lingual: Gaussian bumps on a central fossa) and below the trunk by a
plane; three roots (mesio-buccal, disto-buccal, palatal) are round cones blended onto the
trunk. The dentin is the outer field offset by a thickness field: lateral enamel grows from
``root_layer_mm`` at the CEJ to ``lateral_enamel_mm``; occlusal enamel is thickest under the
cusp tips (``cusp_enamel_mm``) and thinner in the fossae (``fossa_enamel_mm``).

Dimensions: the usual textbook values for this tooth (Wheeler's tables as commonly quoted;
docs/explanation/tooth-optics.md §6 has none for molars and they were not checked against a
stored source): crown length (CEJ to cusp tip) 7.5 mm, mesio-distal 10.0 mm, bucco-lingual 11.0
mm, cervical 8.0 x 10.0 mm, buccal roots about 12 mm and the palatal root about 13 mm long.
Enamel thickness follows docs/explanation/tooth-optics.md §6: thickest at cusp tips (2.5-3.0 mm
quoted by a popular source), about 0.1 mm at the CEJ; molar enamel is thicker than premolar
enamel (Stroud et al. 1998). Not modelled: pulp chamber and canals, the oblique ridge, grooves,
the scalloped CEJ.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PchipInterpolator

from dentalux.teeth.mesh import extract
from dentalux.teeth.sdf import Grid, normalize, round_cone, section, smax, smin, smoothstep
from dentalux.teeth.tooth import Tooth

CROWN_WIDTH_MM = 10.0  # mesio-distal
CROWN_THICKNESS_MM = 11.0  # bucco-lingual
CROWN_LENGTH_MM = 7.5
ROOT_LENGTH_MM = 13.0  # palatal root, the longest

_Z = [-4.5, -2.0, 0.0, 1.5, 3.0, 4.5, 6.0, 8.0]
_HALF_WIDTH = [3.6, 3.85, 4.0, 4.6, 5.0, 4.95, 4.6, 4.1]  # x
_BUCCAL = [4.0, 4.4, 4.6, 5.1, 5.3, 5.2, 4.8, 4.3]  # +y
_LINGUAL = [4.1, 4.6, 5.0, 5.5, 5.7, 5.6, 5.2, 4.6]  # -y
_EXPONENT = 2.6
_FOSSA_Z = 5.5
# cusps: (x, y, height above the fossa plane, width) [mm]
_CUSPS = ((2.4, 2.6, 1.95, 1.55), (-2.5, 2.6, 1.75, 1.5),
          (2.2, -2.7, 2.0, 1.75), (-2.6, -2.9, 1.35, 1.35))
# roots: start point, apex, start radius, apex radius [mm]
_ROOTS = (((2.4, 2.3, -2.5), (2.9, 3.0, -12.0), 1.75, 0.45),
          ((-2.4, 2.3, -2.5), (-3.1, 3.2, -11.5), 1.55, 0.4),
          ((0.0, -2.6, -2.5), (0.0, -4.6, -12.45), 2.0, 0.55))


def _cusp_field(x, y):
    """(height of the occlusal surface above the fossa plane [mm], cusp weight in [0, 1])."""
    h = np.zeros(np.broadcast_shapes(x.shape, y.shape))
    w = np.zeros_like(h)
    for cx, cy, height, sigma in _CUSPS:
        g = np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2.0 * sigma**2))
        h = np.maximum(h, height * g)
        w = np.maximum(w, g)
    return h, w


def molar(resolution: float = 0.2, root_layer_mm: float = 0.08,
          lateral_enamel_mm: float = 1.3, cusp_enamel_mm: float = 2.4,
          fossa_enamel_mm: float = 1.3) -> Tooth:
    """Build the molar on a grid of node spacing ``resolution`` [mm]; thickness parameters
    as in the module docstring [mm]."""
    for key, v, lo, hi in (("root_layer_mm", root_layer_mm, 0.01, 0.5),
                           ("lateral_enamel_mm", lateral_enamel_mm, 0.1, 2.5),
                           ("cusp_enamel_mm", cusp_enamel_mm, 0.2, 3.5),
                           ("fossa_enamel_mm", fossa_enamel_mm, 0.2, 3.5)):
        if not (isinstance(v, int | float) and lo <= v <= hi):
            raise ValueError(f"{key} = {v!r} is out of range: allowed [{lo}, {hi}] mm")
    grid = Grid.around((-5.4, -6.6, -ROOT_LENGTH_MM - 0.3), (5.4, 6.0, CROWN_LENGTH_MM + 0.3),
                       resolution)
    x, y, z = grid.points()
    zc = np.clip(z, _Z[0], _Z[-1])
    a, bu, li = (PchipInterpolator(_Z, v)(zc) for v in (_HALF_WIDTH, _BUCCAL, _LINGUAL))
    sec = normalize(section(x, y, a, bu, li, _EXPONENT), resolution)
    bump, weight = _cusp_field(x, y)
    occlusal = normalize(np.broadcast_to(z - (_FOSSA_Z + bump), np.broadcast_shapes(
        x.shape, y.shape, z.shape)), resolution)
    trunk_floor = _Z[0] + 0.5 - z
    roots = [round_cone(x, y, z, p0, p1, r0, r1) for p0, p1, r0, r1 in _ROOTS]
    root_union = smin(smin(roots[0], roots[1], 0.8), roots[2], 0.8)

    def body(sec_f, occ_f, floor_f, roots_f):
        crown = smax(smax(sec_f, occ_f, 0.8), floor_f, 1.0)
        return smin(crown, roots_f, 1.2)

    lateral = root_layer_mm + (lateral_enamel_mm - root_layer_mm) * smoothstep(0.0, 3.5, z)
    occ_thick = fossa_enamel_mm + (cusp_enamel_mm - fossa_enamel_mm) * weight
    outer = body(sec, occlusal, trunk_floor, root_union)
    inner = body(sec + lateral, occlusal + occ_thick, trunk_floor + root_layer_mm,
                 root_union + root_layer_mm)
    return Tooth(
        name="molar",
        enamel=extract(outer, grid),
        dentin=extract(inner, grid),
        resolution=float(resolution),
        targets={
            "crown_width_mm": [CROWN_WIDTH_MM, "textbook value, maxillary first molar"],
            "crown_thickness_mm": [CROWN_THICKNESS_MM, "textbook value, maxillary first molar"],
            "crown_length_mm": [CROWN_LENGTH_MM, "textbook value, maxillary first molar"],
            "root_length_mm": [ROOT_LENGTH_MM, "textbook value (palatal root)"],
        },
        params={"resolution": resolution, "root_layer_mm": root_layer_mm,
                "lateral_enamel_mm": lateral_enamel_mm, "cusp_enamel_mm": cusp_enamel_mm,
                "fossa_enamel_mm": fossa_enamel_mm},
    )
