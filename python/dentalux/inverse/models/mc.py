"""Monte Carlo forward model: the slab simulator (:func:`dentalux.slab.simulate`).

Every evaluation uses the same seed (common random numbers), so the difference between two
nearby (mua, mus) is far smaller than the statistical error of either, and the weighted
(MCML-style) estimator makes TT and TR continuous in mua. The statistical error of the last
evaluation is kept in ``last_stderr`` so the fit can add it to the interval.
"""

from __future__ import annotations

import numpy as np

from dentalux.inverse.models import Sample


class MonteCarlo:
    """The slab simulator with a fixed seed and photon count."""

    name = "mc"

    def __init__(self, photons: int = 400_000, seed: int = 1, estimator: str = "weighted"):
        from dentalux.limits import MAX_FIT_PHOTONS, as_int

        photons = as_int(photons, "photons", 1000, MAX_FIT_PHOTONS)
        seed = as_int(seed, "seed", 0, 2**64 - 1)
        if estimator not in ("weighted", "analog"):
            raise ValueError(f"estimator = {estimator!r}: allowed 'weighted' or 'analog'")
        self.photons = photons
        self.seed = seed
        self.estimator = estimator
        self.last_stderr = (0.0, 0.0)
        self.evaluations = 0

    def forward(self, mua, mus, sample: Sample):
        """(TT, TR) and, in ``last_stderr``, their standard errors; scalars only."""
        from dentalux.slab import Layer, simulate

        if np.ndim(mua) or np.ndim(mus):
            pairs = zip(*np.broadcast_arrays(mua, mus), strict=True)
            out = [self.forward(a, s, sample) for a, s in pairs]
            return np.array([o[0] for o in out]), np.array([o[1] for o in out])
        layer = Layer(mua=float(mua), mus=float(mus), g=sample.g, n=sample.n,
                      thickness=sample.thickness, fd=sample.fd)
        res = simulate([layer], n_photons=self.photons, seed=self.seed, n_above=sample.n_out,
                       n_below=sample.n_out, estimator=self.estimator)
        self.evaluations += 1
        key_r = "diffuse_reflectance" if sample.diffuse_only else "total_reflectance"
        self.last_stderr = (res.stderr["total_transmittance"], res.stderr[key_r])
        return res.total_transmittance, getattr(res, key_r)
