"""Reflection and transmission operators of a layer and of an interface, at one spatial
frequency k, for radiance vectors over (azimuthal mode, direction node), mode-major.

A lateral modulation exp(i k x) adds i k sin(theta) cos(phi) to the extinction. Azimuth is
expanded in cos(m phi) about the direction of k; the lateral term couples m to m +- 1, and
with the modes scaled by i^m it is real, so every operator is real. The phase function
enters by its Legendre moments, truncated by delta-M (Wiscombe 1977): the moments beyond
``order`` are put into a forward peak that leaves the light's direction unchanged.

A homogeneous layer is solved from the eigenvectors of its generator. With L+ and L- the
down- and up-going radiance, A the extinction, lateral term and in-scattering within a
hemisphere (per unit mu) and B the scattering between hemispheres,
S = L+ + L- and D = L+ - L- obey S'' = (A + B)(A - B) S; its modes exp(-kappa z) and
exp(kappa (z - d)) (Re kappa >= 0, so nothing overflows) meet L+(0) = x and L-(d) = 0.
"""

from __future__ import annotations

import threading
from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from dentalux import _core
from dentalux.reading.layered import special
from dentalux.reading.layered.quadrature import Nodes


def legendre_moments(g: float, fd: float, lobes, count: int) -> np.ndarray:
    """Legendre moments chi_0..chi_count of the phase function: Henyey-Greenstein's are
    g^l, so HG(g) mixed with an isotropic fraction fd (eq. 10) has (1 - fd) g^l (l > 0) and a
    sum of lobes (eq. 8) the weighted sum."""
    ls = np.arange(count + 1)
    if lobes:
        chi = sum(w * float(gl) ** ls for w, gl in lobes)
    else:
        chi = (1 - fd) * float(g) ** ls
    chi = np.array(chi, dtype=float)
    chi[0] = 1.0
    return chi


@lru_cache(maxsize=64)
def _associated(mu_key: tuple, modes: int, order: int) -> np.ndarray:
    """sqrt((l-m)!/(l+m)!) P_l^m(x) at x = (mu, -mu): (modes, order, 2N)."""
    mu = np.asarray(mu_key)
    return special.associated_legendre(modes, order, np.concatenate([mu, -mu]))


def kernels(chi_star: np.ndarray, mu: np.ndarray, w: np.ndarray, modes: int) -> np.ndarray:
    """Scattering kernels per band and mode, (bands, modes, 2N, 2N) over directions (down
    nodes, then up nodes): entry [i, j] is the radiance scattered into direction i per unit
    radiance in direction j and unit scattering, quadrature weight of j included. The
    addition theorem gives mode m: sum_l (2l + 1)/2 chi*_l (l-m)!/(l+m)! P_l^m P_l^m."""
    order = chi_star.shape[1]
    p = _associated(tuple(np.round(mu, 15)), modes, order)
    ww = np.concatenate([w, w])
    coef = (2 * np.arange(order) + 1) / 2 * chi_star
    k = np.einsum("bl,mli,mlj->bmij", coef, p, p) * ww
    # every direction's scattered light integrates to one (the quadrature's mode-0 error)
    k[:, 0] /= (ww[:, None] * k[:, 0]).sum(axis=1, keepdims=True) / ww
    return k


def coupling(modes: int) -> np.ndarray:
    """The lateral term's mode coupling in the modes scaled by i^m: cos(phi) cos(m phi) =
    (cos((m - 1) phi) + cos((m + 1) phi)) / 2, the part into m - 1 with sign -1."""
    c = np.zeros((modes, modes))
    for m in range(modes):
        if m + 1 < modes:
            c[m + 1, m] = 1.0 if m == 0 else 0.5
        if m >= 1:
            c[m - 1, m] = -0.5
    return c


#: the smallest extinction a layer is solved with [1/mm] (see _eigen): over a 10 mm path
#: it changes a reading by 1e-5 of itself
MIN_EXTINCTION = 1e-6

# operators kept while reading several specimens that share layers (:func:`reuse`): a
# design's nodes repeat each material and each thickness. Per thread: bands are solved in
# chunks on several threads, each with its own. A layer's eigen-decomposition (per material:
# the costly part) is kept for the whole block; of the rest (per thickness and per stack) at
# most KEEP (up to about 15 MB each for a chunk of 4 bands), the least recently used dropped
# first, so that a design's many thicknesses do not push out its few materials
_LOCAL = threading.local()
KEEP = 32
# eigen-decompositions kept across solves and threads inside :func:`share` (a design's
# table, its verifications and its evaluations decompose each material once), up to
# SHARE_BYTES, the oldest dropped first
_SHARED: dict | None = None
_SHARED_LOCK = threading.Lock()
SHARE_BYTES = 2 * 1024**3


@contextmanager
def reuse():
    """Within this block (on this thread) a layer's eigenvectors (per material) and its
    reflection and transmission (per material and thickness) are computed once and kept;
    they are dropped on leaving it (they take tens of MB each)."""
    outer = getattr(_LOCAL, "kept", None)
    if outer is None:
        _LOCAL.kept, _LOCAL.eigen = {}, {}
    try:
        yield
    finally:
        if outer is None:
            _LOCAL.kept = _LOCAL.eigen = None


@contextmanager
def share():
    """Within this block the layers' eigen-decompositions are kept for every solve on every
    thread, not only within one :func:`reuse` block; dropped on leaving the outermost."""
    global _SHARED
    outer = _SHARED
    if outer is None:
        _SHARED = {}
    try:
        yield
    finally:
        if outer is None:
            _SHARED = None


def kept(key, make):
    """``make()``, or its kept value under ``key`` inside :func:`reuse` (the KEEP most
    recently used are kept)."""
    store = getattr(_LOCAL, "kept", None)
    if store is None:
        return make()
    value = store.pop(key) if key in store else make()
    store[key] = value
    while len(store) > KEEP:
        store.pop(next(iter(store)))
    return value


def _kept_eigen(key, make):
    """``make()`` (an eigen-decomposition), kept inside :func:`share` or :func:`reuse`."""
    shared = _SHARED
    if shared is not None:
        with _SHARED_LOCK:
            value = shared.get(key)
        if value is None:
            value = make()
            with _SHARED_LOCK:
                shared[key] = value
                total = sum(sum(a.nbytes for a in v) for v in shared.values())
                while len(shared) > 1 and total > SHARE_BYTES:
                    total -= sum(a.nbytes for a in shared.pop(next(iter(shared))))
        return value
    store = getattr(_LOCAL, "eigen", None)
    if store is None:
        return make()
    if key not in store:
        store[key] = make()
    return store[key]


def layer(optics, thickness: float, n: float, nodes: Nodes, ks, modes: int
          ) -> tuple[np.ndarray, np.ndarray]:
    """Reflection and transmission of a homogeneous layer (the same from above and below)
    for every band of ``optics`` = (mua, mus, chi) and every k in ``ks``:
    (bands, len(ks), M, M) each, M = modes x nodes in the layer."""
    mua, mus, chi = optics
    ks = np.asarray(ks, float)
    key = (mua.tobytes(), mus.tobytes(), chi.tobytes(), float(n), nodes.s.tobytes(),
           ks.tobytes(), int(modes))
    eig = _kept_eigen(key, lambda: _eigen(optics, n, nodes, ks, modes))
    return kept(key + (float(thickness),), lambda: _slab(eig, thickness))


def _eigen(optics, n: float, nodes: Nodes, ks: np.ndarray, modes: int):
    """The thickness-free part of :func:`layer`: the modes' eigenvectors and constants."""
    mua, mus, chi = optics
    order = chi.shape[1] - 1
    mu, w = nodes.mu(n), nodes.weights(n)
    nn = len(mu)
    f = chi[:, order]
    kern = kernels((chi[:, :order] - f[:, None]) / (1 - f[:, None]), mu, w, modes)
    mus_s = mus * (1 - f)
    # a clear layer (no extinction) has modes on the imaginary axis, whose sign the
    # eigenvalue's square root cannot tell: a floor far below any reading's resolution
    mut = np.maximum(mua + mus_s, MIN_EXTINCTION)
    size = modes * nn
    bands = len(mua)
    within = np.zeros((bands, size, size))
    between = np.zeros((bands, size, size))
    for m in range(modes):
        blk = slice(m * nn, (m + 1) * nn)
        within[:, blk, blk] = (mut[:, None, None] * np.eye(nn)
                               - mus_s[:, None, None] * kern[:, m, :nn, :nn]) / mu[:, None]
        between[:, blk, blk] = mus_s[:, None, None] * kern[:, m, :nn, nn:] / mu[:, None]
    lateral = np.kron(coupling(modes), np.diag(nodes.s[:nn] / n / mu))
    a = within[:, None] + np.asarray(ks, float)[None, :, None, None] * lateral
    b = between[:, None]
    apb = a + b
    lam, v = np.linalg.eig(apb @ (a - b))
    kappa = np.sqrt(lam.astype(complex))
    kappa = np.where(kappa.real < 0, -kappa, kappa)
    inv_apb = np.linalg.inv(apb)
    partner = _partners(lam)
    if partner is None:  # a real negative eigenvalue: its mode has no real form
        # (A + B) is real: one real inverse for the real and imaginary parts of v kappa
        rhs = v * kappa[..., None, :]
        p = v + (inv_apb @ rhs.real + 1j * (inv_apb @ rhs.imag))
    else:
        # a conjugate pair (v, conj v) spans the real pair (Re v, Im v): the same modes in
        # real arithmetic, where diag(f(kappa)) becomes 2 x 2 blocks (_times)
        v = np.where(np.imag(lam)[..., None, :] < 0, -v.imag, v.real)
        p = v + inv_apb @ _times(v, kappa, partner, -1)
    q = 2 * v - p
    pinv = np.linalg.inv(p)
    return p, pinv, pinv @ q, kappa, partner


def _partners(lam: np.ndarray) -> np.ndarray | None:
    """For the eigenvalues ``lam`` (..., M) from LAPACK (a conjugate pair in consecutive
    places, the positive imaginary part first), each one's partner: j + 1 for the first of
    a pair, j - 1 for the second, j for a real one; None where an eigenvalue is real and
    negative (its kappa is imaginary, so the real form does not hold)."""
    lam = np.asarray(lam)
    idx = np.broadcast_to(np.arange(lam.shape[-1]), lam.shape)
    if not np.iscomplexobj(lam):
        return None if (lam < 0).any() else idx.copy()
    up, down = lam.imag > 0, lam.imag < 0
    if ((lam.imag == 0) & (lam.real < 0)).any():
        return None
    if not (np.array_equal(up[..., :-1], down[..., 1:]) and not up[..., -1].any()
            and not down[..., 0].any()):
        raise RuntimeError("eigenvalues not in conjugate pairs")
    return idx + up - down


def _times(m: np.ndarray, f: np.ndarray, partner: np.ndarray | None, axis: int
           ) -> np.ndarray:
    """``m`` diag(f) (axis -1) or diag(f) ``m`` (axis -2) in the basis of :func:`_eigen`.
    For a pair (x, y) = (Re v, Im v) with f = a + ib at v, diag(f, conj f) is the real block
    [[a, b], [-b, a]] from the right: column x -> a x - b y, y -> b x + a y; from the left,
    row x -> a x + b y, y -> -b x + a y. With f at each column's own eigenvalue (conj f at
    the second), both are m Re f -+ (m with partners swapped) Im f. ``partner`` None: the
    complex basis, f a plain diagonal."""
    if partner is None:
        return m * (f[..., None, :] if axis == -1 else f[..., :, None])
    if axis == -1:
        swapped = np.take_along_axis(m, partner[..., None, :], axis=-1)
        return m * f.real[..., None, :] - swapped * f.imag[..., None, :]
    swapped = np.take_along_axis(m, partner[..., :, None], axis=-2)
    return m * f.real[..., :, None] + swapped * f.imag[..., :, None]


def _slab(eig, thickness: float) -> tuple[np.ndarray, np.ndarray]:
    """A layer's reflection and transmission at ``thickness`` from :func:`_eigen`'s parts."""
    p, pinv, x, kappa, partner = eig
    e = np.exp(-kappa * thickness)
    xe = _times(x, e, partner, -1)
    eye = np.eye(x.shape[-1])
    inner = np.linalg.solve(eye - xe @ xe, pinv)
    r = p @ ((x - _times(xe, e, partner, -2)) @ inner)
    t = p @ ((_times(np.broadcast_to(eye, x.shape), e, partner, -1) - x @ xe) @ inner)
    return r.real, t.real


@dataclass
class Element:
    """A piece of the stack for radiance vectors: reflection from above ``rd``, transmission
    downwards ``td``, reflection from below ``ru``, transmission upwards ``tu``."""

    rd: np.ndarray
    td: np.ndarray
    ru: np.ndarray
    tu: np.ndarray


def interface(n1: float, n2: float, nodes: Nodes, modes: int) -> Element:
    """The plane Fresnel interface from index n1 (above) to n2 (below), node to node and
    mode by mode; a node that one side lacks is totally reflected on the other."""
    c1, c2 = nodes.count(n1), nodes.count(n2)
    common = min(c1, c2)
    r1, r2 = np.ones(c1), np.ones(c2)
    r1[:common] = _core.fresnel_reflectance(nodes.mu(n1)[:common].tolist(), n1, n2)
    r2[:common] = _core.fresnel_reflectance(nodes.mu(n2)[:common].tolist(), n2, n1)
    td, tu = np.zeros((c2, c1)), np.zeros((c1, c2))
    i = np.arange(common)
    td[i, i] = (1 - r1[:common]) * (n2 / n1) ** 2
    tu[i, i] = (1 - r2[:common]) * (n1 / n2) ** 2
    eye = np.eye(modes)
    return Element(*(np.kron(eye, x) for x in (np.diag(r1), td, np.diag(r2), tu)))


def add(a: Element, b: Element) -> Element:
    """``a`` above ``b``, with every order of reflection between them."""
    eye = np.eye(a.ru.shape[-1])
    down = np.linalg.solve(eye - a.ru @ b.rd, a.td)  # every order of a's light into b
    up = np.linalg.solve(eye - b.rd @ a.ru, b.tu)    # and of b's light into a
    return Element(rd=a.rd + a.tu @ (b.rd @ down), td=b.td @ down,
                   ru=b.ru + b.td @ (a.ru @ up), tu=a.tu @ up)


def join(a: Element, b: Element, beam: int, below: int) -> tuple[np.ndarray, ...]:
    """The parts of ``a`` above ``b`` that a reading needs, without forming the whole sum:
    for a unit beam in node ``beam`` from above, the reflected and the transmitted radiance
    vectors, and for unit radiance in each of the first ``below`` nodes from below, the sum
    of the reflected and of the transmitted vectors. One system (I - a.ru b.rd) serves both
    directions through (I - B A)^-1 = I + B (I - A B)^-1 A; :func:`add` would solve two, with
    a whole matrix on the right of each."""
    eye = np.eye(a.ru.shape[-1])
    w = b.tu[..., :below].sum(-1)                       # b's light from below, into a
    rhs = np.stack(np.broadcast_arrays(a.td[..., beam], _apply(a.ru, w)), axis=-1)
    sol = np.linalg.solve(eye - a.ru @ b.rd, rhs)
    x = sol[..., 0]                                     # every order of a's beam into b
    y = w + _apply(b.rd, sol[..., 1])                   # every order of b's light into a
    return (a.rd[..., beam] + _apply(a.tu, _apply(b.rd, x)), _apply(b.td, x),
            b.ru[..., :below].sum(-1) + _apply(b.td, _apply(a.ru, y)), _apply(a.tu, y))


def _apply(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Matrices times vectors over the leading axes."""
    return (m @ v[..., None])[..., 0]
