"""The response of a plane stack (layers between the medium above and the medium below) at
each spatial frequency: what the instrument's readings need, per band."""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from dentalux.reading.layered import operators as ops
from dentalux.reading.layered import single
from dentalux.reading.layered.quadrature import cone_fraction, cone_weights, make_nodes

#: quadrature nodes between consecutive refractive indices: 8 where light can leave into the
#: medium above (what the detector sees), 6 where it is trapped by total internal reflection
#: (fewer there, 5, read the 16 test windows less well; the first interval adds one node at
#: normal incidence)
NODES_PER_INTERVAL = (8, 6)
#: Legendre moments kept before the delta-M truncation. With the single-scattering
#: correction (single.py) 16 moments read the detector cone within 0.1 % at k = 0; more
#: moments than the nodes resolve (about 2 per node and interval) make the kernels ring
#: (measured: docs/notes/2026-12-07-layered-solver.md)
ORDER = 16
#: spatial frequencies solved [1/mm]; between them the response is interpolated (window.py).
#: Against a reference with every midpoint added (benchmarks/layered_settings.py) these 12
#: read as closely as the 14 used before (2.7, 4, 6, 14, 21 where 3, 5, 16 are), for 18 %
#: less CPU; 11 spread evenly in log k read up to 0.2 % off
K_NODES = (0.0, 0.1, 0.25, 0.5, 0.8, 1.2, 1.8, 3.0, 5.0, 9.0, 16.0, 32.0)
#: azimuthal modes by spatial frequency: (k up to [1/mm], modes). The lateral term couples
#: the modes in proportion to k / mu_t; where k is large the response is small and needs
#: fewer of them again. The truncation error alternates in sign between odd and even counts:
#: against 4 more modes everywhere (benchmarks/layered_settings.py), 5 modes at 1.8-9 /mm
#: read within 0.06 % where 6 read within 0.53 %, at 25 % less CPU
MODES_BY_K = ((0.0, 1), (0.3, 3), (1.5, 4), (12.0, 5), (np.inf, 4))
#: the modes for a window that weighs little where MODES_BY_K takes 5 (window.modes_by_k):
#: 4 there. Four modes leave up to 1.8 % of the k = 0 response at 1.8-9 /mm where five
#: leave 0.7 % (against four more modes: enamel, dentin and their stack, 400-700 nm)
MODES_BY_K_LIGHT = ((0.0, 1), (0.3, 3), (np.inf, 4))

#: whether the radiance in a detector cone gets the single-scattering correction (single.py)
SINGLE_SCATTER = True

#: the solver's accuracy, relative to a reading: its discretisation against a converged
#: solution (more nodes, four more modes, more spatial frequencies) is at most 0.1 % on
#: discs (benchmarks/layered_settings.py) and was 0.4 % on a fibre probe's ring, and it
#: agreed with 2 M-photon slab walks within their noise (0.1-0.3 %) on 16 cases
#: (docs/notes/2026-12-07-layered-solver.md)
ACCURACY = 0.005

FIELDS = ("r_cone", "r_all", "into_backing", "q", "e_cone", "e_all")


@dataclass
class Response:
    """Per band and spatial frequency (bands, k): the beam's reflectance into the detector
    cone (over the cone's Lambertian fraction; the hemisphere without a cone) and over the
    hemisphere, its flux into the medium below, and a unit Lambertian exitance from below
    (the backing's light): returned to it (q) and leaving into the cone (e_cone, likewise)
    and the hemisphere (e_all)."""

    k: np.ndarray
    r_cone: np.ndarray
    r_all: np.ndarray
    into_backing: np.ndarray
    q: np.ndarray
    e_cone: np.ndarray
    e_all: np.ndarray


def _optics(band_stacks, index: int, order: int):
    layers = [stack[index] for stack in band_stacks]
    mua = np.array([lay.mua for lay in layers], float)
    mus = np.array([lay.mus for lay in layers], float)
    chi = np.stack([ops.legendre_moments(lay.g, lay.fd, lay.lobes, order) for lay in layers])
    return mua, mus, chi


@lru_cache(maxsize=16)
def _frame(indices: tuple, per_interval, modes: int, cone_deg) -> tuple:
    """What :func:`response` needs of the refractive indices alone (medium above, layers,
    medium below), the same for every chunk of bands: the nodes, the interfaces top to
    bottom, and the weights of the flux into the cone and into the hemispheres above and
    below (up to about 0.5 MB). Read-only: every chunk and thread shares them."""
    nodes = make_nodes(list(indices), per_interval)
    faces = tuple(ops.interface(n1, n2, nodes, modes) for n1, n2 in itertools.pairwise(indices))
    n_above, n_below = indices[0], indices[-1]
    flux_top = 2 * np.pi * nodes.weights(n_above) * nodes.mu(n_above)
    flux_bot = 2 * np.pi * nodes.weights(n_below) * nodes.mu(n_below)
    if cone_deg is None:
        cone = flux_top
    else:
        lo, hi = np.radians(cone_deg)
        cone = cone_weights(nodes.mu(n_above), np.cos(hi), np.cos(lo))
        cone = cone / cone_fraction(cone_deg)
    for a in (flux_top, flux_bot, cone, *(m for f in faces for m in vars(f).values())):
        a.flags.writeable = False
    return nodes, faces, flux_top, flux_bot, cone


def response(band_stacks, ks, n_above: float, n_below: float, cone_deg, modes: int,
             per_interval=NODES_PER_INTERVAL, order: int = ORDER) -> Response:
    """Solve one stack per band (slab ``Layer`` lists, top first, with the same indices and
    thicknesses in every band) at the spatial frequencies ``ks``, with ``modes`` modes."""
    first = band_stacks[0]
    indices = (float(n_above), *(float(lay.n) for lay in first), float(n_below))
    nodes, faces, flux_top, flux_bot, cone = _frame(
        indices, per_interval, int(modes), None if cone_deg is None else tuple(cone_deg))
    total = faces[0]
    ks = np.asarray(ks, float)
    prefix: tuple = ("stack", nodes.s.tobytes(), ks.tobytes(), int(modes), float(n_above))
    optics = [_optics(band_stacks, i, order) for i in range(len(first))]
    # every layer but the last onto the top interface, kept for specimens that share that
    # much of the stack (ops.reuse); the last layer with the bottom interface, kept alike
    for i, lay in enumerate(first[:-1]):
        n_next = first[i + 1].n
        prefix += (tuple(o.tobytes() for o in optics[i]), float(lay.thickness), float(lay.n),
                   float(n_next))

        def extend(above=total, lay=lay, optics=optics[i], face=faces[i + 1]):
            r, t = ops.layer(optics, lay.thickness, lay.n, nodes, ks, modes)
            return ops.add(ops.add(above, ops.Element(r, t, r, t)), face)

        total = ops.kept(prefix, extend)
    last = first[-1]

    def closing():
        r, t = ops.layer(optics[-1], last.thickness, last.n, nodes, ks, modes)
        return ops.add(ops.Element(r, t, r, t), faces[-1])

    bottom = ops.kept(("last", nodes.s.tobytes(), ks.tobytes(), int(modes),
                       tuple(o.tobytes() for o in optics[-1]), float(last.thickness),
                       float(last.n), float(n_below)), closing)
    top, bot = nodes.count(n_above), nodes.count(n_below)
    # the beam in the normal node (node 0) from above, a Lambertian exitance from below
    rd, td, ru, tu = ops.join(total, bottom, 0, bot)
    up = rd[..., :top] / flux_top[0]                  # unit irradiance in the normal node
    down = td[..., :bot] / flux_top[0]
    back = ru[..., :bot] / np.pi                      # unit Lambertian exitance below
    leave = tu[..., :top] / np.pi
    return Response(k=np.asarray(ks, float), r_cone=up @ cone, r_all=up @ flux_top,
                    into_backing=down @ flux_bot, q=back @ flux_bot, e_cone=leave @ cone,
                    e_all=leave @ flux_top)


def modes_for(k: float, schedule=MODES_BY_K) -> int:
    """Azimuthal modes solved at spatial frequency k (``schedule``: as MODES_BY_K)."""
    return next(m for k_max, m in schedule if k <= k_max)


class Stopped(Exception):
    """Raised by :func:`responses` when its ``stop()`` says so (Ctrl-C elsewhere)."""


def responses(band_stacks, n_above: float, n_below: float, cone_deg, ks=K_NODES,
              stop=None, modes_by_k=MODES_BY_K, single_scatter: bool = SINGLE_SCATTER,
              **settings) -> Response:
    """:func:`response` at every spatial frequency of ``ks``, each with the modes
    ``modes_by_k`` gives it, solved in groups of equal modes; ``stop()``, asked before each
    group, ends it early (:class:`Stopped`); ``single_scatter``: the cone's correction."""
    return responses_many([band_stacks], n_above, n_below, cone_deg, ks, stop, modes_by_k,
                          single_scatter, **settings)[0]


def responses_many(specimens, n_above: float, n_below: float, cone_deg, ks=K_NODES,
                   stop=None, modes_by_k=MODES_BY_K, single_scatter: bool = SINGLE_SCATTER,
                   **settings) -> list[Response]:
    """:func:`responses` of several specimens (each one stack per band, the same bands): one
    group of modes at a time for every specimen, so that the operators a group keeps
    (ops.reuse: its layers per thickness, its partial stacks) serve every specimen that
    shares them before the next group's take their place."""
    ks = np.asarray(ks, float)
    groups: dict[int, list[int]] = {}
    for i, k in enumerate(ks):
        groups.setdefault(modes_for(k, modes_by_k), []).append(i)
    outs = [{f: np.zeros((len(bs), len(ks))) for f in FIELDS} for bs in specimens]
    for modes, idx in groups.items():
        for bs, out in zip(specimens, outs, strict=True):
            if stop is not None and stop():
                raise Stopped
            res = response(bs, ks[idx], n_above, n_below, cone_deg, modes, **settings)
            for f in FIELDS:
                out[f][:, idx] = getattr(res, f)
    if cone_deg is not None and single_scatter:
        for bs, out in zip(specimens, outs, strict=True):
            out["r_cone"] += single.correction(bs, ks, n_above, cone_deg,
                                               settings.get("order", ORDER))
    return [Response(k=ks, **out) for out in outs]


def local_parts(band_stacks, n_above: float, n_below: float, order: int = ORDER
                ) -> Response:
    """The parts of the beam's response that stay where it enters (constant in k): its
    specular reflections at the interfaces and its transmission without scattering (outside
    the delta-M peak), from the stack with its scattering turned into extinction."""
    clear = []
    for stack in band_stacks:
        row = []
        for lay in stack:
            f = ops.legendre_moments(lay.g, lay.fd, lay.lobes, order)[order]
            row.append(type(lay)(mua=lay.mua + lay.mus * (1 - f), mus=0.0, g=0.0, n=lay.n,
                                 thickness=lay.thickness))
        clear.append(row)
    return response(clear, [0.0], n_above, n_below, None, 1, order=order)
