"""The single-scattering correction of the radiance read in a detector cone.

Delta-M truncation keeps the fluxes but not the radiance at a given angle: the light
scattered once, at the angle between the beam and the detector, follows the truncated phase
function instead of the true one. Nakajima & Tanaka (1988, J Quant Spectrosc Radiat Transfer
40:51) replace it: the once-scattered radiance computed with the true phase function and
scattering coefficient, less the same computed with the truncated ones (which the discrete
ordinates hold), both analytically. At spatial frequency k a ray scattered at depth z in
layer j and leaving at sin(theta) = s in the medium above is displaced by
z tan(theta_j) + sum_{i<j} d_i tan(theta_i); averaged over azimuth that is J0(k x).
"""

from __future__ import annotations

import numpy as np

from dentalux import _core
from dentalux.reading.layered import special
from dentalux.reading.layered.operators import legendre_moments
from dentalux.reading.layered.quadrature import cone_fraction

# Gauss points over each layer's depth and over the cone's cosines
DEPTH_POINTS = 48
CONE_POINTS = 16


def _fresnel_t(cos1: np.ndarray, n1: float, n2: float) -> np.ndarray:
    return 1.0 - np.asarray(_core.fresnel_reflectance(np.atleast_1d(cos1).tolist(), n1, n2))


def correction(band_stacks, ks, n_above: float, cone_deg, order: int) -> np.ndarray:
    """The change (bands, len(ks)) of the beam's reflectance into the detector cone (over
    its Lambertian fraction) when the once-scattered light takes the true phase function."""
    lo, hi = np.radians(cone_deg)
    x, wx = np.polynomial.legendre.leggauss(CONE_POINTS)
    mu_a = np.cos(hi) + (x + 1) / 2 * (np.cos(lo) - np.cos(hi))  # cosines in the medium above
    w_a = wx / 2 * (np.cos(lo) - np.cos(hi))
    s = n_above * np.sqrt(1 - mu_a**2)
    zx, zw = np.polynomial.legendre.leggauss(DEPTH_POINTS)
    ks = np.asarray(ks, float)
    frac = cone_fraction(cone_deg)
    out = np.zeros((len(band_stacks), len(ks)))
    for b, stack in enumerate(band_stacks):
        n = [lay.n for lay in stack]
        # the beam (normal) into the top layer, and the way out at each exit angle
        beam = float(_fresnel_t(np.ones(1), n_above, n[0])[0])
        out_t = _fresnel_t(np.sqrt(1 - (s / n[0]) ** 2), n[0], n_above)
        shift = np.zeros_like(s)          # lateral displacement through the layers above
        up_att = np.ones_like(s)          # attenuation and transmission on the way up
        for j, lay in enumerate(stack):
            chi = legendre_moments(lay.g, lay.fd, lay.lobes, order)
            f = chi[order]
            mut = lay.mua + lay.mus * (1 - f)
            mu_j = np.sqrt(1 - (s / n[j]) ** 2)
            tan_j = (s / n[j]) / mu_j
            cos_scat = -mu_j
            exact = np.asarray(_core.phase_eval(cos_scat.tolist(), float(lay.g), float(lay.fd),
                                                [tuple(x) for x in lay.lobes] if lay.lobes
                                                else None))
            ls = np.arange(order)
            trunc = ((2 * ls + 1) / (4 * np.pi) * (chi[:order] - f)) \
                @ np.polynomial.legendre.legvander(cos_scat, order - 1).T
            source = lay.mus * exact - lay.mus * trunc  # mus p - mus* p*
            z = (zx + 1) / 2 * lay.thickness
            wz = zw / 2 * lay.thickness
            att = np.exp(-mut * z[:, None] * (1 + 1 / mu_j[None, :]))      # (z, angles)
            disp = shift[None, :] + z[:, None] * tan_j[None, :]
            lat = special.j0(ks[:, None, None] * disp[None])                   # (k, z, angles)
            radiance = (beam * up_att * out_t * (n_above / n[j]) ** 2 * source / mu_j)
            per_angle = np.einsum("z,kza,za->ka", wz, lat, att) * radiance
            out[b] += 2 * np.pi * per_angle @ (w_a * mu_a) / frac
            # on to the next layer: the beam and the exit rays cross layer j and its floor
            if j + 1 < len(stack):
                beam *= np.exp(-mut * lay.thickness) * float(
                    _fresnel_t(np.ones(1), n[j], n[j + 1])[0])
                mu_next = np.sqrt(1 - (s / n[j + 1]) ** 2)
                up_att = up_att * np.exp(-mut * lay.thickness / mu_j) * _fresnel_t(
                    mu_next, n[j + 1], n[j])
                shift = shift + lay.thickness * tan_j
    return out
