"""Benchmark: a two-layer restoration design over 41 bands, searched and verified.

The target is the colour of a known stack (enamel over dentin on the dentin substrate) read
by the Monte Carlo through the instrument with its own seed; the design searches enamel
and dentin thicknesses for it. Prints the search time (the fast model's Monte Carlo nodes
plus the dense search) and the verification time (the full Monte Carlo read of each
design) separately, the recovered thicknesses and the fast model's agreement with the
Monte Carlo. Target: under 60 s on 2 cores.

``--accuracy`` also measures the fast model against the full Monte Carlo at off-node points
(ΔE00 between the two colours, and the z-scores), the numbers quoted in docs/design.md.

    .venv/bin/python benchmarks/design.py [--photons 5000] [--instrument d8-benchtop-sav]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from dentalux import design
from dentalux.color import delta_e00
from dentalux.design import verify


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--photons", type=int, default=5000, help="photons per band and run")
    ap.add_argument("--instrument", default="d8-benchtop-sav")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--truth", default="0.5,0.9", help="enamel,dentin thicknesses [mm]")
    ap.add_argument("--designs", type=int, default=2)
    ap.add_argument("--accuracy", action="store_true", help="also measure fast model vs MC")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    truth = [float(x) for x in args.truth.split(",")]
    layers = [("enamel", (0.2, 1.2)), ("dentin", (0.3, 1.5))]
    t0 = time.perf_counter()
    ref = design.read(list(zip(["enamel", "dentin"], truth, strict=True)), "dentin",
                      instrument=args.instrument, bands="full", photons=args.photons,
                      seed=1234, threads=args.threads)
    target_seconds = time.perf_counter() - t0
    tgt = design.Target(tuple(ref.lab_white), None, {"kind": "stack", "status": "derived"},
                        tuple(ref.stderr[f"lab_white.{c}"] for c in "Lab"))
    res = design.optimise(tgt, layers, total=(0.8, 2.2), substrate="dentin",
                          instrument=args.instrument, bands="full", photons=args.photons,
                          designs=args.designs, threads=args.threads)
    best = res.designs[0]
    out = {
        "bands": 41, "photons": args.photons, "instrument": args.instrument,
        "truth_mm": truth, "target_lab": list(tgt.lab), "target_seconds": target_seconds,
        "search_seconds": res.search_seconds, "verify_seconds": res.verify_seconds,
        "total_seconds": res.seconds, "search_cpu_seconds": res.search_cpu_seconds,
        "verify_cpu_seconds": res.verify_cpu_seconds, "designs": len(res.designs),
        "best_thickness_mm": best["thickness_mm"], "best_delta_e00": best["delta_e00"],
        "best_delta_e00_stderr": best["delta_e00_stderr"], "sensitivity": best["sensitivity"],
        "verified": [d["verified"] for d in res.designs],
        "max_abs_z": [d["verification"]["max_abs_z"] for d in res.designs],
    }
    if args.accuracy:
        rng = np.random.default_rng(7)
        rows = []
        for _ in range(4):
            p = np.array([rng.uniform(*layers[0][1]), rng.uniform(*layers[1][1])])
            fast = res.surface.at(p)
            row = {"thickness_mm": p.round(3).tolist()}
            # an independent read (seed 99): the difference holds the noise of both and the
            # interpolation error (the nodes' noise is not correlated enough between
            # thicknesses for a same-seed read to separate the two)
            for label, seed in (("independent", 99),):
                mc = design.read(list(zip(["enamel", "dentin"], p, strict=True)), "dentin",
                                 instrument=args.instrument, bands="full",
                                 photons=args.photons, seed=seed, threads=args.threads)
                cmp = verify.compare(fast, mc, tp=False)
                row[label] = {"delta_e00_fast_vs_mc": float(delta_e00(
                    np.asarray(fast["values"]["lab_white"]), np.asarray(mc.lab_white))),
                    "max_abs_z": cmp["max_abs_z"]}
            rows.append(row)
        out["accuracy"] = rows
    if args.json:
        print(json.dumps(out, indent=1))
        return
    print(f"two-layer design, 41 bands, {args.photons} photons/band/run, {args.instrument}")
    print(f"  target read        {target_seconds:6.1f} s (not part of the design)")
    print(f"  search             {res.search_seconds:6.1f} s wall, {res.search_cpu_seconds:6.1f} s "
          "CPU (fast model nodes + dense search)")
    print(f"  verification       {res.verify_seconds:6.1f} s wall, {res.verify_cpu_seconds:6.1f} s "
          f"CPU ({len(res.designs)} designs, full MC)")
    print(f"  (on an idle 2-core machine the wall time is about CPU / 2: "
          f"{(res.search_cpu_seconds + res.verify_cpu_seconds) / 2:.1f} s)")
    print(f"  total (design)     {res.seconds:6.1f} s   target < 60 s on 2 cores")
    print(f"  truth {truth} mm -> best {best['thickness_mm']} mm, ΔE00 "
          f"{best['delta_e00']:.2f} ± {best['delta_e00_stderr']:.2f} ({best['verdict']}), "
          f"sensitivity {np.round(best['sensitivity'], 2).tolist()} ΔE00/0.1 mm, "
          f"verified {best['verified']} (max |z| {best['verification']['max_abs_z']:.2f})")
    for row in out.get("accuracy", []):
        ind = row["independent"]
        print(f"  fast vs MC at {row['thickness_mm']}: ΔE00 {ind['delta_e00_fast_vs_mc']:.2f} "
              f"(max |z| {ind['max_abs_z']:.2f})")



if __name__ == "__main__":
    main()
