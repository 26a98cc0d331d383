"""A procedural maxillary central incisor (frame and boundaries: :mod:`dentalux.teeth.tooth`).

The outer surface is a loft of superellipse cross-sections along z (half-widths from smooth
monotone splines through the control points below), closed by a rounded incisal edge and a
rounded apex. Its field is normalised to a first-order distance, and the dentin is the set
where that distance exceeds a thickness field: ``lateral(z)`` on the faces and ``incisal`` under
the incisal edge. Every part of the dentin field is the outer field plus at least
``root_layer_mm`` > 0, which keeps the dentin strictly inside.

Dimensions: crown width 8.71 mm and crown length 10.23 mm are the clinical-crown means of
Orozco-Varo et al. 2015 (J Prosthet Dent 113:565; docs/explanation/tooth-optics.md §6). Crown
thickness (labio-lingual, 7.0 mm), cervical width (7.0 mm) and root length (13 mm) are the usual
textbook values for this tooth (Wheeler's tables as commonly quoted; not checked against a
stored source). Enamel thickness: not found for incisal/labial enamel of incisors (§6 [NF]);
chosen to follow the general pattern of §6 (about 0.1 mm at the CEJ, 1-2.5 mm at the edge or
cusps): about 0.9 mm labially in the incisal two thirds, 0.6 mm lingually, and 1.8 mm of
enamel above the dentin at the incisal edge, so the incisal edge is enamel only.
Not modelled: the pulp, mamelons, the scalloped CEJ, the lingual marginal ridges (the lingual
fossa is only a concave lingual profile).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PchipInterpolator

from dentalux.teeth.mesh import extract
from dentalux.teeth.sdf import Grid, normalize, section, smax, smoothstep
from dentalux.teeth.tooth import Tooth

CROWN_WIDTH_MM = 8.7
CROWN_LENGTH_MM = 10.2
CROWN_THICKNESS_MM = 7.0
ROOT_LENGTH_MM = 13.0

# control points (z [mm], value [mm]); z = 0 is the CEJ
_Z = [-13.0, -8.0, -4.0, 0.0, 2.0, 4.5, 6.5, 8.5, 10.6]
_HALF_WIDTH = [0.95, 2.05, 2.85, 3.5, 3.7, 4.15, 4.35, 4.35, 4.35]  # mesio-distal, x
_LABIAL = [0.95, 2.0, 2.75, 3.15, 3.45, 3.05, 2.3, 1.6, 0.85]  # +y half-width
# -y half-width: cingulum bulge, then the concave lingual fossa, then the thin incisal edge
_Z_LINGUAL = [-13.0, -8.0, -4.0, 0.0, 1.8, 3.3, 5.0, 6.8, 8.7, 10.6]
_LINGUAL = [0.95, 2.0, 2.95, 3.55, 3.55, 2.5, 1.55, 1.05, 0.6, 0.25]
_EXPONENT = [2.2, 2.2, 2.2, 2.4, 2.6, 2.9, 3.0, 3.0, 3.0]


def _fields(resolution: float, root_layer_mm: float, labial_mm: float, incisal_mm: float):
    """The grid, the outer surface's field and the dentin's field (module doc)."""
    grid = Grid.around((-4.6, -4.0, -ROOT_LENGTH_MM - 0.3), (4.6, 3.8, CROWN_LENGTH_MM + 0.3),
                       resolution)
    x, y, z = grid.points()
    spline = {k: PchipInterpolator(zs, v, extrapolate=True)
              for k, zs, v in (("a", _Z, _HALF_WIDTH), ("lab", _Z, _LABIAL),
                               ("lin", _Z_LINGUAL, _LINGUAL), ("m", _Z, _EXPONENT))}
    zc = np.clip(z, _Z[0], _Z[-1])
    a, lab, lin, m = (spline[k](zc) for k in ("a", "lab", "lin", "m"))
    sec = normalize(section(x, y, a, lab, lin, m), resolution)
    # incisal edge: straight, with rounded corners (the distal one rounder)
    corner = np.where(x > 0, 0.45, 1.1) * (np.abs(x) / CROWN_WIDTH_MM * 2.0) ** 4
    incisal = z - (CROWN_LENGTH_MM - corner)
    apex = -ROOT_LENGTH_MM - z
    outer = smax(smax(sec, incisal, 0.6), apex, 1.2)
    # thickness field: lateral enamel grows from the CEJ to the incisal two thirds;
    # lingual enamel is 2/3 of labial (smooth in y)
    side = 0.8333 + 0.1667 * np.tanh(y / 1.0)
    lateral = root_layer_mm + (labial_mm * side - root_layer_mm) * smoothstep(0.0, 4.5, z)
    inner = smax(smax(sec + lateral, incisal + incisal_mm, 0.6),
                 apex + root_layer_mm, 1.2)
    return grid, outer, inner


def _check(**values) -> None:
    for key, (v, lo, hi) in values.items():
        if not (isinstance(v, int | float) and lo <= v <= hi):
            raise ValueError(f"{key} = {v!r} is out of range: allowed [{lo}, {hi}] mm")


def incisor(resolution: float = 0.2, root_layer_mm: float = 0.08,
            labial_enamel_mm: float = 0.9, incisal_enamel_mm: float = 1.8) -> Tooth:
    """Build the incisor on a grid of node spacing ``resolution`` [mm] (0.2 mm gives about
    27 k triangles per surface). ``root_layer_mm``: gap between the surfaces over the root
    and the enamel thickness at the CEJ; ``labial_enamel_mm``: labial enamel in the incisal
    two thirds (lingual 2/3 of it); ``incisal_enamel_mm``: enamel above the dentin at the
    incisal edge."""
    _check(root_layer_mm=(root_layer_mm, 0.01, 0.5),
           labial_enamel_mm=(labial_enamel_mm, 0.1, 2.0),
           incisal_enamel_mm=(incisal_enamel_mm, 0.2, 4.0))
    grid, outer, inner = _fields(resolution, root_layer_mm, labial_enamel_mm, incisal_enamel_mm)
    tooth = Tooth(
        name="incisor",
        enamel=extract(outer, grid),
        dentin=extract(inner, grid),
        resolution=float(resolution),
        targets={
            "crown_width_mm": [CROWN_WIDTH_MM, "Orozco-Varo et al. 2015 (8.71 mm)"],
            "crown_length_mm": [CROWN_LENGTH_MM, "Orozco-Varo et al. 2015 (10.23 mm)"],
            "crown_thickness_mm": [CROWN_THICKNESS_MM, "textbook value (not verified here)"],
            "root_length_mm": [ROOT_LENGTH_MM, "textbook value (not verified here)"],
        },
        params={"resolution": resolution, "root_layer_mm": root_layer_mm,
                "labial_enamel_mm": labial_enamel_mm, "incisal_enamel_mm": incisal_enamel_mm},
    )
    return tooth


def crown_surfaces(layers_mm, resolution: float = 0.2, root_layer_mm: float = 0.08,
                   incisal_mm: float = 1.8) -> list:
    """An incisor crowned with shells of labial thickness ``layers_mm`` (top to bottom):
    nested closed meshes, the outer surface (the natural tooth's), each interface and the
    prepared dentin's surface. The preparation is the natural dentin surface of
    :func:`incisor` with ``labial_enamel_mm`` = the shells' total (lingual 2/3 of it,
    tapering to ``root_layer_mm`` at the CEJ, as a crown's margin does) and at least
    ``incisal_mm`` under the incisal edge; interface k lies at the fraction (shells 1..k) /
    total of the way from the outer field to the dentin field. Both fields are first-order
    distances on the faces, so on the labial face shell k is ``layers_mm[k]`` thick; and as
    the dentin field exceeds the outer one everywhere (by >= ``root_layer_mm``), every
    interface lies strictly between them: the meshes are disjoint."""
    layers_mm = [float(t) for t in layers_mm]
    total = sum(layers_mm)
    if not layers_mm or any(t <= 0 for t in layers_mm):
        raise ValueError(f"layers_mm = {layers_mm!r}: give one or more thicknesses > 0 [mm]")
    _check(total_mm=(total, max(0.1, 2 * root_layer_mm), 2.0),
           root_layer_mm=(root_layer_mm, 0.01, 0.5), incisal_mm=(incisal_mm, 0.2, 4.0))
    grid, outer, inner = _fields(resolution, root_layer_mm, total, max(incisal_mm, total))
    out = [extract(outer, grid)]
    done = 0.0
    for t in layers_mm[:-1]:
        done += t
        f = done / total
        out.append(extract((1.0 - f) * outer + f * inner, grid))
    return out + [extract(inner, grid)]
