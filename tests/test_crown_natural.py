"""The natural incisor of the crown figure, read in the render as a 45°/0° instrument reads a
tooth (the figure's two 45° lights, a white-tile calibration): its labial middle third falls
inside the published natural-tooth colour range, and its incisal third is more translucent
than its cervical third (TP over a black and a white contrastor). Renders at 160 × 120 with
the preview photon counts: `make validate` only."""

from dataclasses import replace

import pytest
from dentalux import figures as F
from dentalux import natural_teeth


@pytest.mark.slow
def test_natural_incisor_colour_and_translucency_by_thirds():
    q = replace(F.QUALITIES["preview"], resolution=(160, 120))
    tp = F.crown_translucency(q)
    print("\nthird: Lab over black | over white | TP")
    for name in F.NATURAL_THIRDS:
        print(name, [round(x, 1) for x in tp[name]["lab_black"]],
              [round(x, 1) for x in tp[name]["lab_white"]], round(tp[name]["tp"], 2))
    rng = natural_teeth.reference_range("mid-incisal")
    assert natural_teeth.inside(tp["middle"]["lab_black"], rng), (tp["middle"], rng)
    # the enamel-only incisal edge against the dentin-backed cervical third: a margin far
    # beyond the few-tenths scatter of a region's mean at these photon counts
    assert tp["incisal"]["tp"] > 2 * tp["cervical"]["tp"] + 3.0, tp
