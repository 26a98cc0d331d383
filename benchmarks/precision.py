"""Variance × CPU-seconds of a specimen reading, per method, in one run (2 cores).

A reading's cost to reach a standard error s is proportional to s² × CPU-s of any run (the
variance falls as 1/photons), so the product is the method's figure of merit: lower is
better, and the ratio of two methods is how many times cheaper one reaches the same
precision. Methods, each through the default instrument (the contact probe), 41 bands:

- ``separate-runs``: the reading before the reading engine: one slab walk per band and per
  backing (black, white) and one more for the transmitted light (the probe's black backing
  is not ideal), bands independent;
- ``backing-orders``: the reading engine (dentalux.reading): one walk per band tallied by
  backing order, black, white and transmitted from the same photons;
- ``shared-walks``: the engine with every band from shared walks (a hero band per photon,
  ``walks="shared"``), the same number of walks.

Cases: enamel 1 mm; dentin 2 mm; the two-layer stack enamel 0.6 / dentin 0.9 mm. For every
quantity the variance is the spread over seeds (not the claimed standard error), so the
figure needs no trust in either method's error estimate; the claimed s.e. is printed beside
it as a check. ``--seeds`` and ``--photons`` size the run.

    .venv/bin/python benchmarks/precision.py [--seeds 8] [--photons 10000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from dentalux import dental, instrument, reading
from dentalux.color import system
from dentalux.slab import simulate
from dentalux.spectra import Reconstruction, resolve_bands

CASES = {
    "enamel 1 mm": [("enamel", 1.0)],
    "dentin 2 mm": [("dentin", 2.0)],
    "enamel 0.6 / dentin 0.9": [("enamel", 0.6), ("dentin", 0.9)],
}
QUANTITIES = ("lab_black.L", "lab_black.a", "lab_black.b", "lab_white.L", "lab_white.a",
              "lab_white.b", "tp00", "cr")


def separate_runs(parts, photons: int, seed: int) -> tuple[dict, float]:
    """The reading with one walk per band and backing (the method before the engine)."""
    inst = instrument.get(instrument.DEFAULT)
    wl = resolve_bands("full")
    rb_black = dental.backing_spectrum(inst.backing_black, wl, "backing_black")
    rb_white = dental.backing_spectrum(inst.backing_white, wl, "backing_white")
    mats = [(dental._resolve_material(m), t) for m, t in parts]
    band_stacks = reading.stacks(mats, wl)
    cpu = time.process_time()
    vals = np.zeros((3, len(wl)))
    for k, stack in enumerate(band_stacks):
        common = dict(n_photons=photons, estimator="weighted", seed=seed,
                      incidence=inst.spec.incidence, n_above=1.0, n_below=1.0)
        for i, (rb, band) in enumerate(((rb_black[k], k), (rb_white[k], 100_000 + k))):
            res = simulate(stack, band=band, window=inst.window(rb), **common)
            vals[i, k] = inst.reading(res.window, res.window_stderr)[0]
        t = simulate(stack, band=200_000 + k, window=inst.window(0.0), **common)
        vals[2, k] = t.window["viewed_transmittance"] / inst.white_fraction()
    cpu = time.process_time() - cpu
    cs = system("D65", "2")
    rec = Reconstruction(wl, grid=cs.wavelengths, basis="hold")
    out = dental.colour_of(vals[None], cs, rec, "black")
    flat = {"tp00": float(out["tp00"][0]), "cr": float(out["cr"][0])}
    for key in ("lab_black", "lab_white"):
        for j, c in enumerate("Lab"):
            flat[f"{key}.{c}"] = float(out[key][0][j])
    return flat, cpu


METHODS = ("separate-runs", "backing-orders", "shared-walks")


def engine(parts, photons: int, seed: int, walks: str = "per-band") -> tuple[dict, float, dict]:
    m = dental.read(parts, instrument=instrument.DEFAULT, photons=photons, seed=seed,
                    walks=walks)
    flat = {"tp00": m.tp00, "cr": m.cr}
    for key in ("lab_black", "lab_white"):
        for j, c in enumerate("Lab"):
            flat[f"{key}.{c}"] = getattr(m, key)[j]
    return flat, m.cpu_seconds, m.stderr


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--photons", type=int, default=10_000)
    args = ap.parse_args()
    print(f"instrument {instrument.DEFAULT}, 41 bands, {args.photons} photons per band and "
          f"walk, {args.seeds} seeds; variance = spread over seeds")
    for case, parts in CASES.items():
        runs = {m: [] for m in METHODS}
        cpu = dict.fromkeys(METHODS, 0.0)
        claimed = {m: [] for m in METHODS[1:]}
        for seed in range(1, args.seeds + 1):
            flat, c = separate_runs(parts, args.photons, seed)
            runs["separate-runs"].append(flat)
            cpu["separate-runs"] += c
            for method, walks in (("backing-orders", "per-band"), ("shared-walks", "shared")):
                flat, c, se = engine(parts, args.photons, seed, walks)
                runs[method].append(flat)
                cpu[method] += c
                claimed[method].append(se)
        print(f"\n{case}")
        per = {m: cpu[m] / args.seeds for m in cpu}
        print("  CPU-s per reading: " + ", ".join(f"{m} {per[m]:.2f}" for m in per))
        print("  sd over seeds (claimed s.e.) and variance x CPU-s relative to separate-runs "
              "(gain: how many times cheaper to the same standard error)")
        for q in QUANTITIES:
            sd = {m: float(np.std([r[q] for r in runs[m]], ddof=1)) for m in runs}
            merit = {m: sd[m] ** 2 * per[m] for m in runs}
            cells = [f"{METHODS[0]} {sd[METHODS[0]]:.3f}"]
            for m in METHODS[1:]:
                se = float(np.mean([c[q] for c in claimed[m]]))
                cells.append(f"{m} {sd[m]:.3f} ({se:.3f}) gain {merit[METHODS[0]] / merit[m]:.1f}x")
            print(f"  {q:12s} " + "; ".join(cells))


if __name__ == "__main__":
    main()
