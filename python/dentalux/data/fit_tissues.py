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
the check. Dentin gets a factor on its transcribed μa, chosen on a coarse grid so that 0.9 mm
of the fitted enamel over 6 mm of dentin, read by the ``45-0`` preset over black, lies nearest
the centre of the natural-tooth range (L*, natural_teeth.py), and then a factor on μs for TP.

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
DENTIN_MUA_GRID = (0.3, 0.15, 0.07)
SOURCE = {"enamel": "enamel@zoller2018-kienle", "dentin": "dentin@zoller2018-kienle"}


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
    from dentalux import natural_teeth

    dentin = materials.get(SOURCE["dentin"])
    centre = float(np.mean(natural_teeth.reference_range("mid-incisal")["L"]))
    best = None
    for ka in DENTIN_MUA_GRID:
        mua = (lambda k: lambda lam: float(dentin.at(lam).mua) * k)(ka)
        factor = fit_factor(dentin, TP_TARGET["dentin"], mua, hi=20.0, steps=7)
        tooth = dental.read([(fitted, 0.9), (Variant(dentin, factor, mua), 6.0)],
                            instrument="45-0", photons=10_000, bands=list(range(380, 781, 20)))
        value, se = tp(Variant(dentin, factor, mua))
        print(f"dentin mua x {ka}: mus x {factor:.3f}, TP {value:.2f} +- {se:.2f}; enamel over "
              f"dentin reads {np.round(tooth.lab_black, 1)} (range centre L* {centre:.1f})")
        if best is None or abs(tooth.lab_black[0] - centre) < best[0]:
            best = (abs(tooth.lab_black[0] - centre), ka, factor)
    print(f"dentin: mua x {best[1]}, mus x {best[2]:.3f}")
