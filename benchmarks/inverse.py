"""Inversion benchmark and model comparison (prints figures; not a test).

    .venv/bin/python benchmarks/inverse.py            # timings
    .venv/bin/python benchmarks/inverse.py --tables   # + the markdown tables of docs/inversion.md

Timings: seconds per wavelength for each model on the paper's Table 1 rows (warm: the first,
import-laden call is run once and not counted), mc at fit tolerance 0.001 on TT/TR with its
default 400 000 photons per evaluation, the weighted estimator and a fixed seed.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np
from dentalux.inverse import fit
from dentalux.inverse.models import Sample, get_model
from dentalux.slab import Layer, simulate

DATA = Path(__file__).resolve().parents[1] / "python" / "dentalux" / "data"
ROWS = [  # label, tt, tr, n  (g = 0.75, d = 0.5 mm)
    ("450 nm", 0.4897, 0.3016, 1.550),
    ("540 nm", 0.6016, 0.3243, 1.540),
    ("605 nm", 0.6540, 0.3255, 1.537),
    ("D65", 0.6121, 0.3228, 1.540),
]
FORWARD_CASES = [  # mua, mus, g, n, d
    (0.1147, 7.44, 0.75, 1.55, 0.5),
    (0.0361, 5.83, 0.75, 1.54, 0.5),
    (0.01, 6.0, 0.96, 1.63, 1.0),
    (0.1, 6.0, 0.96, 1.63, 1.0),
    (0.35, 28.0, 0.93, 1.54, 1.0),
    (0.1, 20.0, 0.9, 1.0, 2.0),
    (0.5, 2.0, 0.0, 1.4, 0.3),
    (0.01, 50.0, 0.75, 1.5, 3.0),
]


def timings(repeats: int) -> None:
    print(f"cores: {os.cpu_count()}, load average: {os.getloadavg()[0]:.1f}")
    fit(tt=0.6016, tr=0.3243, n=1.54, g=0.75, thickness=0.5, model="mc")  # warm-up
    for model in ("telegrapher", "km", "ad", "mc"):
        kw = {"km_k2": 0.0} if model == "km" else {}
        per_row = []
        evals = []
        for _, tt, tr, n in ROWS[:3]:
            ts = []
            for _ in range(repeats if model != "mc" else 1):
                t0 = time.perf_counter()
                r = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model=model, **kw)
                ts.append(time.perf_counter() - t0)
            per_row.append(min(ts))
            evals.append(r.evaluations)
        unit, scale = ("ms", 1e3) if model in ("telegrapher", "km", "ad") else ("s", 1.0)
        print(f"{model:12s} per wavelength: median {statistics.median(per_row) * scale:8.3f} "
              f"{unit}, max {max(per_row) * scale:8.3f} {unit}  (model evaluations: {evals})")
    t0 = time.perf_counter()
    simulate([Layer(mua=0.036, mus=5.83, g=0.75, n=1.54, thickness=0.5)], n_photons=400_000,
             seed=1, estimator="weighted")
    print(f"one mc evaluation (400k photons, weighted): {time.perf_counter() - t0:.3f} s")


def table1_markdown() -> None:
    print("\n| row | model | μa [1/mm] | μa interval | μs [1/mm] | μs interval | μs' [1/mm] "
          "| fit TT | fit TR | mc at this (μa, μs): TT, TR |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, tt, tr, n in ROWS:
        for model, kw, name in (("mc", {}, "mc"), ("ad", {}, "ad"),
                                ("telegrapher", {}, "telegrapher"),
                                ("km", {}, "km (Fresnel k2)"),
                                ("km", {"km_k2": 0.0}, "km (k2 = 0)")):
            try:
                r = fit(tt=tt, tr=tr, n=n, g=0.75, thickness=0.5, model=model, **kw)
            except ValueError as exc:
                msg = str(exc).split(": closest fit")[1] if "closest" in str(exc) else str(exc)
                print(f"| {label} | {name} | cannot reproduce (closest fit{msg}) "
                      "| | | | | | | |")
                continue
            chk = simulate([Layer(mua=r.mua, mus=r.mus, g=0.75, n=n, thickness=0.5)],
                           n_photons=1_000_000, seed=4242, estimator="weighted")
            mua = f"{r.mua:.4f}" if r.mua_resolved else f"{r.mua:.4f} (≤ {r.mua_ci[1]:.4f})"
            print(f"| {label} | {name} | {mua} | [{r.mua_ci[0]:.4f}, {r.mua_ci[1]:.4f}] | "
                  f"{r.mus:.3f} | [{r.mus_ci[0]:.3f}, {r.mus_ci[1]:.3f}] | {r.musp:.3f} | "
                  f"{r.fit_tt:.4f} | {r.fit_tr:.4f} | {chk.total_transmittance:.4f}, "
                  f"{chk.total_reflectance:.4f} |")


def forward_markdown() -> None:
    print("\n| μa | μs | g | n | d [mm] | mc TT, TR (± 1 s.e.) | ad ΔTT, ΔTR | "
          "telegrapher ΔTT, ΔTR | P1 (no δ) ΔTT, ΔTR | km ΔTT, ΔTR |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    from dentalux.inverse.models.telegrapher import Telegrapher

    models = [get_model("ad"), get_model("telegrapher"), Telegrapher(delta=False),
              get_model("km")]
    worst = np.zeros(len(models))
    for mua, mus, g, n, d in FORWARD_CASES:
        res = simulate([Layer(mua=mua, mus=mus, g=g, n=n, thickness=d)], n_photons=2_000_000,
                       seed=77, estimator="weighted")
        t_mc, r_mc = res.total_transmittance, res.total_reflectance
        se = max(res.stderr["total_transmittance"], res.stderr["total_reflectance"])
        cells = []
        for i, m in enumerate(models):
            tt, tr = m.forward(mua, mus, Sample(g=g, n=n, thickness=d))
            dt, dr = float(tt) - t_mc, float(tr) - r_mc
            worst[i] = max(worst[i], abs(dt), abs(dr))
            cells.append(f"{dt:+.4f}, {dr:+.4f}")
        print(f"| {mua} | {mus} | {g} | {n} | {d} | {t_mc:.4f}, {r_mc:.4f} (±{se:.4f}) | "
              + " | ".join(cells) + " |")
    print("| | | | | | largest abs. difference | " + " | ".join(f"{w:.4f}" for w in worst)
          + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--tables", action="store_true", help="print the docs tables")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    timings(args.repeats)
    if args.tables:
        table1_markdown()
        forward_markdown()


if __name__ == "__main__":
    main()
