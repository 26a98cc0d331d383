"""Readings calibrated on the instrument's own white tile (:mod:`dentalux.white_reference`).

A reading is (specimen's signal) / (tile's signal) × (tile's certified reflectance), band by
band, both signals through the same window, geometry and contact. Dividing one reading by
another cancels the ideal-white normaliser of :func:`dentalux.reading.engine._spectra`, so
the specimen's readings as the engine returns them can be used as they are. The transmitted
channel keeps its own reference (the open beam, a perfect transmitter).

The tile is read by the specimen's solver. The layered solver ('layered', or 'auto' through a
normal beam) reads an unbounded tile with no noise at all. A Monte Carlo tile has its own
seed, and its replicates are paired with the specimen's, so the tile's standard error reaches
every number computed from the reading (:meth:`dentalux.reading.spectra.ReadSpectra.propagate`).
The solver is not switched for the tile, so that the tile and the specimen are read the
same way and the ratio compares like with like.
"""

from __future__ import annotations

import numpy as np

from dentalux.reading.spectra import RimBound, replicate_variance, with_bounds

# the tile's walks use seed + this (mod 2^64): independent of the specimen's photons
SEED_OFFSET = 104_729
# tile readings already made (a design reads many specimens through one instrument)
_READ: dict = {}
_KEEP = 32
CALIBRATED = (0, 1)  # the channels a tile calibrates: over black and over white


def spectrum(value, wl) -> np.ndarray:
    """A number or (wavelengths, values) at the bands ``wl`` [nm] (held outside its range)."""
    if isinstance(value, tuple):
        return np.interp(wl, value[0], value[1])
    return np.full(len(wl), float(value))


def tile_reading(inst, wl, rb_black, photons: int, seed: int, estimator: str, threads,
                 solver: str = "monte-carlo"):
    """The tile's reading through ``inst`` by ``solver`` (a :class:`ReadSpectra`; channel 0
    is the tile over its backing)."""
    from dentalux import white_reference
    from dentalux.reading import engine

    tile = inst.white_reference
    bare = white_reference.instrument_for(inst)
    rb = np.asarray(rb_black if tile.backing is None else spectrum(tile.backing, wl), float)
    key = (bare, tile, tuple(map(float, wl)), tuple(rb), int(photons), int(seed), estimator,
           solver)
    if key not in _READ:
        if len(_READ) >= _KEEP:
            _READ.pop(next(iter(_READ)))
        _READ[key] = engine.measure(tile.layers(wl), wl, bare, rb, rb, photons,
                                    (int(seed) + SEED_OFFSET) % 2**64, estimator, threads,
                                    False, solver=solver)
    return _READ[key]


def calibrate(out, wl, inst, rb_black, photons: int, seed: int, estimator: str, threads,
              solver: str = "monte-carlo"):
    """``out`` (the specimen's ReadSpectra through ``inst``) divided by the tile's reading and
    multiplied by its certified reflectance, over black and over white; replicates linearised
    so that the tile's noise adds to the specimen's (module doc)."""
    if out.replicates is None:
        raise ValueError("white_reference: this reading has no replicates to calibrate "
                         "(the 'infinite' instrument has no tile)")
    tile = tile_reading(inst, wl, rb_black, photons, seed, estimator, threads, solver)
    t_reps = tile.replicates[:, 0, :]  # (R_t, bands)
    t_bar = tile.values[0]
    if np.any(~(t_bar > 0)):
        raise ValueError(f"white_reference: the tile reads {t_bar.min():.3g} through "
                         f"{inst.name!r}, so nothing can be divided by it: give a tile that "
                         "sends light into the window")
    cert = spectrum(inst.white_reference.reflectance, wl)
    s_reps, s_w = out.replicates, out.replicate_weights
    n_s, n_t = len(s_w), len(tile.replicate_weights)
    if n_t == 1:  # a tile with no noise (the layered solver, no rim)
        dev_t, w = np.zeros((n_s, len(wl))), s_w
    elif n_s == 1 or (n_s == n_t and np.allclose(s_w, tile.replicate_weights)):
        dev_t, w = t_reps - t_bar, tile.replicate_weights
        s_reps = np.broadcast_to(s_reps, (n_t,) + s_reps.shape[1:])
    else:
        raise ValueError(f"white_reference: the specimen's {n_s} replicates and the tile's "
                         f"{n_t} cannot be paired; use walks = 'per-band' or more photons")
    reps = np.array(s_reps, dtype=float)
    values = np.array(out.values, dtype=float)
    for c in CALIBRATED:
        # first order in the replicates' deviations: S_r/T - S (T_r - T)/T^2, times cert
        reps[:, c] = cert * (s_reps[:, c] / t_bar - out.values[c] * dev_t / t_bar**2)
        values[c] = cert * out.values[c] / t_bar
    var = replicate_variance(w, reps - values)
    # where a rim walk saw no event (spectra.RimBound): the specimen's terms are divided by
    # the tile as its reading is; the tile's own lower the tile, which raises the reading
    scale = np.ones_like(out.values)
    scale[list(CALIBRATED)] = cert / t_bar
    bounds = [RimBound(b.effect * scale, b.cap * scale, b.launched) for b in out.rim_bounds]
    raise_by = np.zeros_like(out.values)
    raise_by[list(CALIBRATED)] = cert * out.values[list(CALIBRATED)] / t_bar**2
    bounds += [RimBound(-b.effect[0] * raise_by, b.cap[0] * raise_by, b.launched)
               for b in tile.rim_bounds if np.any(b.effect[0])]
    out.values, out.replicates, out.replicate_weights = values, reps, w
    out.stderr = with_bounds(var, bounds)
    out.rim_bounds = tuple(bounds)
    out.photons += tile.photons
    out.extra["white_reference"] = {"tile_reading": t_bar.tolist(),
                                    "tile_reading_stderr": tile.stderr[0].tolist(),
                                    "tile_method": tile.method}
    return out
