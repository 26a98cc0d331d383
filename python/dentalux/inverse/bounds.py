"""Input checks for a fit: field ranges, and the bounds no slab can cross.

For a slab of index n in surroundings n_out lit by a normal collimated beam:

- TT + TR <= 1 (what is absorbed cannot be negative);
- TR >= R0 = ((n - n_out)/(n + n_out))^2 when TR includes the specular reflection: the first
  face reflects R0 whatever is inside;
- TT <= (1 - R0)/(1 + R0), the transmittance of a clear, non-absorbing slab (the unscattered
  limit with multiple reflections between the faces): scattering and absorption only lower it.

Each violation raises ValueError naming the bound and the numbers.

A further, model-level bound is used to explain a failed fit (:func:`clear_slab_tr`): for a
given TT, a non-scattering absorbing slab has the lowest TR that the transport models reach
(scattering sends light back). Data just below that line - typical of weakly scattering
samples with noise - cannot be fitted.
"""

from __future__ import annotations

import math
from numbers import Real

from dentalux.inverse.models.boundary import specular


def check_number(name: str, value, lo: float, hi: float, lo_open: bool = False,
                 hi_open: bool = False, unit: str = "") -> float:
    """``value`` as a float, or ValueError naming ``name`` and the allowed range."""
    lb, rb = ("(" if lo_open else "["), (")" if hi_open else "]")
    rng = f"{lb}{lo}, {hi}{rb}" + (f" {unit}" if unit else "")
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
        raise ValueError(f"{name} = {value!r} is out of range: allowed a number in {rng}")
    v = float(value)
    if v < lo or v > hi or (lo_open and v == lo) or (hi_open and v == hi):
        raise ValueError(f"{name} = {v} is out of range: allowed {rng}")
    return v


def check_measurement(tt: float, tr: float, n: float, n_out: float, diffuse_only: bool) -> None:
    """Raise ValueError when (TT, TR) is outside what any slab with these indices can give."""
    r0 = specular(n, n_out)
    if tt + tr > 1.0:
        raise ValueError(
            f"tt + tr = {tt + tr:.6g} > 1: the absorbed fraction would be negative "
            "(bound crossed: TT + TR <= 1)"
        )
    if not diffuse_only and tr < r0:
        raise ValueError(
            f"tr = {tr:.6g} is below the specular reflection of the front face, "
            f"R0 = {r0:.6g} for n = {n}, n_outside = {n_out} (bound crossed: TR >= R0; "
            "use tr_diffuse_only if TR excludes the specular reflection)"
        )
    t_clear = (1.0 - r0) / (1.0 + r0)
    if tt > t_clear:
        raise ValueError(
            f"tt = {tt:.6g} is above the unscattered limit {t_clear:.6g} of a clear slab with "
            f"n = {n}, n_outside = {n_out} (bound crossed: TT <= (1 - R0)/(1 + R0))"
        )


def clear_slab_tr(tt: float, n: float, n_out: float, diffuse_only: bool) -> float:
    """TR of the non-scattering, absorbing slab whose TT equals ``tt``.

    With x = exp(-mua d) and R0 the normal-incidence Fresnel reflectance:
    TT = (1 - R0)^2 x / (1 - R0^2 x^2), TR = R0 + (1 - R0)^2 R0 x^2 / (1 - R0^2 x^2).
    """
    r0 = specular(n, n_out)
    a = (1.0 - r0) ** 2
    if r0 * tt < 1e-12:
        x = tt / a
    else:
        x = (-a + math.sqrt(a * a + 4.0 * r0 * r0 * tt * tt)) / (2.0 * r0 * r0 * tt)
    x = min(x, 1.0)
    tr = r0 + a * r0 * x * x / (1.0 - r0 * r0 * x * x)
    return tr - r0 if diffuse_only else tr
