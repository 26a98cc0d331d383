"""Regenerate ``example-composite.csv``: SYNTHETIC measurements of an invented resin composite.

The "measurements" are forward simulations of a 1 mm disc with the dentalux slab simulator
(normal incidence, disc in air, total reflectance and total transmittance including the
specular and unscattered parts) from coefficients chosen here to resemble a yellowish,
moderately translucent composite. No real material was measured. The chosen ("true")
coefficients are written into the CSV's header so a fit can be compared with them.

Run: ``.venv/bin/python python/dentalux/data/make_example_composite.py`` (about a minute).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from dentalux.slab import Layer, simulate

WAVELENGTHS_NM = np.arange(400.0, 701.0, 25.0)
THICKNESS_MM = 1.0
N = 1.52
G = 0.75
PHOTONS = 1_000_000
SEED = 2026


def true_mus(lam):
    """Chosen scattering coefficient [1/mm]: 4.0 (λ/550 nm)^-1.0."""
    return 4.0 * (np.asarray(lam) / 550.0) ** -1.0


def true_mua(lam):
    """Chosen absorption coefficient [1/mm]: 0.03 + 0.25 exp(-(λ - 400 nm)/50 nm) (blue
    absorption, hence a yellowish colour)."""
    return 0.03 + 0.25 * np.exp(-(np.asarray(lam) - 400.0) / 50.0)


def main(path: Path = Path(__file__).with_name("example-composite.csv")) -> None:
    rows = []
    for band, lam in enumerate(WAVELENGTHS_NM):
        layer = Layer(mua=float(true_mua(lam)), mus=float(true_mus(lam)), g=G, n=N,
                      thickness=THICKNESS_MM)
        r = simulate([layer], n_photons=PHOTONS, seed=SEED, band=band)
        rows.append((lam, r.total_transmittance, r.total_reflectance,
                     r.stderr["total_transmittance"], r.stderr["total_reflectance"]))
    se = max(max(r[3], r[4]) for r in rows)
    lines = [
        "# SYNTHETIC EXAMPLE DATA - not a measurement of any real material.",
        "# An invented resin composite disc, 'measured' by forward simulation with",
        "# dentalux.slab.simulate (normal incidence, disc in air, "
        f"{PHOTONS} photons per wavelength, seed {SEED}).",
        "# tt, tr: total transmittance and total reflectance (specular and unscattered light",
        f"# included), fractions; Monte Carlo standard error <= {se:.1e}.",
        "# True coefficients used: mus = 4.0 (lambda/550)^-1.0 1/mm;",
        "# mua = 0.03 + 0.25 exp(-(lambda-400)/50) 1/mm; g = 0.75 (HG, fd = 0); n = 1.52.",
        "# Regenerate: .venv/bin/python python/dentalux/data/make_example_composite.py",
        "wavelength_nm,tt,tr,n,g,thickness_mm",
    ]
    for lam, tt, tr, _, _ in rows:
        lines.append(f"{lam:.0f},{tt:.4f},{tr:.4f},{N:.3f},{G:.2f},{THICKNESS_MM:.1f}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(path)


if __name__ == "__main__":
    main()
