"""``fit --readings`` benchmark: wall and CPU time of a fit, and its round trip (not a test).

    PYTHONPATH=python .venv/bin/python benchmarks/fit_readings.py --solver auto

Readings of a known material through ``contact-probe-3mm`` at 0.5 and 1.0 mm over black and
white (Monte Carlo, 40 000 photons per band, seed 5, 41 bands; kept in ``--cache`` so that
every run fits the same readings) are fitted with the true g and n, spectral and CIELAB-only;
the fitted material is then read at 1.5 and 2.0 mm and compared with the true material, two
ways: by Monte Carlo (fit 20 000 photons, seed 12; truth 40 000, seed 11; as
docs/notes/2026-12-07-fit-readings.md) and by the layered solver (both readings noise-free but
for the rim correction, so the comparison shows the fit's own error). ``--solver old`` runs
whatever ``dentalux`` is on the path with its own default (an older checkout).
"""

from __future__ import annotations

import argparse
import inspect
import json
import math
import time
from pathlib import Path

import numpy as np
from dentalux import dental, materials, readings
from dentalux.color import delta_e00
from dentalux.inverse import readings_fit as rf
from dentalux.testing import STAND_IN_COMPOSITE

INST = "contact-probe-3mm"
BANDS = [float(w) for w in range(380, 781, 10)]
COMPOSITE = STAND_IN_COMPOSITE


def truth_material(name: str, cache: Path):
    if name == "composite":
        f = cache / "comp.toml"
        f.write_text(COMPOSITE)
        return materials.load(f)["comp"]
    return materials.get(name)


def make_readings(mat, cache: Path, tag: str) -> tuple[Path, Path]:
    """The spectral and the CIELAB-only readings file of ``mat`` (made once per cache)."""
    spec, lab = cache / f"{tag}-spectral.csv", cache / f"{tag}-lab.csv"
    if spec.exists() and lab.exists():
        return spec, lab
    for t in (0.5, 1.0):
        m = dental.read([(mat, t)], instrument=INST, photons=40_000, seed=5, bands=BANDS)
        readings.write(spec, _shade_json(m), t)
    rows = ["thickness_mm,backing,L,a,b,sd_L,sd_a,sd_b"]
    text = [ln for ln in spec.read_text().splitlines() if not ln.startswith("#")]
    header = text[0].split(",")
    for line in text[1:]:
        cells = dict(zip(header, line.split(","), strict=True))
        rows.append(",".join(cells[c] for c in ("thickness_mm", "backing", "L", "a", "b",
                                                "sd_L", "sd_a", "sd_b")))
    lab.write_text("\n".join(rows) + "\n")
    return spec, lab


def _shade_json(m) -> dict:
    """The fields of ``shade --json`` that readings.write needs."""
    out = {"wavelength_nm": m.wavelengths_nm, "stderr": {}}
    for b in ("black", "white"):
        out[f"lab_{b}"] = list(getattr(m, f"lab_{b}"))
        out["stderr"][f"lab_{b}"] = [m.stderr[f"lab_{b}.{c}"] for c in "Lab"]
        out[f"reflectance_{b}"] = m.spectra[f"over_{b}"]
        out[f"reflectance_{b}_stderr"] = m.spectra[f"over_{b}_stderr"]
    return out


def compare(fitted, truth, t: float, solver: str) -> tuple[float, float, float]:
    """Worst ΔE00 over black / white of the fitted material's reading at ``t`` against the
    truth's, and the combined standard error, read by ``solver``."""
    kw = dict(instrument=INST, bands=BANDS)
    if solver == "layered":
        a = dental.read([(fitted, t)], photons=20_000, seed=12, solver="layered", **kw)
        b = dental.read([(truth, t)], photons=20_000, seed=11, solver="layered", **kw)
    else:
        a = dental.read([(fitted, t)], photons=20_000, seed=12, **kw)
        b = dental.read([(truth, t)], photons=40_000, seed=11, **kw)
    de = [float(delta_e00(getattr(a, f"lab_{k}"), getattr(b, f"lab_{k}")))
          for k in ("black", "white")]
    se = math.hypot(dental.reading_precision(a), dental.reading_precision(b))
    return de[0], de[1], se


def km_own(data, fitted, truth, g: float, n: float, t: float) -> list[float]:
    """ΔE00 over black / white of Kubelka-Munk's own prediction at ``t`` (its model over the
    instrument's backings) against the truth's Monte Carlo reading (40 000 photons, seed 11)."""
    from dentalux import instrument

    prob = rf.Problem(data, instrument.get(INST), g, n, "km", 0, 1, BANDS)
    b = dental.read([(truth, t)], instrument=INST, bands=BANDS, photons=40_000, seed=11,
                    solver="monte-carlo")
    mua, mus = (np.array([getattr(fitted.at(w), c) for w in BANDS], float) for c in ("mua", "mus"))
    return [round(float(delta_e00(prob.lab(rf.km_reflectance(
        mua, mus, g, n, t, prob.rg(k), prob.diffuse_only)),
        getattr(b, f"lab_{k}"))), 2) for k in ("black", "white")]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--solver", default="auto", help="monte-carlo | layered | auto | old")
    ap.add_argument("--cache", default="/tmp/fit-readings-bench")
    ap.add_argument("--cases", default="composite:spectral,composite:lab,dentin:lab")
    ap.add_argument("--model", default="mc", help="mc | km")
    args = ap.parse_args()
    cache = Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    kw = {} if args.solver == "old" else {"solver": args.solver}
    if kw and "solver" not in inspect.signature(rf.fit).parameters:
        raise SystemExit("this dentalux has no fit(solver=...): use --solver old")
    for case in args.cases.split(","):
        name, form = case.split(":")
        truth = truth_material(name, cache)
        spec, lab = make_readings(truth, cache, name)
        data = readings.load(spec if form == "spectral" else lab)
        g = float(np.mean(truth.g))
        n = float(np.mean(truth.n))
        t0, c0 = time.perf_counter(), time.process_time()
        res = rf.fit(data, INST, g=g, n=n, model=args.model, **kw)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        out = cache / f"{name}-{form}-{args.solver}-{args.model}.toml"
        import tomli_w

        out.write_bytes(tomli_w.dumps(rf.material_doc(
            res, data, __import__("dentalux").instrument.get(INST), "fit")).encode())
        fitted = materials.load(out)["fit"]
        row = {"case": case, "solver": getattr(res, "solver", "old"), "wall_s": round(wall, 1),
               "cpu_s": round(cpu, 1), "core_cpu_s": round(res.cpu_seconds, 1),
               "model_calls": res.evaluations,
               "residuals": [round(r["delta_e00"], 2) for r in res.residuals],
               "model_se": round(res.mc_stderr_de00, 3)}
        if args.model == "km":
            for t in (1.5, 2.0):
                row[f"{t}mm_km_own"] = km_own(data, fitted, truth, g, n, t)
            print(json.dumps(row), flush=True)
            continue
        for t in (1.5, 2.0):
            for how in ("monte-carlo", "layered"):
                b, w, se = compare(fitted, truth, t, how)
                row[f"{t}mm_{how}"] = [round(b, 2), round(w, 2), round(se, 2)]
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
