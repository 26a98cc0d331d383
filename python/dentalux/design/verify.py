"""Verification of a design by the full Monte Carlo read through the instrument.

The design's specimen is read by :func:`dentalux.dental.read` (the same forward model as
``dentalux shade --layer``), with a different seed from the search's response surface, so
the two are independent estimates. A design is ``verified`` when every compared number
(L*, a*, b* over the white backing, and TP00 where a TP target is given) agrees with the
fast model within ``SIGMAS`` combined standard errors, sqrt(s_fast^2 + s_mc^2 + FLOOR^2),
and the verification could have failed: ``SIGMAS`` combined standard errors amount to less
than a perceptible difference (ΔE00 0.8) at the design's colour. A verification too noisy to
see a perceptible disagreement verifies nothing and says so. FLOOR stands for what no
standard error covers, the fast model's interpolation between its nodes: where both reads
are noise-free (the layered solver on a laterally infinite specimen) the two must then agree
within SIGMAS x FLOOR = 0.1 in each of L*, a*, b* and TP00, the resolution a decision needs.
"""

from __future__ import annotations

import math

import numpy as np

from dentalux import dental
from dentalux.color import delta_e00, delta_e00_scale

SIGMAS = 4.0
#: the standard error every comparison allows at least, in L*, a*, b* and TP00 (module doc)
FLOOR = 0.025


def delta_e_stderr(lab, lab_err, target, target_err=(0.0, 0.0, 0.0)) -> float:
    """First-order standard error of ΔE00(lab, target) from both colours' L*, a*, b* errors."""
    lab, target = np.asarray(lab, float), np.asarray(target, float)
    de = float(delta_e00(lab, target))
    var = 0.0
    for j in range(3):
        step = np.zeros(3)
        step[j] = 1e-4
        d1 = (float(delta_e00(lab + step, target)) - de) / 1e-4
        d2 = (float(delta_e00(lab, target + step)) - de) / 1e-4
        var += (d1 * lab_err[j]) ** 2 + (d2 * target_err[j]) ** 2
    return math.sqrt(var)


def compare(fast: dict, mc: dental.DentalMetrics, tp: bool) -> dict:
    """z-scores of the fast model against the Monte Carlo read, and the verdict."""
    keys = [("L", 0), ("a", 1), ("b", 2)]
    z = {}
    combined = [math.hypot(fast["stderr"]["lab_white"][j], mc.stderr[f"lab_white.{c}"], FLOOR)
                for c, j in keys]
    for c, j in keys:
        z[f"lab_white.{c}"] = (fast["values"]["lab_white"][j] - mc.lab_white[j]) / combined[j]
    if tp:
        s = math.hypot(fast["stderr"]["tp00"], mc.stderr["tp00"], FLOOR)
        z["tp00"] = (fast["values"]["tp00"] - mc.tp00) / s
    worst = max(abs(v) for v in z.values())
    resolution = SIGMAS * delta_e00_scale(mc.lab_white, combined)
    could_fail = resolution <= dental.PT
    return {"z": z, "max_abs_z": worst, "verified": bool(worst <= SIGMAS and could_fail),
            "agrees": bool(worst <= SIGMAS), "resolution_delta_e00": resolution,
            "could_fail": bool(could_fail),
            "delta_e00_fast_vs_mc": float(delta_e00(np.asarray(fast["values"]["lab_white"]),
                                                    np.asarray(mc.lab_white)))}
