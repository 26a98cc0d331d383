"""Kubelka-Munk two-flux slab with Saunderson's surface correction.

Mapping from transport coefficients (the common no-absorption-term form, see
docs/explanation/tooth-optics.md 2.3): K = 2 mua, S = (3/4) mus (1 - g) [1/mm]. The interior of the
slab of thickness X has, with beta = sqrt(K (K + 2 S)),

    R_i = S sinh(beta X) / ((S + K) sinh(beta X) + beta cosh(beta X)),
    T_i = beta / ((S + K) sinh(beta X) + beta cosh(beta X)),

written with sinh(beta X) / (beta X) so that K -> 0 is exact. The two faces are added as
layers (Saunderson): light enters with 1 - k1 (k1 = normal-incidence Fresnel reflectance,
counted in TR as the specular part) and is then treated as diffuse; diffuse light inside is
reflected by each face with k2 = R_phi, the Lambertian-averaged internal Fresnel
reflectance. Interior plus bottom face: R_b = R_i + T_i^2 k2 / (1 - R_i k2),
T_b = T_i (1 - k2) / (1 - R_i k2); then the top face gives
TR = k1 + (1 - k1)(1 - k2) R_b / (1 - k2 R_b) and TT = (1 - k1) T_b / (1 - k2 R_b).
KM has no collimated beam, so it is poor when few photons scatter. In particular, with the
Fresnel k2 of a high-index sample its clear-slab limit TR = k1 + (1 - k1) k2 / (1 + k2) is
far above the true one (0.41 vs 0.087 for n = 1.55), so thin, weakly scattering discs such
as the paper's Table 1 lie outside what it can produce and the fit reports that bound.
``KubelkaMunk(k2=...)`` sets an empirical internal reflectance instead (Saunderson's k2 is
often treated as a free constant, 0.4-0.6 in colorant work; k2 = 0 drops the internal
reflections altogether).
"""

from __future__ import annotations

import numpy as np

from dentalux.inverse.models import Sample
from dentalux.inverse.models.boundary import moments, specular


class KubelkaMunk:
    """Kubelka-Munk with Saunderson correction (see module docstring)."""

    name = "km"

    def __init__(self, k2: float | None = None):
        if k2 is not None and not (0.0 <= k2 < 1.0):
            raise ValueError(f"km_k2 = {k2}: allowed [0, 1)")
        self.k2 = k2

    def forward(self, mua, mus, sample: Sample):
        """(TT, TR) for absorption mua and scattering mus [1/mm]; arrays broadcast."""
        mua = np.asarray(mua, dtype=float)
        mus = np.asarray(mus, dtype=float)
        k = 2.0 * mua
        s = 0.75 * mus * (1.0 - sample.g_eff)
        x = sample.thickness
        bx = np.sqrt(k * (k + 2.0 * s)) * x
        # sinh(bx)/bx and cosh(bx), divided by cosh(bx) for large bx to avoid overflow.
        big = bx > 30.0
        bxs = np.where(big, 1.0, bx)
        shc = np.where(bx < 1e-6, 1.0 + bx**2 / 6.0, np.sinh(bxs) / np.where(bx < 1e-6, 1, bxs))
        ch = np.cosh(bxs)
        # Large bx: sinh/cosh -> 1, so R_i -> S/(S+K+beta), T_i -> 2 beta e^{-bx}/(S+K+beta).
        den = (s + k) * x * shc + ch
        r_i = np.where(big, s / (s + k + bx / x), s * x * shc / den)
        t_i = np.where(big, 2.0 * (bx / x) * np.exp(-bx) / (s + k + bx / x), 1.0 / den)
        k1 = specular(sample.n, sample.n_out)
        k2 = moments(sample.n, sample.n_out)[0] if self.k2 is None else self.k2
        r_b = r_i + t_i**2 * k2 / (1.0 - r_i * k2)
        t_b = t_i * (1.0 - k2) / (1.0 - r_i * k2)
        tr = (0.0 if sample.diffuse_only else k1) + (1.0 - k1) * (1.0 - k2) * r_b / (1.0 - k2 * r_b)
        tt = (1.0 - k1) * t_b / (1.0 - k2 * r_b)
        return tt, tr
