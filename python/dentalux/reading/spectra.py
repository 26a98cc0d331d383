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
- ``rim_bounds``: where the layered solver's rim walk saw no event in a band and channel,
  its replicates all agree and their spread is 0; a :class:`RimBound` per walk gives the
  standard error that the zero count allows instead, which :meth:`propagate` adds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

CHANNELS = ("over_black", "over_white", "transmitted")
# step of the numerical derivatives of the delta method (readings are fractions of 1)
STEP = 1e-6
#: a rim walk that saw no event in N launched photons (no photon brought light past the rim
#: into the window) bounds the chance of one per photon below RIM_ZERO_EVENTS / N at 95 %:
#: the rule of three (-ln 0.05 = 2.996). Over several bands or channels with none, the same
#: bound holds for the sum of their chances (the zero count is one observation of them all)
RIM_ZERO_EVENTS = 3.0


def replicate_variance(weights: np.ndarray, deviations: np.ndarray) -> np.ndarray:
    """Variance of the weighted mean of replicates from their deviations about it (R, ...),
    weights (R,) summing to one, with the R / (R - 1) correction for the estimated mean."""
    r = len(weights)
    return np.tensordot(weights**2, deviations**2, axes=([0], [0])) * r / max(r - 1, 1)


@dataclass
class RimBound:
    """What one rim walk's zero count allows the terms it saw no event of.

    Per channel and band (0 where the walk saw an event): ``effect``, the largest change one
    launched photon can make to the reading (negative: a rim term lowers it), and ``cap``,
    the most the term's mean can be (the laterally infinite specimen's reading; the finite
    one is not negative); ``launched``, the walk's photons per band. Per photon the term
    Y = sum of gradient x change lies in [-down, up] and is nonzero with a chance q, so
    Var(mean) = Var(Y) / N <= E[Y^2] / N <= max(up, down) min(q max(up, down), W) / N,
    W = sum |gradient| cap; the chances q of the bands with no event sum to at most
    RIM_ZERO_EVENTS / N. A single term reads sqrt(B min(3 B / N, cap) / N), B = |effect|:
    sqrt(3) B / N where the rule of three binds."""

    effect: np.ndarray
    cap: np.ndarray
    launched: float

    def cell_variance(self) -> np.ndarray:
        """The variance bound of each channel's reading in each band on its own."""
        b, n = np.abs(self.effect), self.launched
        return b * np.minimum(RIM_ZERO_EVENTS * b / n, self.cap) / n

    def variance(self, grad: np.ndarray) -> np.ndarray:
        """The variance bound of an output of gradient ``grad`` ((channels × bands,) or
        (channels × bands, k), as in :meth:`ReadSpectra.propagate`): the largest over the
        bands' chances q (summing to at most RIM_ZERO_EVENTS / N, each band's at most what
        its cap allows), filled largest band first."""
        g = grad.reshape(self.effect.shape + (-1,))  # (channels, bands, k)
        move = g * self.effect[..., None]
        span = np.maximum(np.sum(np.maximum(move, 0.0), axis=0),
                          np.sum(np.maximum(-move, 0.0), axis=0))  # (bands, k)
        worth = np.sum(np.abs(g) * self.cap[..., None], axis=0)
        out = np.zeros(span.shape[1])
        for j in range(span.shape[1]):
            left = RIM_ZERO_EVENTS / self.launched
            for b in np.argsort(-span[:, j], kind="stable"):
                if span[b, j] <= 0 or left <= 0:
                    break
                q = min(left, worth[b, j] / span[b, j])
                out[j] += q * span[b, j] ** 2
                left -= q
        out /= self.launched
        return out.reshape(grad.shape[1:]) if grad.ndim > 1 else out[0]


def with_bounds(var: np.ndarray, bounds) -> np.ndarray:
    """Standard errors from the variances ``var`` (channels × bands) and the rim walks'
    bounds: sqrt(var + the bounds' variance) where a walk saw no event, sqrt(var) bit for bit
    elsewhere."""
    extra = sum((rb.cell_variance() for rb in bounds), np.zeros_like(var))
    return np.where(extra > 0, np.sqrt(var + extra), np.sqrt(var))


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
    rim_bounds: tuple[RimBound, ...] = ()

    def channel(self, name: str) -> np.ndarray:
        return self.values[CHANNELS.index(name)]

    def replicate_stderr(self) -> np.ndarray:
        """Standard errors (channels × bands) from the replicates alone: ``stderr`` less the
        rim walks' bounds (the noise between readings, where a fit weighs by it)."""
        return np.sqrt(replicate_variance(self.replicate_weights,
                                          self.replicates - self.values))

    def propagate(self, fn: Callable[[np.ndarray], dict]) -> tuple[dict, dict]:
        """``fn`` of the spectra (a batch (..., channels, bands) -> dict of arrays (...) or
        (..., 3)) at the estimate, and the standard error of each of its outputs (first
        order, with every correlation the replicates carry)."""
        return self.propagate_parts(fn)[:2]

    def propagate_parts(self, fn: Callable[[np.ndarray], dict]) -> tuple[dict, dict, dict]:
        """:meth:`propagate`, and the standard errors from the replicates alone (without the
        rim walks' bounds; the same where there are none), from one evaluation of ``fn``."""
        if self.replicates is not None:
            base = self.values
            n_in = base.size
            batch = np.broadcast_to(base, (1 + n_in,) + base.shape).copy()
            batch.reshape(1 + n_in, -1)[1 + np.arange(n_in), np.arange(n_in)] += STEP
            out = fn(batch)
            dev = (self.replicates - base).reshape(len(self.replicates), -1)  # (R, n_in)
            w = self.replicate_weights
            stderr, alone = {}, {}
            for key, value in out.items():
                grad = (value[1:] - value[0]) / STEP  # (n_in,) or (n_in, 3)
                z = np.tensordot(dev, grad, axes=([1], [0]))  # (R,) or (R, 3)
                var = replicate_variance(w, z)
                alone[key] = np.sqrt(var)
                for rb in self.rim_bounds:  # independent walks: their variances add
                    var = var + rb.variance(grad)
                stderr[key] = np.sqrt(var)
            return {k: v[0] for k, v in out.items()}, stderr, alone
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
        return {k: v[0] for k, v in out.items()}, stderr, stderr
