"""From the stack's response per spatial frequency to what an instrument's window reads.

For a lit region of unit power S and a window W on a laterally infinite specimen, the power
read is the overlap integral of S, W and the specimen's point response; by Parseval it is
(1/2 pi) int k dk S(k) W(k) F(k) with S, W the Hankel transforms of the (concentric) lit and
viewed discs or rings and F the response at spatial frequency k. F is smooth and solved at a
few k (stack.K_NODES); the kernel S W oscillates and is integrated on a fine grid.

Regions that are not concentric (a fibre probe's separate fibres, :mod:`dentalux.fibres`)
are a sum over pairs of a lit disc and a read disc: shifting the read disc by d multiplies
the cross-spectrum by exp(i k.d), whose average over the directions of k is J0(k d), so a
pair reads with the kernel S W J0(k d), weighted by its source's share of the power. A pair
is ((inner, outer radius) lit, (inner, outer) read, d, weight); concentric regions are the
one pair (lit, view, 0, 1).

The Lambertian backing is local (zero gap), so it multiplies at each k: the reading over a
backing R_b is V_0 + sum_{j >= 1} V_j R_b^j with V_0 the bare stack and V_j the integral of
E e q^(j-1) (E: the beam's flux into the backing, q: the backing's light returned to it,
e: the backing's light leaving in the window), the order sums that the slab walk tallies.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from dentalux.reading.layered import interpolate
from dentalux.reading.layered.special import j0, j1
from dentalux.reading.layered.stack import (
    K_NODES,
    MODES_BY_K,
    MODES_BY_K_LIGHT,
    Response,
    modes_for,
)

# the k integral: the kernel oscillates with period 2 pi / (largest radius, plus the pair's
# distance where the regions are not concentric) and falls as
# k^-2; it is summed on a grid of FINE_PER_PERIOD points per period. Past the last solved k a
# response keeps its local part (specular reflections and the unscattered beam, constant in
# k) and its remainder falls as k^-p, p from the last two nodes within [0, 1] (1: a spreading
# response; 0: one that does not spread, such as light through a clear film on a Lambertian
# backing), summed to TAIL_FACTOR times the last node; beyond that the kernel's remaining
# mass (the exact overlap less the sums) counts with weight 1 - p, so a response constant in
# k is read with the exact overlap
FINE_PER_PERIOD = 64
TAIL_FACTOR = 8.0
#: the tail exponents tabulated; between them the tail's weight is interpolated
TAIL_EXPONENTS = np.linspace(0.0, 1.0, 5)
# the responses are splined in asinh(k / K_SCALE), which resolves their fall near k = 0
K_SCALE = 0.05
#: a window reads only the spatial frequencies its kernel weighs: the last nodes are left
#: unsolved while their weights and the tail's, together, stay within NODE_TOLERANCE of the
#: window's overlap. A response is largest at k = 0 (the point spread function is positive),
#: so a node of weight w moves the reading by at most w times the k = 0 response; against
#: every node solved this moves the presets' readings by at most 2e-4 of themselves
#: (tests/test_layered.py), far inside stack.ACCURACY
NODE_TOLERANCE = 1e-3
#: a window whose weights at the nodes where stack.MODES_BY_K_LIGHT takes fewer modes than
#: stack.MODES_BY_K (with the tail's, if the last is one) sum within FEWER_MODES_WEIGHT of
#: its overlap is solved with the lighter schedule: the modes' truncation there counts a
#: tenth at most. Against a reference with four more modes (benchmarks/layered_settings.py,
#: 11 bands) `45-0` (weight 0.05) and `d8-benchtop-mav` (0.06) then read within 0.12 % (0.10 %
#: with five modes) for a quarter less CPU; `d8-benchtop-sav` (0.13), `noncontact` (0.22)
#: and the probes (0.31; with four modes the 3 mm probe read 0.35-1.2 % off) keep five
FEWER_MODES_WEIGHT = 0.1


def disc_kernel(k, lit: tuple[float, float], view: tuple[float, float]) -> np.ndarray:
    """(1/2 pi) k S(k) W(k) for the lit ring ``lit`` = (inner, outer radius [mm]) at unit
    power and the window ring ``view``."""
    k = np.asarray(k, float)

    def disc(r):  # the Hankel transform of a disc of radius r: 2 pi r J1(k r) / k
        return 2 * np.pi * r * j1(k * r) / k if r > 0 else np.zeros_like(k)

    s = (disc(lit[1]) - disc(lit[0])) / (np.pi * (lit[1] ** 2 - lit[0] ** 2))
    return k * s * (disc(view[1]) - disc(view[0])) / (2 * np.pi)


def overlap(lit, view) -> float:
    """Fraction of the lit ring's power falling inside the window ring (concentric)."""
    lo, hi = max(lit[0], view[0]), min(lit[1], view[1])
    return 0.0 if hi <= lo else (hi**2 - lo**2) / (lit[1] ** 2 - lit[0] ** 2)


def lens(d: float, a: float, b: float) -> float:
    """Area [mm^2] shared by two discs of radii a and b whose centres are d apart."""
    if d >= a + b:
        return 0.0
    if d <= abs(a - b):
        return np.pi * min(a, b) ** 2
    ca = np.clip((d * d + a * a - b * b) / (2 * d * a), -1.0, 1.0)
    cb = np.clip((d * d + b * b - a * a) / (2 * d * b), -1.0, 1.0)
    k = (-d + a + b) * (d + a - b) * (d - a + b) * (d + a + b)
    return float(a * a * np.arccos(ca) + b * b * np.arccos(cb) - 0.5 * np.sqrt(max(k, 0.0)))


def pairs_overlap(pairs) -> float:
    """Fraction of the lit power falling inside the read regions, over every pair (a shifted
    pair's regions are discs)."""
    return sum(w * (overlap(lit, view) if d == 0
                    else lens(d, lit[1], view[1]) / (np.pi * lit[1] ** 2))
               for lit, view, d, w in pairs)


def pairs_kernel(k, pairs) -> np.ndarray:
    """(1/2 pi) k sum_pairs w S(k) W(k) J0(k d) (module doc; J0(0) = 1 exactly)."""
    k = np.asarray(k, float)
    return sum(w * (disc_kernel(k, lit, view) * j0(k * d)) for lit, view, d, w in pairs)


@lru_cache(maxsize=32)
def _weights(ks: tuple, pairs: tuple) -> tuple[np.ndarray, np.ndarray, float]:
    """Linear weights of the window's reading: (spline part per node, the last node's tail
    weight per exponent of TAIL_EXPONENTS, the overlap that the local part is read with)."""
    k_last = ks[-1]
    step = 2 * np.pi / max(max(lit[1], view[1]) + d for lit, view, d, _ in pairs) \
        / FINE_PER_PERIOD
    fine = np.arange(step / 2, k_last, step)
    far = np.arange(k_last + step / 2, TAIL_FACTOR * k_last, step)
    basis = interpolate.cubic_spline(np.arcsinh(np.asarray(ks) / K_SCALE),
                                     np.arcsinh(fine / K_SCALE))    # (fine, nodes)
    near_kernel = pairs_kernel(fine, pairs) * step
    far_kernel = pairs_kernel(far, pairs) * step
    spline = near_kernel @ basis
    over = pairs_overlap(pairs)
    beyond = over - near_kernel.sum() - far_kernel.sum()
    tails = np.array([(k_last / far) ** p @ far_kernel + (1 - p) * beyond
                      for p in TAIL_EXPONENTS])
    return spline, tails, over


@lru_cache(maxsize=32)
def nodes_for(pairs: tuple, ks: tuple = K_NODES) -> tuple:
    """The spatial frequencies of ``ks`` that the window ``pairs`` (:func:`as_pairs`) needs
    solved: all but the last nodes whose weights, with the tail's, sum within NODE_TOLERANCE
    of its overlap (none dropped where the regions do not overlap, as separate fibres)."""
    spline, tails, over = _weights(tuple(map(float, ks)), pairs)
    if over <= 0:
        return tuple(ks)
    beyond = np.cumsum(np.abs(spline)[::-1])[::-1] + np.abs(tails).max()  # from node j on
    keep = len(ks)
    while keep > 3 and beyond[keep - 1] <= NODE_TOLERANCE * over:
        keep -= 1
    return tuple(ks[:keep])


@lru_cache(maxsize=32)
def modes_by_k(pairs: tuple, ks: tuple) -> tuple:
    """The azimuthal modes' schedule for the window ``pairs`` solved at ``ks``
    (:func:`nodes_for`): stack.MODES_BY_K_LIGHT where the nodes it solves with fewer modes
    weigh within FEWER_MODES_WEIGHT of the overlap, else stack.MODES_BY_K."""
    spline, tails, over = _weights(tuple(map(float, ks)), pairs)
    fewer = np.array([modes_for(k, MODES_BY_K_LIGHT) < modes_for(k, MODES_BY_K) for k in ks])
    weight = np.abs(spline[fewer]).sum() + (np.abs(tails).max() if fewer[-1] else 0.0)
    return MODES_BY_K_LIGHT if over > 0 and weight <= FEWER_MODES_WEIGHT * over else MODES_BY_K


def tail_exponent(ks, rest: np.ndarray) -> np.ndarray:
    """How the remainder falls past the last node, k^-p with p in [0, 1] from its last two
    nodes (1 where they differ in sign or vanish)."""
    a, b = rest[..., -2], rest[..., -1]
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.log(a / b) / np.log(ks[-1] / ks[-2])
    return np.where((a * b > 0) & np.isfinite(p), np.clip(p, 0.0, 1.0), 1.0)


def as_pairs(lit, view, pairs=None) -> tuple:
    """``pairs`` as hashable floats, or the concentric lit ring and window as one pair."""
    if pairs is None:
        pairs = ((lit, view, 0.0, 1.0),)
    return tuple((tuple(map(float, li)), tuple(map(float, vi)), float(d), float(w))
                 for li, vi, d, w in pairs)


def integrate(ks, values: np.ndarray, lit, view, local=0.0, pairs=None) -> np.ndarray:
    """The window's reading of responses ``values`` (..., len(ks)) whose part ``local``
    (...) is constant in k (module doc); ``pairs`` (given: ``lit`` and ``view`` unused)
    for regions that are not concentric."""
    spline, tails, over = _weights(tuple(map(float, ks)), as_pairs(lit, view, pairs))
    local = np.asarray(local, float)
    rest = values - local[..., None]
    tail = np.interp(tail_exponent(np.asarray(ks, float), rest), TAIL_EXPONENTS, tails)
    return rest @ spline + rest[..., -1] * tail + local * over


def order_sums(res: Response, local: Response, first_surface: float, lit, view,
               max_order: int, keys: tuple[str, ...], pairs=None) -> np.ndarray:
    """The window tallies by backing order that the slab walk estimates, (bands, max_order
    + 1, keys) per unit incident power, from the stack's response ``res``, its local parts
    and its first-surface (specular) reflectance; no rim (its key is 0). ``pairs``: regions
    that are not concentric (module doc), in place of ``lit`` and ``view``."""
    pairs = as_pairs(lit, view, pairs)

    def read(values, local_part=0.0):
        return integrate(res.k, values, lit, view, local_part, pairs)

    bands = res.r_all.shape[0]
    out = np.zeros((bands, max_order + 1, len(keys)))
    col = {k: i for i, k in enumerate(keys)}
    spec = local.r_all[:, 0]
    ballistic = local.into_backing[:, 0]
    q_pow = res.q[:, None, :] ** np.arange(max_order)[None, :, None]  # (bands, j-1, k)
    both = res.into_backing[:, None, :] * q_pow
    viewed = read(res.r_all, spec)
    out[:, 0, col["viewed_reflectance"]] = viewed
    out[:, 0, col["viewed_specular"]] = first_surface * pairs_overlap(pairs)
    out[:, 0, col["viewed_cone_reflectance"]] = read(res.r_cone)
    out[:, 0, col["outside_reflectance"]] = res.r_all[:, 0] - viewed
    out[:, 0, col["viewed_transmittance"]] = read(res.into_backing, ballistic)
    up_all = both * res.e_all[:, None, :]
    viewed_j = read(up_all)
    out[:, 1:, col["viewed_reflectance"]] = viewed_j
    out[:, 1:, col["viewed_cone_reflectance"]] = read(both * res.e_cone[:, None, :])
    out[:, 1:, col["outside_reflectance"]] = up_all[..., 0] - viewed_j
    out[:, 1:, col["viewed_transmittance"]] = read(both * res.q[:, None, :])
    return out

