"""The natural incisor of the crown figure, read in the render as a 45°/0° instrument reads a
tooth (the figure's two 45° lights, a white-tile calibration): its labial middle third falls
inside the published natural-tooth colour range, and its incisal third is more translucent
than its cervical third (TP over a black and a white contrastor). Renders at 160 × 120 with
the preview photon counts: `make validate` only."""

from dataclasses import replace

import pytest
from dentalux import figures as F
from dentalux import natural_teeth


@pytest.fixture(scope="module")
def thirds():
    return F.crown_translucency(replace(F.QUALITIES["preview"], resolution=(160, 120)))


@pytest.mark.slow
def test_natural_incisor_colour_and_translucency_by_thirds(thirds):
    tp = thirds
    print("\nthird: Lab over black | over white | TP")
    for name in F.NATURAL_THIRDS:
        print(name, [round(x, 1) for x in tp[name]["lab_black"]],
              [round(x, 1) for x in tp[name]["lab_white"]],
              f"{tp[name]['tp']:.2f} ± {tp[name]['tp_stderr']:.2f}")
    rng = natural_teeth.reference_range("mid-incisal")
    lab = tp["middle"]["lab_black"]
    assert rng["L"][0] <= lab[0] <= rng["L"][1], (lab, rng)  # lightness inside the range
    # the enamel-only incisal edge against the dentin-backed cervical third, beyond 4
    # standard errors of the difference (bootstrap over each region's pixels)
    inc, cer = tp["incisal"], tp["cervical"]
    assert inc["tp"] - cer["tp"] > 4 * (inc["tp_stderr"] ** 2 + cer["tp_stderr"] ** 2) ** 0.5, tp


@pytest.mark.slow
def test_natural_incisor_colour_inside_the_published_range(thirds):
    # measured 7 Dec 2026 (fourth session): the middle third over black at L*a*b* 68.8 / -0.3
    # / 9.0, inside the range (a* >= -1.4), where an earlier tissue fit read a* -2.2
    tp = thirds
    rng = natural_teeth.reference_range("mid-incisal")
    assert natural_teeth.inside(tp["middle"]["lab_black"], rng), (tp["middle"], rng)
