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

import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager

import numpy as np
from threadpoolctl import threadpool_limits

from dentalux import _core, limits
from dentalux.progress import bar
from dentalux.reading.layered.quadrature import cone_fraction
from dentalux.reading.spectra import ReadSpectra, RimBound, replicate_variance, with_bounds
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
#: how a reading is computed: 'monte-carlo' (the slab walks above), 'layered' (the
#: deterministic solver of dentalux.reading.layered, with a Monte Carlo walk for what the
#: specimen's rim takes), or 'auto' (layered where it holds, else monte-carlo)
SOLVERS = ("monte-carlo", "layered", "auto")
#: the solver of every reading unless one is named: the layered solver wherever the beam is
#: along the normal or within MAX_TILT_DEG of it (its only noise is the rim's walk), the
#: walks elsewhere
DEFAULT_SOLVER = "auto"
# bands solved together by the layered solver, one chunk per thread (a design's kept
# operators take up to about 50 MB per band of a chunk)
LAYERED_CHUNK = 4


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


def by_indices(band_stacks) -> dict[tuple, list[int]]:
    """The bands of ``band_stacks`` grouped by their layers' refractive indices: the layered
    solver's nodes follow the indices, so a group is solved together."""
    groups: dict[tuple, list[int]] = {}
    for i, stack in enumerate(band_stacks):
        groups.setdefault(tuple(lay.n for lay in stack), []).append(i)
    return groups


def _tuples(band_stacks) -> list[list[tuple]]:
    return [[layer.as_tuple(i) for i, layer in enumerate(stack)] for stack in band_stacks]


def _ordered_runs(band_stacks, inst, photons, seed, key0, n_below, estimator, threads, cb,
                  survival, past_rim_only=False):
    """The core's order sums (bands, replicates, orders + 1, keys) and photons per replicate
    (``past_rim_only``: only what the specimen's rim takes, the layered solver's
    correction)."""
    kind, deg = parse_incidence(inst.spec.incidence)
    raw = _core.slab_read_bands(
        _tuples(band_stacks), [key0 + k for k in range(len(band_stacks))], int(photons),
        int(seed), inst.window(0.0), MAX_ORDER, float(survival), n_above=1.0,
        n_below=float(n_below), incidence=kind, angle_deg=deg, estimator=estimator,
        threads=threads, progress=cb, past_rim_only=past_rim_only)
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


#: the largest tilt of an instrument's beam that the layered solver reads as a beam along
#: the normal: the d/8 geometry's 8°, whose tilt moves a reading by 0.2-0.3 % at most (walks
#: of 1.6 M photons against the 0-d geometry; docs/notes/2026-12-07-default-and-speed.md),
#: within the solver's stated accuracy (layered.stack.ACCURACY); the rim walk keeps the tilt
MAX_TILT_DEG = 8.0


def layered_refusal(inst) -> str | None:
    """Why the layered solver cannot read through ``inst``, or None where it can: it needs a
    beam along the normal (the detector cone, lit region and window are then symmetric
    about it) or within MAX_TILT_DEG of it, read as along it."""
    if inst.is_infinite or inst.spec.incidence == "normal":
        return None
    kind, deg = parse_incidence(inst.spec.incidence)
    if kind == "angle" and deg <= MAX_TILT_DEG:
        return None
    return (f"solver = 'layered': instrument {inst.name!r} ({inst.geometry}) lights at "
            f"{inst.spec.incidence!r}; the layered solver needs a beam along the normal "
            f"or within {MAX_TILT_DEG:g} deg of it. Use solver = 'monte-carlo' (or 'auto')")


def _survival(rb_black, rb_white) -> float:
    return float(np.clip(max(np.max(rb_white), np.max(rb_black)), *SURVIVAL_RANGE))


# the layered solver's last order sums, by specimen and window (about 130 kB each): a
# reading sized by --precision, a design's nodes solved together, the replicate seeds of a
# test read the same specimens again
_SOLVED: dict = {}
_SOLVED_KEEP = 256


def _regions(inst) -> tuple:
    """What the layered solver reads through: (detector cone, lit ring, window ring, pairs),
    the rings None and the pairs given for a fibre probe (window.py)."""
    if inst.fibres is not None:
        return inst.spec.cone_deg, None, None, inst.fibres.pairs()
    a0, a, b0, b, _, _, cone = inst.window(0.0)
    return cone, (a0, a), (b0, b), None


@contextmanager
def sharing():
    """Within this block the layered solver keeps each material's eigen-decomposition across
    solves (:func:`dentalux.reading.layered.share`): a design's table, its verifications and
    its evaluations then decompose each material once. Usable as a decorator."""
    from dentalux.reading import layered

    with layered.share():
        yield


#: the rim walk launches one photon per RIM_SHARE photons of a reading's budget
#: (``photons``): the core splits each on its way out to the rim and back (slab.rs,
#: RIM_SPLIT_FRACTIONS), into 4-13 walks on the library's tissues (enamel 1 mm to the 4.4 mm
#: natural incisor, measured by CPU), so a budget costs about what as many plain walks did
#: and reads with 5-13 times less variance per CPU-second
RIM_SHARE = 8


def rim_photons(photons: int) -> int:
    """Photons per band the rim walk launches for a budget of ``photons``."""
    return max(1, -(-int(photons) // RIM_SHARE))


def rim_event_bound(inst, rb_black, rb_white, survival: float) -> np.ndarray:
    """The most that one photon launched by the rim walk can take from each channel's reading
    (channels × bands): its weight (1 at launch, never more but through the backing's
    survival roulette, which the backing's reflectance R_b undoes order by order, (R_b /
    survival)^k at order k) times what the window counts it (1 / the detector cone's
    Lambertian fraction; the transmitted light has no cone), over the reading's white
    normaliser."""
    cone = inst.spec.cone_deg
    gain = 1.0 / cone_fraction(cone) if cone else 1.0

    def roulette(rb):
        return np.maximum(1.0, np.asarray(rb, dtype=float) / survival) ** MAX_ORDER

    return np.stack([gain * roulette(rb_black), gain * roulette(rb_white),
                     np.ones(len(rb_black))]) / inst.white_fraction()


def rim_bound(corr: np.ndarray, infinite: np.ndarray, bound: np.ndarray, launched: float,
              channels) -> RimBound | None:
    """The :class:`RimBound` of a rim walk whose replicates' terms are ``corr`` (R, channels,
    bands; the term of a band and channel where the walk saw no event is exactly 0 in every
    replicate, its tallies' weights being positive) for the ``channels`` it reads, from the
    most one photon can take (``bound``, :func:`rim_event_bound`) and the laterally infinite
    specimen's readings (``infinite``); None where it saw an event everywhere."""
    none = np.all(corr == 0.0, axis=0)
    none[[c for c in range(none.shape[0]) if c not in channels]] = False
    if not none.any():
        return None
    return RimBound(effect=np.where(none, -bound, 0.0),
                    cap=np.where(none, np.maximum(infinite, 0.0), 0.0), launched=launched)


def check_batches(photons: int, rim: bool) -> None:
    """Refuse a Monte Carlo part that would run as one batch: its standard error comes from
    the spread between batches, and one batch has none (it read 0). The core's smallest
    batch sets the floor: a walk needs more than SLAB_MIN_BATCH photons per band, a rim walk
    more than RIM_SHARE x SLAB_MIN_RIM_BATCH."""
    floor = RIM_SHARE * int(_core.SLAB_MIN_RIM_BATCH) if rim else int(_core.SLAB_MIN_BATCH)
    if int(photons) <= floor:
        what = "the rim walk's budget" if rim else "the walks"
        raise ValueError(
            f"photons = {int(photons)} per band is too few for a standard error: "
            f"{what} would run as one batch; allowed at least {floor + 1} photons per band")


def _solve_key(band_stacks, inst, n_below: float) -> tuple:
    # what the solve reads through (the specimen's rim is the walk's, not the solver's)
    return (tuple(tuple(lay.as_tuple(i) for i, lay in enumerate(stack))
                  for stack in band_stacks), _regions(inst), float(n_below))


def _solve_orders(specimens, inst, n_below: float, cb, done: int,
                  threads: int | None = None) -> list[np.ndarray]:
    """The layered solver's order sums (bands, orders + 1, keys) of each specimen (one stack
    per band) through ``inst``'s window, for laterally infinite specimens; kept in _SOLVED."""
    keys = [_solve_key(bs, inst, n_below) for bs in specimens]
    todo = [i for i, k in enumerate(keys) if k not in _SOLVED]
    fresh = dict(zip(todo, _solve_orders_uncached([specimens[i] for i in todo], inst,
                                                  n_below, cb, done, threads), strict=True))
    out = [fresh[i] if i in fresh else _SOLVED[key] for i, key in enumerate(keys)]
    for i, value in fresh.items():
        if len(_SOLVED) >= _SOLVED_KEEP:
            _SOLVED.pop(next(iter(_SOLVED)))
        _SOLVED[keys[i]] = value
    if cb:
        cb(done + sum(len(bs) for bs in specimens))
    return out


def _solve_orders_uncached(specimens, inst, n_below: float, cb, done: int,
                           threads: int | None = None) -> list[np.ndarray]:
    """:func:`_solve_orders` without the cache: chunks of bands of one set of refractive
    indices, every specimen within a chunk, so that specimens sharing a layer (a design's
    nodes) share its operators (layered.reuse)."""
    from dentalux.reading import layered
    from dentalux.reading.layered import window

    cone, lit, view, pairs = _regions(inst)
    regions = window.as_pairs(lit, view, pairs)
    ks = window.nodes_for(regions)
    modes = window.modes_by_k(regions, ks)
    outs = [np.zeros((len(bs), MAX_ORDER + 1, len(WINDOW_KEYS))) for bs in specimens]
    groups: dict[tuple, list[tuple[int, list[int]]]] = {}
    for spec_i, bs in enumerate(specimens):
        for indices, members in by_indices(bs).items():
            groups.setdefault(indices, []).append((spec_i, members))
    chunks = [(indices, entries, lo) for indices, entries in groups.items()
              for lo in range(0, max(len(m) for _, m in entries), LAYERED_CHUNK)]

    stop = threading.Event()  # set on Ctrl-C: the running chunks end at their next step

    def solve(chunk) -> int:
        indices, entries, lo = chunk
        first = float(_core.fresnel_reflectance([1.0], 1.0, indices[0])[0])
        count = 0
        # this chunk's bands of every specimen (a specimen whose bands end before it has none)
        work = [(spec_i, members[lo:lo + LAYERED_CHUNK]) for spec_i, members in entries]
        work = [(spec_i, idx) for spec_i, idx in work if idx]
        groups = [[specimens[spec_i][i] for i in idx] for spec_i, idx in work]
        with layered.reuse():
            found = layered.responses_many(groups, 1.0, n_below, cone, ks, stop=stop.is_set,
                                           modes_by_k=modes)
            for (spec_i, idx), group, res in zip(work, groups, found, strict=True):
                local = layered.local_parts(group, 1.0, n_below)
                outs[spec_i][idx] = layered.order_sums(res, local, first, lit, view,
                                                       MAX_ORDER, WINDOW_KEYS, pairs)
                count += len(idx)
        return count

    # chunks on threads (numpy's LAPACK calls release the GIL), each with one BLAS thread:
    # BLAS's own threads on matrices of this size spin more than they compute (measured:
    # 3 CPU-s for an enamel solve with one, 24-64 with BLAS's threads on a loaded machine)
    workers = min(len(chunks), threads or os.cpu_count() or 1)
    pool = ThreadPoolExecutor(max_workers=max(workers, 1))
    with threadpool_limits(limits=1, user_api="blas"):
        futures = [pool.submit(solve, chunk) for chunk in chunks]
        try:
            for fut in futures:
                done += fut.result()
                if cb:
                    cb(done)
        finally:
            # on Ctrl-C (or an error) the chunks not started are dropped and the running
            # ones stop at their next spatial frequency group
            stop.set()
            for fut in futures:
                fut.cancel()
            pool.shutdown(wait=True)
    return outs


def solved(band_stacks, inst, rb_black, rb_white, photons: int, seed: int,
           estimator: str = "weighted", threads=None, progress=False,
           contact: float | None = None) -> ReadSpectra:
    """The instrument's readings from the layered solver (:mod:`dentalux.reading.layered`),
    exact for a laterally infinite specimen, with a Monte Carlo walk of ``photons`` per band
    for what a finite specimen's rim takes (past-rim tallies, the only noise)."""
    why = layered_refusal(inst)
    if why:
        raise ValueError(why)
    wl_count = len(band_stacks)
    n_below = 1.0 if contact is None else float(contact)
    runs = 1 if contact is None else 2
    rim = inst.fibres is None and np.isfinite(inst.window(0.0)[4])
    start_cpu, start = time.process_time(), time.perf_counter()
    total = wl_count * runs * (2 if rim else 1)
    with bar(total, "bands", progress) as cb:
        sums = _solve_orders([band_stacks], inst, n_below, cb, 0, threads)[0]
        t_sums = sums if contact is None else _solve_orders([band_stacks], inst, 1.0, cb,
                                                            wl_count, threads)[0]
        solver_cpu = time.process_time() - start_cpu
        if not rim:
            n_rep = np.ones(1)
            sums, t_sums = sums[:, None], t_sums[:, None]
            mc_photons, bounds = 0, ()
        else:
            limits.check_slab(photons, threads, seed=seed)
            check_batches(photons, rim=True)
            survival = _survival(rb_black, rb_white)
            key = int(_core.RIM_RUN_KEY)
            t_key = key + int(_core.TRANSMITTED_RUN_KEY)

            sources = rim_photons(photons)
            corr, n_rep, _ = _ordered_runs(band_stacks, inst, sources, seed, key, n_below,
                                           estimator, threads, None, survival, True)
            infinite = _channels(sums[:, None], t_sums[:, None], inst, rb_black, rb_white)[0]
            t_corr = corr
            sums = sums[:, None] * n_rep[None, :, None, None] - corr
            if contact is None:
                t_sums = sums
            else:
                t_corr = _ordered_runs(band_stacks, inst, sources, seed, t_key, 1.0,
                                       estimator, threads, None, survival, True)[0]
                t_sums = t_sums[:, None] * n_rep[None, :, None, None] - t_corr
            # where the rim walk saw no event its replicates agree: the zero count's bound
            # stands for their spread (spectra.RimBound); a contact's transmitted light is
            # its own walk
            terms = _channels(corr, t_corr, inst, rb_black, rb_white)
            bound = rim_event_bound(inst, rb_black, rb_white, survival)
            walks = [(0, 1, 2)] if contact is None else [(0, 1), (2,)]
            bounds = tuple(b for b in (rim_bound(terms, infinite, bound, float(n_rep.sum()),
                                                 w) for w in walks) if b is not None)
            mc_photons = int(photons) * wl_count * runs  # the budget (RIM_SHARE)
            if cb:
                cb(total)
    extra = {"runs": runs, "rim_correction": bool(rim), "solver_cpu_seconds": solver_cpu}
    if rim:
        extra["rim_launched_per_band"] = int(n_rep.sum())
    return _spectra(sums, t_sums, n_rep, inst, rb_black, rb_white, start_cpu, start,
                    photons=mc_photons, method="layered", extra=extra, bounds=bounds)


def windowed(band_stacks, inst, rb_black, rb_white, photons: int, seed: int,
             estimator: str = "weighted", threads=None, progress=False,
             contact: float | None = None, walks: str = "per-band") -> ReadSpectra:
    """The instrument's readings over black, over white and in transmission of one stack
    per band, tallied by backing order (module doc): ``walks`` 'per-band' (one walk per
    band) or 'shared' (every band from shared walks with a hero band per photon)."""
    wl_count = len(band_stacks)
    limits.check_slab(photons, threads, seed=seed)
    n_below = 1.0 if contact is None else float(contact)
    survival = _survival(rb_black, rb_white)
    runs = 1 if contact is None else 2
    start_cpu, start = time.process_time(), time.perf_counter()
    if walks not in WALKS:
        raise ValueError(f"walks = {walks!r}: allowed {', '.join(WALKS)}")
    shared = walks == "shared"
    if not shared:
        check_batches(photons, rim=False)
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
    return _spectra(sums, t_sums, n_rep, inst, rb_black, rb_white, start_cpu, start,
                    photons=int(photons) * wl_count * runs,
                    method="shared-walks" if shared else "backing-orders",
                    extra={"runs": runs, "truncated_max": float(np.max(truncated)),
                           "survival": survival, **extra})


def _channels(sums, t_sums, inst, rb_black, rb_white) -> np.ndarray:
    """The readings over black, over white and in transmission (R, channels, bands) that
    order sums (bands, R, orders + 1, keys) tally, unnormalised by photons."""
    spec = inst.spec
    read_key = "viewed_cone_reflectance" if spec.cone_deg else "viewed_reflectance"
    f = inst.white_fraction()

    def reading(rb):
        v = _polynomial(sums, read_key, rb)
        if spec.cone_deg is None and spec.specular == "excluded":
            v = v - _polynomial(sums, "viewed_specular", rb)
        return v / f

    zero = np.zeros(sums.shape[0])
    return np.stack([reading(rb_black), reading(rb_white),
                     _polynomial(t_sums, "viewed_transmittance", zero) / f], axis=1)


def _spectra(sums, t_sums, n_rep, inst, rb_black, rb_white, start_cpu, start, photons,
             method, extra, bounds=()) -> ReadSpectra:
    """The readings over black, over white and in transmission from order sums (bands,
    replicates, orders + 1, keys) and the photons of each replicate (``bounds``: the rim
    walks' :class:`RimBound`, where they saw no event)."""
    per_rep = _channels(sums, t_sums, inst, rb_black, rb_white)
    loss = np.stack([_polynomial(sums, "outside_reflectance", rb)
                     + _polynomial(sums, "rim_loss", rb) for rb in (rb_black, rb_white)], axis=1)
    # replicate estimates are sums over their photons: means per replicate, and the overall
    # mean weighted by photons
    weights = n_rep / n_rep.sum()
    reps = per_rep / n_rep[:, None, None]
    values = np.tensordot(weights, reps, axes=([0], [0]))
    var = replicate_variance(weights, reps - values)
    edge = np.tensordot(weights, loss / n_rep[:, None, None], axes=([0], [0]))
    return ReadSpectra(
        wavelengths_nm=np.zeros(0), values=values, stderr=with_bounds(var, bounds),
        edge_loss=edge, photons=photons, cpu_seconds=time.process_time() - start_cpu,
        method=method, replicates=reps, replicate_weights=weights,
        extra={"seconds": time.perf_counter() - start, **extra}, rim_bounds=bounds)


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


def infinite_solved(band_stacks, rb_black, rb_white, contact: float | None = None
                    ) -> ReadSpectra:
    """The ``infinite`` geometry's readings by the adding formula, its R1, T1, R2, T2 from
    the layered solver at spatial frequency 0 (no noise)."""
    from dentalux.reading import layered

    start_cpu, start = time.process_time(), time.perf_counter()
    n_below = 1.0 if contact is None else float(contact)
    vals = np.zeros((5, len(band_stacks)))
    for members in by_indices(band_stacks).values():
        group = [band_stacks[i] for i in members]
        with threadpool_limits(limits=1, user_api="blas"):
            res = layered.responses(group, 1.0, n_below, None, ks=(0.0,))
            air = res if contact is None else layered.responses(group, 1.0, 1.0, None,
                                                                ks=(0.0,))
        vals[:4, members] = [res.r_all[:, 0], res.into_backing[:, 0], res.q[:, 0],
                             res.e_all[:, 0]]
        vals[4, members] = air.into_backing[:, 0]

    def combine(batch):  # (..., 5, bands) -> (..., 3, bands)
        r1, t1, r2, t2, tt = (batch[..., i, :] for i in range(5))
        return np.stack([over_backing(r1, t1, r2, t2, rb_black),
                         over_backing(r1, t1, r2, t2, rb_white), tt], axis=-2)

    values = combine(vals)
    return ReadSpectra(
        wavelengths_nm=np.zeros(0), values=values, stderr=np.zeros_like(values),
        edge_loss=np.zeros((2, len(band_stacks))), photons=0,
        cpu_seconds=time.process_time() - start_cpu, method="layered", inputs=vals,
        inputs_stderr=np.zeros_like(vals), combine=combine,
        extra={"seconds": time.perf_counter() - start,
               **{k: vals[i] for i, k in enumerate(ADDING_INPUTS)},
               **{f"{k}_stderr": np.zeros_like(vals[i]) for i, k in enumerate(ADDING_INPUTS)}})


def use_layered(inst, solver: str) -> bool:
    """Whether ``solver`` ('monte-carlo', 'layered', 'auto') reads through ``inst`` with the
    layered solver; 'layered' where it does not hold is refused (ValueError)."""
    if solver not in SOLVERS:
        raise ValueError(f"solver = {solver!r}: allowed {', '.join(SOLVERS)}")
    if solver == "monte-carlo" and inst.fibres is not None:
        raise ValueError(f"solver = 'monte-carlo': instrument {inst.name!r} is a fibre probe, "
                         "which the slab walk cannot follow (separate fibres); it is read by "
                         "the layered solver: use solver = 'layered' or 'auto'")
    if solver == "monte-carlo":
        return False
    if solver == "auto":
        return layered_refusal(inst) is None
    why = layered_refusal(inst)
    if why:
        raise ValueError(why)
    return True


def measure_many(specimens, wl, inst, rb_black, rb_white, photons: int, seed: int,
                 estimator: str = "weighted", threads=None, progress=False,
                 solver: str = DEFAULT_SOLVER) -> list[ReadSpectra]:
    """:func:`measure` of several specimens (a design's nodes) with the same seed; the
    layered solver solves them together, each layer and thickness once."""
    shared_cpu = 0.0
    if use_layered(inst, solver) and not inst.is_infinite:
        contact = inst.contact_index
        start_cpu = time.process_time()
        with bar(len(specimens) * len(wl), "bands solved", progress) as cb:
            _solve_orders(specimens, inst, 1.0 if contact is None else float(contact), cb, 0,
                          threads)
            if contact is not None:
                _solve_orders(specimens, inst, 1.0, None, 0, threads)
        # the solve's CPU shared among the readings it served
        shared_cpu = (time.process_time() - start_cpu) / max(len(specimens), 1)
    out = []
    with bar(len(specimens), "readings", progress) as cb:
        for bs in specimens:
            out.append(measure(bs, wl, inst, rb_black, rb_white, photons, seed, estimator,
                               threads, False, solver=solver))
            out[-1].cpu_seconds += shared_cpu
            if cb:
                cb(len(out))
    return out


def measure(band_stacks, wl, inst, rb_black, rb_white, photons: int, seed: int,
            estimator: str = "weighted", threads=None, progress=False,
            walks: str = "per-band", solver: str = DEFAULT_SOLVER) -> ReadSpectra:
    """The readings of one stack per band (``band_stacks``, top layer first) at the bands
    ``wl`` [nm] through ``inst`` with backing reflectances ``rb_black``, ``rb_white`` per
    band (module doc). ``walks``: 'per-band' or 'shared' (instrument windows only);
    ``solver``: one of SOLVERS ('auto' with shared walks reads by the walks)."""
    if walks not in WALKS:
        raise ValueError(f"walks = {walks!r}: allowed {', '.join(WALKS)}")
    contact = inst.contact_index
    layered = use_layered(inst, solver)
    if walks == "shared" and layered:
        # shared walks are a Monte Carlo method: 'auto' keeps the walks they name
        if inst.fibres is not None:
            raise ValueError(f"walks = 'shared': instrument {inst.name!r} is a fibre probe, "
                             "read by the layered solver only; leave walks as 'per-band'")
        if solver == "layered":
            raise ValueError("walks = 'shared' needs solver = 'monte-carlo' (or 'auto')")
        layered = False
    if layered:
        if inst.is_infinite:
            out = infinite_solved(band_stacks, rb_black, rb_white, contact)
        else:
            out = solved(band_stacks, inst, rb_black, rb_white, photons, seed, estimator,
                         threads, progress, contact)
    elif inst.is_infinite:
        out = infinite(band_stacks, rb_black, rb_white, photons, seed, estimator, threads,
                       progress, contact)
    else:
        out = windowed(band_stacks, inst, rb_black, rb_white, photons, seed, estimator,
                       threads, progress, contact, walks)
    if inst.white_reference is not None:  # divide by the instrument's own tile instead
        from dentalux.reading import white_reference

        out = white_reference.calibrate(out, wl, inst, rb_black, photons, seed, estimator,
                                        threads, solver)
    out.wavelengths_nm = np.asarray(wl, dtype=float)
    return out
