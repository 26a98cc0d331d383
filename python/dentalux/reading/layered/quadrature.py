"""Direction nodes shared by every medium of a plane stack.

A direction is a node in s = n sin(theta), the quantity Snell's law keeps across plane
interfaces: one node set serves every layer and the media above and below (a medium of
index n holds the nodes with s < n, a prefix of the set), refraction maps a node onto itself,
and radiance / n^2 crosses with the Fresnel transmittance. The weights are etendues
E = w mu n^2, the same in every medium holding the node, so the flux crossing an interface is
conserved node by node.

The nodes are split where a medium's critical angle falls (s = its index): in the interval
ending at an index n the owner's mu goes to 0, and the nodes are Gauss points in that mu;
elsewhere they are Gauss points in s^2, in which every medium's mu is smooth. The first
interval is Gauss-Radau with a node at normal incidence, where the beam comes in.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from dentalux import _core
from dentalux.reading.layered import interpolate


def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(n)
    return (x + 1) / 2, w / 2


def _radau(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Radau nodes and weights on [0, 1], with a node fixed at 1."""
    c = np.zeros(n + 1)
    c[n - 1:] = 1.0  # P_{n-1} + P_n vanishes at -1 and at the free nodes
    roots = np.polynomial.legendre.legroots(c)
    roots = np.sort(roots[np.abs(roots + 1) > 1e-9])
    p = np.polynomial.legendre.legval(roots, np.eye(n)[n - 1])
    x = np.concatenate([[-1.0], roots])
    w = np.concatenate([[2.0 / n**2], (1 - roots) / (n**2 * p**2)])
    return (1 - x[::-1]) / 2, w[::-1] / 2


@dataclass(frozen=True)
class Nodes:
    """Direction nodes in s, ascending (``s[0] = 0``: normal incidence), with their etendue
    weights."""

    s: np.ndarray
    etendue: np.ndarray

    def count(self, n: float) -> int:
        """How many nodes a medium of index n holds (those with s < n)."""
        return int(np.searchsorted(self.s, n, side="left"))

    def mu(self, n: float) -> np.ndarray:
        """Direction cosines of the nodes in a medium of index n."""
        s = self.s[: self.count(n)]
        return np.sqrt(1.0 - (s / n) ** 2)

    def weights(self, n: float) -> np.ndarray:
        """Quadrature weights in mu in a medium of index n (they sum to 1)."""
        return self.etendue[: self.count(n)] / (self.mu(n) * n**2)


def make_nodes(indices, per_interval) -> Nodes:
    """Nodes for media of refractive ``indices`` (the first is the medium above), with
    ``per_interval`` nodes between consecutive distinct indices (module doc): a count, or
    (count where light can leave into the medium above, count where it is trapped)."""
    leave, trapped = (per_interval if isinstance(per_interval, tuple)
                      else (per_interval, per_interval))
    breaks = sorted({0.0, *map(float, indices)})
    s_all, e_all = [], []
    for i, (lo, hi) in enumerate(itertools.pairwise(breaks)):
        count = leave if hi <= float(indices[0]) else trapped
        x, w = _radau(count + 1) if i == 0 else _gauss(count)
        # every interval ends at an index; its owner is the medium of that index
        mu_lo = np.sqrt(1 - (lo / hi) ** 2)
        mu = x * mu_lo
        s_all.append(hi * np.sqrt(np.clip(1 - mu**2, 0, None)))
        e_all.append(w * mu_lo * mu * hi**2)
    s, e = np.concatenate(s_all), np.concatenate(e_all)
    order = np.argsort(s, kind="stable")
    return Nodes(s=s[order], etendue=e[order])


def cone_fraction(cone_deg) -> float:
    """The Lambertian fraction of the detector cone (lo, hi) [deg], sin²(hi) − sin²(lo):
    the core's (instrument::cone_fraction), so the solver and the walks read one formula."""
    lo, hi = (float(a) for a in cone_deg)
    return _core.cone_fraction(lo, hi)


def cone_weights(mu: np.ndarray, mu_lo: float, mu_hi: float) -> np.ndarray:
    """Weights c with sum_j c_j L_j = the flux into the cone mu_lo..mu_hi of a radiance L
    given at the nodes ``mu`` of the medium above: L interpolated through the oblique nodes
    (the normal node also holds the beam's specular reflections, a delta)."""
    x, w = np.polynomial.legendre.leggauss(32)
    pts = mu_lo + (x + 1) / 2 * (mu_hi - mu_lo)
    basis = interpolate.polynomial(mu[1:], pts)  # (points, nodes)
    return 2 * np.pi * np.concatenate([[0.0], (w * (mu_hi - mu_lo) / 2 * pts) @ basis])
