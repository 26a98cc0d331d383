"""A specimen's spectra as an instrument reads them, with what their uncertainty needs.

:class:`ReadSpectra` holds, per band, the reading over the black backing, over the white
backing and in transmission (reflectance factors, :mod:`dentalux.instrument`), and what
carries their Monte Carlo uncertainty into any number computed from them:

- ``replicates``: independent replicate estimates of the same spectra (groups of photon
  batches). Every channel and every band of one replicate comes from the same photons where
  the walk is shared, so their correlations (black with white, the bands of one walk) are
  in the replicates and :meth:`propagate` keeps them.
- otherwise ``inputs``, ``inputs_stderr`` and ``combine``: independent per-band inputs (the
  infinite geometry's R1, T1, R2, T2 and the transmittance, each its own run) and the map
  from them to the spectra; the delta method then adds their variances.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

CHANNELS = ("over_black", "over_white", "transmitted")
# step of the numerical derivatives of the delta method (readings are fractions of 1)
STEP = 1e-6


def replicate_variance(weights: np.ndarray, deviations: np.ndarray) -> np.ndarray:
    """Variance of the weighted mean of replicates from their deviations about it (R, ...),
    weights (R,) summing to one, with the R / (R - 1) correction for the estimated mean."""
    r = len(weights)
    return np.tensordot(weights**2, deviations**2, axes=([0], [0])) * r / max(r - 1, 1)


@dataclass
class ReadSpectra:
    """Readings (channels × bands) of one specimen, with their uncertainty carriers."""

    wavelengths_nm: np.ndarray
    values: np.ndarray
    stderr: np.ndarray
    edge_loss: np.ndarray
    photons: int
    cpu_seconds: float
    method: str
    replicates: np.ndarray | None = None
    replicate_weights: np.ndarray | None = None
    inputs: np.ndarray | None = None
    inputs_stderr: np.ndarray | None = None
    combine: Callable[[np.ndarray], np.ndarray] | None = None
    extra: dict = field(default_factory=dict)

    def channel(self, name: str) -> np.ndarray:
        return self.values[CHANNELS.index(name)]

    def propagate(self, fn: Callable[[np.ndarray], dict]) -> tuple[dict, dict]:
        """``fn`` of the spectra (a batch (..., channels, bands) -> dict of arrays (...) or
        (..., 3)) at the estimate, and the standard error of each of its outputs (first
        order, with every correlation the replicates carry)."""
        if self.replicates is not None:
            base = self.values
            n_in = base.size
            batch = np.broadcast_to(base, (1 + n_in,) + base.shape).copy()
            batch.reshape(1 + n_in, -1)[1 + np.arange(n_in), np.arange(n_in)] += STEP
            out = fn(batch)
            dev = (self.replicates - base).reshape(len(self.replicates), -1)  # (R, n_in)
            w = self.replicate_weights
            stderr = {}
            for key, value in out.items():
                grad = (value[1:] - value[0]) / STEP  # (n_in,) or (n_in, 3)
                z = np.tensordot(dev, grad, axes=([1], [0]))  # (R,) or (R, 3)
                stderr[key] = np.sqrt(replicate_variance(w, z))
            return {k: v[0] for k, v in out.items()}, stderr
        base = self.inputs
        n_in = base.size
        batch = np.broadcast_to(base, (1 + n_in,) + base.shape).copy()
        batch.reshape(1 + n_in, -1)[1 + np.arange(n_in), np.arange(n_in)] += STEP
        out = fn(self.combine(batch))
        sig = self.inputs_stderr.ravel()
        stderr = {}
        for key, value in out.items():
            grad = (value[1:] - value[0]) / STEP
            stderr[key] = np.sqrt(np.tensordot(sig**2, grad**2, axes=([0], [0])))
        return {k: v[0] for k, v in out.items()}, stderr
