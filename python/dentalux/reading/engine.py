"""The reading engine: a layered specimen, an instrument and bands -> the spectra it reads.

Every command that reads a specimen (``shade``, ``design``'s nodes and verification,
``report``) calls :func:`measure`. Two geometries:

- **An instrument window** (every preset but ``infinite``): one slab walk per band with the
  lit spot, the window and a Lambertian backing inside it (:mod:`dentalux.instrument`). The
  walk tallies the window by backing order (the core's ``BackingOrders``), so the reading
  over a backing of reflectance R_b is the polynomial Σ_k V_k R_b^k, exact: the black and
  the white backing, and the transmitted light (order 0 reaching the backing inside the
  window), all come from the same photons. Their noise is shared, so most of it cancels in
  TP, TP00 and CR. With an optical contact the transmitted reading (the disc in air) is its
  own walk. Standard errors come from replicates (groups of photon batches), which carry
  every correlation.
- **``infinite``**: the laterally infinite disc on ideal backings by the adding formula
  R(R_b) = R1 + T1 R_b T2 / (1 − R_b R2), from a beam run (R1, T1) and a flipped diffuse run
  (R2, T2) per band, and a run in air for the transmitted light where the disc is in
  optical contact; independent runs, propagated by the delta method.
"""

from __future__ import annotations

import time

import numpy as np

from dentalux import _core, limits
from dentalux.progress import bar
from dentalux.reading.spectra import ReadSpectra
from dentalux.slab import Layer, parse_incidence, simulate

# the core's tallies of a window run, in its order (instrument.rs WINDOW_KEYS)
WINDOW_KEYS = tuple(_core.SLAB_WINDOW_KEYS)
# highest backing order tallied: a walk returns to the backing with probability about R_b R2
# per order (R2 the stack's diffuse reflectance from below), so 64 orders leave at most
# (0.95 x 0.95)^64 = 1.4e-3 of a white backing's multiple reflections and usually far less
# (the cut weight is tallied and reported as ``truncated``)
MAX_ORDER = 64
# survival probability after a backing reflection: the brightest backing read, kept within
# [0.5, 0.95] so that walks under a near-ideal white still end
SURVIVAL_RANGE = (0.5, 0.95)
# how the bands of an instrument window are walked (windowed): one walk per band (the
# default), or every band from shared walks with a hero band per photon. Measured on
# 7 Dec 2026 (docs/notes/2026-12-07-reading-engine.md): shared walks cost 2.2x (enamel) to
# 5.4x (the enamel/dentin stack, whose dentin g varies with the band) per photon; they read
# a* and b* 1.3-2x cheaper for the same standard error, and L* 1.7-7x dearer.
WALKS = ("per-band", "shared")


def stacks(parts, wl) -> list[list[Layer]]:
    """One stack of :class:`Layer` per band from [(material, thickness mm)], top first."""
    out = []
    for lam in wl:
        stack = []
        for m, t in parts:
            o = m.at(float(lam))
            stack.append(Layer(mua=float(o.mua), mus=float(o.mus), g=float(o.g), n=float(o.n),
                               thickness=float(t), fd=float(o.fd)))
        out.append(stack)
    return out


def _tuples(band_stacks) -> list[list[tuple]]:
    return [[layer.as_tuple(i) for i, layer in enumerate(stack)] for stack in band_stacks]


def _ordered_runs(band_stacks, inst, photons, seed, key0, n_below, estimator, threads, cb,
                  survival):
    """The core's order sums (bands, replicates, orders + 1, keys) and photons per replicate."""
    kind, deg = parse_incidence(inst.spec.incidence)
    raw = _core.slab_read_bands(
        _tuples(band_stacks), [key0 + k for k in range(len(band_stacks))], int(photons),
        int(seed), inst.window(0.0), MAX_ORDER, float(survival), n_above=1.0,
        n_below=float(n_below), incidence=kind, angle_deg=deg, estimator=estimator,
        threads=threads, progress=cb)
    return (np.asarray(raw["order_sums"]), np.asarray(raw["batch_photons"], dtype=float),
            np.asarray(raw["truncated"]))


def _shared_runs(band_stacks, inst, photons, seed, key, n_below, threads, cb, survival):
    """The same as :func:`_ordered_runs` from shared walks (a hero band per photon, the core's
    slab_spectral): ``photons`` walks per band, ``photons`` x bands in all."""
    kind, deg = parse_incidence(inst.spec.incidence)
    raw = _core.slab_read_spectral(
        _tuples(band_stacks), int(photons) * len(band_stacks), int(seed), int(key),
        inst.window(0.0), MAX_ORDER, float(survival), n_above=1.0, n_below=float(n_below),
        incidence=kind, angle_deg=deg, threads=threads, progress=cb)
    sums = np.moveaxis(np.asarray(raw["order_sums"]), 1, 0)  # (bands, R, orders, keys)
    return (sums, np.asarray(raw["replicate_photons"], dtype=float),
            np.asarray(raw["truncated"]), float(raw["concentration"]))


def can_share(band_stacks) -> bool:
    """Whether the bands can be read from shared walks: every layer with one refractive
    index in all bands (refraction and Fresnel choices are then the same in every band)."""
    first = band_stacks[0]
    return all(layer.n == ref.n and layer.thickness == ref.thickness
               for stack in band_stacks for layer, ref in zip(stack, first, strict=True))


def _polynomial(sums: np.ndarray, key: str, rb: np.ndarray) -> np.ndarray:
    """Σ_k sums[..., k, key] R_b^k per band: sums (bands, R, orders, keys) -> (R, bands)."""
    powers = rb[:, None] ** np.arange(sums.shape[2])[None, :]  # (bands, orders)
    return np.einsum("brk,bk->rb", sums[..., WINDOW_KEYS.index(key)], powers)


def windowed(band_stacks, inst, rb_black, rb_white, photons: int, seed: int,
             estimator: str = "weighted", threads=None, progress=False,
             contact: float | None = None, walks: str = "per-band") -> ReadSpectra:
    """The instrument's readings over black, over white and in transmission of one stack
    per band, tallied by backing order (module doc): ``walks`` 'per-band' (one walk per
    band) or 'shared' (every band from shared walks with a hero band per photon)."""
    wl_count = len(band_stacks)
    limits.check_slab(photons, threads, seed=seed)
    n_below = 1.0 if contact is None else float(contact)
    survival = float(np.clip(max(np.max(rb_white), np.max(rb_black)), *SURVIVAL_RANGE))
    runs = 1 if contact is None else 2
    start_cpu, start = time.process_time(), time.perf_counter()
    if walks not in WALKS:
        raise ValueError(f"walks = {walks!r}: allowed {', '.join(WALKS)}")
    shared = walks == "shared"
    if shared and not can_share(band_stacks):
        raise ValueError("walks = 'shared': a layer's refractive index differs between bands; "
                         "use walks = 'per-band'")
    extra = {}
    with bar(wl_count * int(photons) * runs, "photons", progress) as cb:
        second = (lambda done: cb(wl_count * int(photons) + done)) if cb else None
        t_key = int(_core.TRANSMITTED_RUN_KEY)
        if shared:
            sums, n_rep, truncated, extra["concentration"] = _shared_runs(
                band_stacks, inst, photons, seed, 0, n_below, threads, cb, survival)
            if contact is not None:
                t_sums = _shared_runs(band_stacks, inst, photons, seed, t_key, 1.0, threads,
                                      second, survival)[0]
        else:
            sums, n_rep, truncated = _ordered_runs(band_stacks, inst, photons, seed, 0,
                                                   n_below, estimator, threads, cb, survival)
            if contact is not None:
                t_sums = _ordered_runs(band_stacks, inst, photons, seed, t_key, 1.0,
                                       estimator, threads, second, survival)[0]
        if contact is None:
            t_sums = sums
    spec = inst.spec
    read_key = "viewed_cone_reflectance" if spec.cone_deg else "viewed_reflectance"
    f = inst.white_fraction()

    def reading(rb):
        v = _polynomial(sums, read_key, rb)
        if spec.cone_deg is None and spec.specular == "excluded":
            v = v - _polynomial(sums, "viewed_specular", rb)
        return v / f

    zero = np.zeros(wl_count)
    per_rep = np.stack([reading(rb_black), reading(rb_white),
                        _polynomial(t_sums, "viewed_transmittance", zero) / f], axis=1)
    loss = np.stack([_polynomial(sums, "outside_reflectance", rb)
                     + _polynomial(sums, "rim_loss", rb) for rb in (rb_black, rb_white)], axis=1)
    # replicate estimates are sums over their photons: means per replicate, and the overall
    # mean weighted by photons
    weights = n_rep / n_rep.sum()
    reps = per_rep / n_rep[:, None, None]
    values = np.tensordot(weights, reps, axes=([0], [0]))
    r = len(weights)
    var = np.tensordot(weights**2, (reps - values) ** 2, axes=([0], [0])) * r / max(r - 1, 1)
    edge = np.tensordot(weights, loss / n_rep[:, None, None], axes=([0], [0]))
    return ReadSpectra(
        wavelengths_nm=np.zeros(0), values=values, stderr=np.sqrt(var), edge_loss=edge,
        photons=int(photons) * wl_count * runs,
        cpu_seconds=time.process_time() - start_cpu,
        method="shared-walks" if shared else "backing-orders",
        replicates=reps, replicate_weights=weights,
        extra={"seconds": time.perf_counter() - start, "runs": runs,
               "truncated_max": float(np.max(truncated)), "survival": survival, **extra})


# the adding formula's per-band inputs, in the order of ReadSpectra.inputs (the fifth input
# is the transmitted reading)
ADDING_INPUTS = ("r1", "t1", "r2", "t2")


def over_backing(r1, t1, r2, t2, rb):
    """Reflectance of a laterally infinite disc on a Lambertian backing rb (adding)."""
    return r1 + t1 * rb * t2 / (1.0 - rb * r2)


def infinite(band_stacks, rb_black, rb_white, photons: int, seed: int,
             estimator: str = "weighted", threads=None, progress=False,
             contact: float | None = None) -> ReadSpectra:
    """The ``infinite`` geometry's readings by the adding formula (module doc)."""
    n_below = 1.0 if contact is None else float(contact)
    runs = 2 if contact is None else 3
    wl_count = len(band_stacks)
    vals = np.zeros((5, wl_count))
    errs = np.zeros((5, wl_count))
    start_cpu, start = time.process_time(), time.perf_counter()
    diffuse_key = int(_core.DIFFUSE_RUN_KEY)
    transmitted_key = int(_core.TRANSMITTED_RUN_KEY)
    with bar(wl_count * runs, "bands", progress) as cb:
        for k, stack in enumerate(band_stacks):
            common = dict(n_photons=int(photons), estimator=estimator, threads=threads,
                          seed=seed)
            a = simulate(stack, band=k, n_above=1.0, n_below=n_below, **common)
            b = simulate(stack[::-1], band=diffuse_key + k, n_above=n_below, n_below=1.0,
                         incidence="diffuse", **common)
            c = a if contact is None else simulate(stack, band=transmitted_key + k, **common)
            for i, (res, key) in enumerate(((a, "total_reflectance"),
                                            (a, "total_transmittance"),
                                            (b, "total_reflectance"),
                                            (b, "total_transmittance"),
                                            (c, "total_transmittance"))):
                vals[i, k] = getattr(res, key)
                errs[i, k] = res.stderr[key]
            if cb:
                cb((k + 1) * runs)

    def combine(batch):  # (..., 5, bands) -> (..., 3, bands)
        r1, t1, r2, t2, tt = (batch[..., i, :] for i in range(5))
        return np.stack([over_backing(r1, t1, r2, t2, rb_black),
                         over_backing(r1, t1, r2, t2, rb_white), tt], axis=-2)

    values = combine(vals)
    # marginal errors of each channel (for the spectra's own display)
    out = ReadSpectra(
        wavelengths_nm=np.zeros(0), values=values, stderr=np.zeros_like(values),
        edge_loss=np.zeros((2, wl_count)), photons=int(photons) * runs * wl_count,
        cpu_seconds=0.0, method="adding", inputs=vals, inputs_stderr=errs, combine=combine,
        extra={"runs": runs, **{k: vals[i] for i, k in enumerate(ADDING_INPUTS)},
               **{f"{k}_stderr": errs[i] for i, k in enumerate(ADDING_INPUTS)}})
    _, per_channel = out.propagate(lambda b: {"x": b.reshape(b.shape[0], -1)})
    out.stderr = per_channel["x"].reshape(values.shape)
    out.cpu_seconds = time.process_time() - start_cpu
    out.extra["seconds"] = time.perf_counter() - start
    return out


def measure(band_stacks, wl, inst, rb_black, rb_white, photons: int, seed: int,
            estimator: str = "weighted", threads=None, progress=False,
            walks: str = "per-band") -> ReadSpectra:
    """The readings of one stack per band (``band_stacks``, top layer first) at the bands
    ``wl`` [nm] through ``inst`` with backing reflectances ``rb_black``, ``rb_white`` per
    band (module doc). ``walks``: 'per-band' or 'shared' (instrument windows only)."""
    if walks not in WALKS:
        raise ValueError(f"walks = {walks!r}: allowed {', '.join(WALKS)}")
    contact = inst.contact_index
    if inst.is_infinite:
        out = infinite(band_stacks, rb_black, rb_white, photons, seed, estimator, threads,
                       progress, contact)
    else:
        out = windowed(band_stacks, inst, rb_black, rb_white, photons, seed, estimator,
                       threads, progress, contact, walks)
    out.wavelengths_nm = np.asarray(wl, dtype=float)
    return out
