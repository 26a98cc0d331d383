"""Variance × CPU-seconds of a specimen reading, per method, in one run (2 cores).

A reading's cost to reach a standard error s is proportional to s² × CPU-s of any run (the
variance falls as 1/photons), so the product is the method's figure of merit: lower is
better, and the ratio of two methods is how many times cheaper one reaches the same
precision. Methods, each through the contact probe (``contact-probe-3mm``, whose 10 mm
specimen has a rim; the default instrument, 45-0, has none, so its layered reading has no
noise at all), 41 bands:

- ``separate-runs``: the reading before the reading engine: one slab walk per band and per
  backing (black, white) and one more for the transmitted light (the probe's black backing
  is not ideal), bands independent;
- ``backing-orders``: the reading engine (dentalux.reading): one walk per band tallied by
  backing order, black, white and transmitted from the same photons;
- ``shared-walks``: the engine with every band from shared walks (a hero band per photon,
  ``walks="shared"``), the same number of walks;
- ``layered``: the engine's deterministic solver (``solver="layered"``,
  dentalux.reading.layered), exact for a laterally infinite specimen; the probe's 10 mm
  specimen is finite, so a walk of the same photons per band tallies what its rim takes, and
  that walk (split on its way to the rim and back, ``engine.RIM_SHARE``) is the reading's
  only noise.

The layered reading's CPU has a fixed part, the solver (deterministic, the same for every
seed), and a part that grows with photons, the rim walk; variance × CPU-s only means
something for the second, so the two are reported apart. The engine caches the solver's
result per specimen (``engine._SOLVED``): the cache is cleared once per case, the first
seed's reading pays the solver and gives its CPU, and every reading's walk CPU is its CPU
less its solver's (none once cached); solving again at every seed would measure the same
fixed cost once per seed. The layered gain column is variance × walk CPU-s; ``bo/layered``
beside it is how many times the CPU-s of one layered reading (solver and walk)
backing-orders needs to reach the layered spread (variance_bo × CPU-s_bo / sd_layered²,
over the layered CPU-s): the choice for one reading of a new specimen. (The engine runs the
solver's BLAS on one thread per chunk of bands: with BLAS's own threads the loaded machine
counted their waiting, 7-20 times the work.)

Cases: enamel 1 mm; dentin 2 mm; the two-layer stack enamel 0.6 / dentin 0.9 mm. For every
quantity the variance is the spread over seeds (not the claimed standard error), so the
figure needs no trust in either method's error estimate; the claimed s.e. is printed beside
it as a check. ``--seeds`` and ``--photons`` size the run, ``--methods`` picks some of the
methods (gains are relative to the first picked, in the order above).

    .venv/bin/python benchmarks/precision.py [--seeds 8] [--photons 10000]
        [--methods backing-orders layered]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from dentalux import dental, instrument, reading
from dentalux.color import system
from dentalux.reading import engine as reading_engine
from dentalux.slab import simulate
from dentalux.spectra import Reconstruction, resolve_bands

# the instrument of every method: a probe on a finite specimen (module doc)
PROBE = "contact-probe-3mm"
CASES = {
    "enamel 1 mm": [("enamel", 1.0)],
    "dentin 2 mm": [("dentin", 2.0)],
    "enamel 0.6 / dentin 0.9": [("enamel", 0.6), ("dentin", 0.9)],
}
QUANTITIES = ("lab_black.L", "lab_black.a", "lab_black.b", "lab_white.L", "lab_white.a",
              "lab_white.b", "tp00", "cr")


def separate_runs(parts, photons: int, seed: int) -> tuple[dict, float]:
    """The reading with one walk per band and backing (the method before the engine)."""
    inst = instrument.get(PROBE)
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


METHODS = ("separate-runs", "backing-orders", "shared-walks", "layered")
# how the engine reads for each method but separate-runs: (walks, solver)
ENGINE = {"backing-orders": ("per-band", "monte-carlo"), "shared-walks": ("shared", "monte-carlo"),
          "layered": ("per-band", "layered")}


def engine(parts, photons: int, seed: int, walks: str = "per-band",
           solver: str = "monte-carlo") -> tuple[dict, float, dict, float]:
    """A reading through the engine: the values, CPU-s, claimed s.e. and the solver's CPU-s
    (0 for the walks, and for a layered reading whose solution was cached)."""
    m = dental.read(parts, instrument=PROBE, photons=photons, seed=seed,
                    walks=walks, solver=solver)
    flat = {"tp00": m.tp00, "cr": m.cr}
    for key in ("lab_black", "lab_white"):
        for j, c in enumerate("Lab"):
            flat[f"{key}.{c}"] = getattr(m, key)[j]
    return flat, m.cpu_seconds, m.stderr, m.fixed_cpu_seconds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--photons", type=int, default=10_000)
    ap.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS),
                    help="methods to run (default: all); gains are relative to the first "
                         "in the order " + ", ".join(METHODS))
    args = ap.parse_args()
    methods = [m for m in METHODS if m in args.methods]
    ref = methods[0]
    print(f"instrument {PROBE}, 41 bands, {args.photons} photons per band and "
          f"walk, {args.seeds} seeds; variance = spread over seeds")
    for case, parts in CASES.items():
        runs = {m: [] for m in methods}
        cpu = dict.fromkeys(methods, 0.0)
        claimed = {m: [] for m in methods if m != "separate-runs"}
        solver_cpu = 0.0
        # the first layered reading of the case pays the solver (module doc)
        reading_engine._SOLVED.clear()
        for seed in range(1, args.seeds + 1):
            if "separate-runs" in methods:
                flat, c = separate_runs(parts, args.photons, seed)
                runs["separate-runs"].append(flat)
                cpu["separate-runs"] += c
            for method in claimed:
                flat, c, se, fixed = engine(parts, args.photons, seed, *ENGINE[method])
                runs[method].append(flat)
                cpu[method] += c - fixed  # the walk's CPU; the solver's is kept apart
                solver_cpu += fixed
                claimed[method].append(se)
        print(f"\n{case}")
        per = {m: cpu[m] / args.seeds for m in cpu}
        # the CPU-s of one layered reading of a new specimen: the solver and the walk
        whole = per.get("layered", 0.0) + solver_cpu
        print("  CPU-s per reading: " + ", ".join(
            f"{m} {whole:.2f} (solver {solver_cpu:.2f} once, walk {per[m]:.2f})"
            if m == "layered" else f"{m} {per[m]:.2f}" for m in per))
        print(f"  sd over seeds (claimed s.e.) and variance x CPU-s relative to {ref} "
              "(gain: how many times cheaper to the same standard error; layered: walk "
              "CPU-s only)")
        if "layered" in methods and "backing-orders" in methods:
            print("  bo/layered: CPU-s backing-orders needs for the layered sd, over the "
                  "layered CPU-s per reading (solver and walk)")
        for q in QUANTITIES:
            sd = {m: float(np.std([r[q] for r in runs[m]], ddof=1)) for m in runs}
            merit = {m: sd[m] ** 2 * per[m] for m in runs}
            cells = [f"{ref} {sd[ref]:.3f}"] if ref == "separate-runs" else []
            for m in methods:
                if m == "separate-runs":
                    continue
                se = float(np.mean([c[q] for c in claimed[m]]))
                cell = f"{m} {sd[m]:.3f} ({se:.3f})"
                if m != ref:
                    cell += f" gain {merit[ref] / merit[m]:.1f}x"
                if m == "layered" and "backing-orders" in methods:
                    ratio = merit["backing-orders"] / sd[m] ** 2 / whole
                    cell += f" bo/layered {ratio:.3g}x"
                cells.append(cell)
            print(f"  {q:12s} " + "; ".join(cells))


if __name__ == "__main__":
    main()
