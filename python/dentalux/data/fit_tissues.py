"""Derive the fitted default enamel and dentin of materials.toml (run from the checkout).

Two published readings of human teeth pin the defaults (tooth_measurements.csv,
natural_teeth.csv):

- the TP of 1 mm slabs through a 3 mm window (Yu, Ahn & Lee 2009: enamel 18.7, dentin 16.4),
  read here through the ``contact-probe-3mm`` instrument by the Monte Carlo slab simulator;
- the colour of enamel of infinite thickness (Wee et al. 2023, 45:0, in vivo: L* 73.5,
  b* 11.9), computed here by adding-doubling (iadpython, 16 quadrature points) for a 60 mm
  slab, specular reflection excluded as 45:0 excludes it.

Each tissue keeps g, n and the μs spectral shape of its Kienle-group variant (Zoller et al.
2018, transcribed). Enamel gets a factor on μs (for TP) and a power-law μa(λ) = μa(700 nm)
(λ/700)^-p (for L* and b* at infinite thickness), fitted alternately; a* is not fitted and is
the check. Dentin keeps the μs of ``dentin@fitted-yu2009`` (a factor on the transcription,
for TP) and gets a power-law μa(λ) fitted so that the procedural incisor's labial middle
third along the view (0.9 mm fitted enamel, 2.9 mm dentin, 0.6 mm enamel), read by the
``45-0`` preset over black, lies nearest Wee et al.'s mean natural-tooth colour, each of L*,
a*, b* weighted by its published sd (natural_teeth.csv); its TP is then checked.

    python python/dentalux/data/fit_tissues.py   # prints the fitted numbers
"""

from __future__ import annotations

import math

import numpy as np
from dentalux import dental, materials

INSTRUMENT = "contact-probe-3mm"
PHOTONS = 20_000
TP_TARGET = {"enamel": 18.7, "dentin": 16.4}
ENAMEL_INFINITE_LB = (73.5, 11.9)  # Wee et al. 2023, mid-incisal enamel at infinite thickness
SOURCE = {"enamel": "enamel@zoller2018-kienle", "dentin": "dentin@zoller2018-kienle"}
# the incisor's labial middle third along the view (dentalux.design.render.NATURAL_STACK)
MIDDLE_THIRD_MM = (0.9, 2.9, 0.6)
# Wee et al. 2023, natural teeth: mean and sd of L*, a*, b* (natural_teeth.csv)
TOOTH_MEAN, TOOTH_SD = (73.5, 2.2, 11.9), (7.6, 1.8, 8.4)
COLOUR_BANDS = list(range(400, 701, 20))


class Variant:
    """A material with μs multiplied by ``factor`` and, optionally, μa(λ) replaced."""

    def __init__(self, base, factor: float, mua=None):
        self.base, self.factor, self.mua = base, factor, mua
        self.name = f"{base.name} x{factor:.3g}"

    def at(self, lam):
        o = self.base.at(lam)
        mua = o.mua if self.mua is None else self.mua(float(lam))
        return type("Optics", (), dict(mua=mua, mus=o.mus * self.factor, g=o.g, fd=o.fd,
                                       n=o.n))


def tp(material) -> tuple[float, float]:
    m = dental.metrics(material, 1.0, photons=PHOTONS, instrument=INSTRUMENT)
    return m.tp, m.stderr["tp"]


def fit_factor(base, target: float, mua=None, lo: float = 1.0, hi: float = 60.0,
               steps: int = 9) -> float:
    """Bisection in log(factor) on TP (TP falls as scattering rises; common random numbers)."""
    for _ in range(steps):
        mid = math.sqrt(lo * hi)
        if tp(Variant(base, mid, mua))[0] > target:
            lo = mid
        else:
            hi = mid
    return math.sqrt(lo * hi)


def power_mua(mua700: float, p: float):
    return lambda lam: mua700 * (lam / 700.0) ** (-p)


def infinite_lab(material) -> np.ndarray:
    """CIELAB of a 60 mm slab of ``material`` (specular excluded), by adding-doubling."""
    import iadpython as iad
    from dentalux.color import spectrum_to_Lab
    from dentalux.spectra import full_bands

    wl = full_bands()
    r = []
    for lam in wl:
        o = material.at(float(lam))
        d = 60.0
        s = iad.Sample(a=o.mus / (o.mua + o.mus), b=(o.mua + o.mus) * d, g=float(o.g), d=d,
                       n=float(o.n), quad_pts=16)
        r.append(float(s.rt()[0]) - ((o.n - 1) / (o.n + 1)) ** 2)
    return spectrum_to_Lab(np.array(r), wl)


def fit_enamel_absorption(base, factor: float, x0=(math.log(0.02), 3.0)) -> tuple[float, float]:
    """μa(700 nm) and p so that the infinite slab reads Wee et al.'s L* and b*."""
    from scipy.optimize import least_squares

    target = np.array(ENAMEL_INFINITE_LB)

    def residual(x):
        lab = infinite_lab(Variant(base, factor, power_mua(math.exp(x[0]), x[1])))
        return lab[[0, 2]] - target

    x = least_squares(residual, x0=list(x0), diff_step=1e-3).x
    return math.exp(x[0]), float(x[1])


def middle_third_lab(enamel, dentin) -> np.ndarray:
    """CIELAB of the middle-third stack over black (45-0, both backings 0), Monte Carlo."""
    e, d, lingual = MIDDLE_THIRD_MM
    m = dental.read([(enamel, e), (dentin, d), (enamel, lingual)], instrument="45-0",
                    backing_black=0.0, backing_white=0.0, photons=10_000, bands=COLOUR_BANDS)
    return np.asarray(m.lab_black)


def fit_dentin_absorption(enamel, dentin, x0=(math.log(0.006), 5.0)) -> tuple[float, float]:
    """μa(700 nm) and p of dentin's power law nearest the natural-tooth mean, L*, a*, b*
    each over its sd (common random numbers: every evaluation has seed 1)."""
    from scipy.optimize import least_squares

    mean, sd = np.array(TOOTH_MEAN), np.array(TOOTH_SD)

    def residual(x):
        lab = middle_third_lab(enamel, Variant(dentin, 1.0, power_mua(math.exp(x[0]), x[1])))
        return (lab - mean) / sd

    x = least_squares(residual, x0=list(x0), diff_step=1e-2, max_nfev=25).x
    return math.exp(x[0]), float(x[1])


if __name__ == "__main__":
    enamel = materials.get(SOURCE["enamel"])
    factor, mua = 20.0, None
    for _ in range(2):
        mua700, p = fit_enamel_absorption(enamel, factor)
        mua = power_mua(mua700, p)
        factor = fit_factor(enamel, TP_TARGET["enamel"], mua)
    mua700, p = fit_enamel_absorption(enamel, factor)
    fitted = Variant(enamel, factor, power_mua(mua700, p))
    print(f"enamel: mus x {factor:.3f}; mua(700) {mua700:.5f}, p {p:.3f} -> mua(400) "
          f"{power_mua(mua700, p)(400.0):.5f}; TP {tp(fitted)[0]:.2f} +- {tp(fitted)[1]:.2f};"
          f" infinite Lab {np.round(infinite_lab(fitted), 2)}")
    # dentin: the μs of dentin@fitted-yu2009 (2.09 x the transcription, for TP), μa fitted
    dentin = materials.get("dentin@fitted-yu2009")
    mua700, p = fit_dentin_absorption(fitted, dentin)
    fitted_dentin = Variant(dentin, 1.0, power_mua(mua700, p))
    value, se = tp(fitted_dentin)
    print(f"dentin: mua(700) {mua700:.5f}, p {p:.3f} -> mua(400) {power_mua(mua700, p)(400.0):.4f};"
          f" TP {value:.2f} +- {se:.2f}; middle third reads "
          f"{np.round(middle_third_lab(fitted, fitted_dentin), 2)}")
