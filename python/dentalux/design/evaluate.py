"""Given thicknesses, ranked (``dentalux design --evaluate 0.5/0.9,0.6/0.8``).

A technician often has a few candidate layerings in mind (what the last case used, what the
kit suggests) and wants them compared, not searched. :func:`evaluate` reads each candidate as
the design's verification does: the specimen of :func:`dentalux.design.substrates.specimen`
(the layers, the cement, the substrate) through :func:`dentalux.dental.read` with the
substrate's backings, one seed for every candidate (common random numbers: the candidates'
differences are less noisy than their values). Each gets its ΔE00 to the target over the
white backing with its standard error (:func:`dentalux.design.verify.delta_e_stderr`), the
verdict against 0.8 / 1.8 that its ±2 s.e. interval allows (:func:`dentalux.dental.verdict`)
and, with a TP target, ΔTP00. They are ranked by ΔE00 (+ ΔTP00 with a TP target), as the
search ranks its designs; ``to_json`` keeps the design keys (``thickness_mm``, ``delta_e00``,
``delta_e00_stderr``, ``verdict``) under ``evaluated``.

A layer is ``MATERIAL`` or ``MATERIAL:MIN-MAX``; a candidate outside a given range or the
total range is read all the same and marked ``within_ranges: false``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from dentalux import dental
from dentalux import instrument as instruments
from dentalux.design import constraints, substrates, targets, verify
from dentalux.reading import DEFAULT_SOLVER
from dentalux.reading.engine import sharing

#: the seed offset of the candidates' reads (the verification's: seed + 1)
SEED_OFFSET = 1
#: candidates per call: each is one full Monte Carlo read
MAX_CANDIDATES = 50


@dataclass
class EvaluationResult:
    """Candidates ranked by ΔE00 to the target (``to_json`` is ``design --evaluate --json``)."""

    target: targets.Target
    evaluated: list[dict]
    instrument: dict
    substrate: str
    layers: list[dict]
    cement: dict | None
    seconds: float
    cpu_seconds: float
    photons_per_band: int
    bands_nm: list | None = None

    def to_json(self) -> dict:
        return {"target": self.target.to_json(), "evaluated": self.evaluated,
                "instrument": self.instrument, "substrate": self.substrate,
                "layers": self.layers, "cement": self.cement, "seconds": self.seconds,
                "cpu_seconds": self.cpu_seconds, "photons_per_band": self.photons_per_band,
                "bands_nm": self.bands_nm}


def parse_candidates(text, layers: int) -> list[list[float]]:
    """``"0.5/0.9,0.6/0.8"`` (or a list of sequences) -> [[0.5, 0.9], [0.6, 0.8]]: each
    candidate as many thicknesses [mm] as layers, each in (0, MAX_MM]."""
    if isinstance(text, str):
        items = [c.strip() for c in text.split(",") if c.strip()]
        raw = [c.split("/") for c in items]
    else:
        items = list(text or [])
        raw = [list(c) if not isinstance(c, (int, float)) else [c] for c in items]
    if not raw:
        raise ValueError(f"evaluate = {text!r}: give thicknesses T1/T2/...[,T1/T2/...] [mm]")
    if len(raw) > MAX_CANDIDATES:
        raise ValueError(f"evaluate: {len(raw)} candidates given, allowed at most "
                         f"{MAX_CANDIDATES} (each is a full Monte Carlo read)")
    out = []
    for i, cand in enumerate(raw):
        if len(cand) != layers:
            raise ValueError(f"evaluate candidate {i + 1} = {items[i]!r}: {len(cand)} "
                             f"thickness(es) for {layers} layer(s); write one per layer, top "
                             "to bottom, separated by '/'")
        ts = []
        for x in cand:
            try:
                t = float(x)
            except (TypeError, ValueError):
                t = math.nan
            if isinstance(x, bool) or not (math.isfinite(t) and 0 < t <= constraints.MAX_MM):
                raise ValueError(f"evaluate candidate {i + 1} = {items[i]!r}: thickness "
                                 f"{x!r} is out of range: allowed 0 < mm <= "
                                 f"{constraints.MAX_MM:g}")
            ts.append(t)
        out.append(ts)
    return out


def parse_layers(layers) -> list[tuple[object, tuple[float, float] | None]]:
    """1 to 3 layers, each ``MATERIAL``, ``MATERIAL:MIN-MAX``, a material object or
    (material, (min, max) or None)."""
    if layers is None or isinstance(layers, (str, bytes)) or not hasattr(layers, "__iter__"):
        raise ValueError(f"layers = {layers!r}: expected a list of MATERIAL or "
                         "MATERIAL:MIN-MAX")
    out = []
    for i, item in enumerate(layers):
        if isinstance(item, str):
            material, sep, rng = item.rpartition(":")
            if sep and material.strip() and constraints._RANGE.match(rng):
                out.append(constraints.parse_layer(item, i))
            else:
                out.append((item.strip(), None))
        elif isinstance(item, tuple) and len(item) == 2:
            material, rng = item
            out.append((material, None if rng is None else
                        constraints.check_range(rng, f"layer[{i}] thickness range")))
        else:
            out.append((item, None))
    if not out:
        raise ValueError("layers: at least one layer is needed (allowed 1 to 3)")
    if len(out) > constraints.MAX_LAYERS:
        raise ValueError(f"layers: {len(out)} given, allowed 1 to {constraints.MAX_LAYERS} "
                         "layers")
    return out


def _cement(cement):
    """``MATERIAL:MM`` or (material, mm) -> (resolved material, mm), or None."""
    parsed = constraints.parse_cement(cement)
    return None if parsed is None else (dental._resolve_material(parsed[0]), parsed[1])


@sharing()
def evaluate(target, layers, candidates, total=None, substrate: str = "dentin", cement=None,
             instrument=instruments.DEFAULT, bands=dental.DEFAULT_BANDS,
             target_tp: float | None = None, photons: int = 10_000, seed: int = 1,
             precision: float | None = None, illuminant: str = "D65", observer: str = "2",
             reconstruction: str = "hold", estimator: str = "weighted",
             threads: int | None = None, progress: bool | None = False,
             solver: str = DEFAULT_SOLVER) -> EvaluationResult:
    """Read each of ``candidates`` (thicknesses [mm] top to bottom, or ``"T1/T2,..."``) of
    ``layers`` on ``substrate`` and rank them by ΔE00 to ``target`` (module doc). The
    arguments are :func:`dentalux.design.optimise`'s; ``precision`` (a standard error in
    ΔE00 units) sizes each read instead of ``photons``."""
    from dentalux.color import delta_e00
    from dentalux.design.forward import check_data
    from dentalux.spectra import resolve_bands

    start, cpu0 = time.perf_counter(), time.process_time()
    spec = parse_layers(layers)
    cands = parse_candidates(candidates, len(spec))
    ranges = [r for _, r in spec]
    total = None if total is None else constraints.check_total(
        total, [r if r is not None else (0.0, constraints.MAX_MM) for r in ranges])
    substrate = substrates.check(substrate)
    inst = instruments.get(instrument)
    wl = resolve_bands(bands)
    parts = []
    for i, (material, _) in enumerate(spec):
        m = dental._resolve_material(material)
        check_data(m, wl, f"layer[{i}] material")
        parts.append(m)
    cement = _cement(cement)
    if cement is not None:
        check_data(cement[0], wl, "cement material")
    common = dict(bands=wl, illuminant=illuminant, observer=observer,
                  reconstruction=reconstruction, estimator=estimator, threads=threads,
                  progress=progress, solver=solver)
    tgt = targets.parse(target, target_tp, read=lambda stack: dental.read(
        stack, instrument=inst, photons=photons, seed=seed + 2, precision=precision,
        **common))
    tp = tgt.tp00 is not None
    if tp and substrates.backings(substrate):
        raise ValueError(f"target_tp with substrate = {substrate!r}: an opaque core replaces "
                         "both backings, so TP is 0 by construction; a TP target needs "
                         "substrate none, dentin or stump")
    names = [str(getattr(p, "name", "material")) for p in parts]
    out = []
    for thick in cands:
        t0 = time.perf_counter()
        specimen = substrates.specimen(list(zip(parts, thick, strict=True)), substrate, cement)
        m = dental.read(specimen, instrument=inst, photons=photons, seed=seed + SEED_OFFSET,
                        precision=precision, **substrates.backings(substrate), **common)
        used = photons if precision is None else int(m.precision["photons_per_band"])
        lab = m.lab_white
        lab_err = [m.stderr[f"lab_white.{c}"] for c in "Lab"]
        de = float(delta_e00(np.asarray(lab), np.asarray(tgt.lab)))
        de_err = verify.delta_e_stderr(lab, lab_err, tgt.lab, tgt.lab_stderr)
        within = all(r is None or r[0] - 1e-9 <= t <= r[1] + 1e-9
                     for t, r in zip(thick, ranges, strict=True))
        if total is not None:
            within = within and total[0] - 1e-9 <= sum(thick) <= total[1] + 1e-9
        d = {"thickness_mm": thick, "materials": names, "lab": lab, "lab_stderr": lab_err,
             "delta_e00": de, "delta_e00_stderr": de_err,
             "verdict": dental.verdict(de, de_err),
             "verdict_probability": dental.verdict_probabilities(de, de_err),
             "within_ranges": within, "photons_per_band": used,
             "seconds": time.perf_counter() - t0}
        if tp:
            dtp = abs(m.tp00 - tgt.tp00)
            d.update(tp00=m.tp00, tp00_stderr=m.stderr["tp00"], delta_tp00=dtp,
                     delta_tp00_stderr=math.hypot(m.stderr["tp00"], tgt.tp00_stderr),
                     translucency_verdict=dental.translucency_verdict(dtp))
        out.append(d)
    out.sort(key=lambda d: d["delta_e00"] + (d.get("delta_tp00", 0.0) if tp else 0.0))
    for i, d in enumerate(out):
        d["rank"] = i + 1
    inst_json = inst.override(**substrates.backings(substrate)).to_json()
    return EvaluationResult(
        target=tgt, evaluated=out, instrument=inst_json, substrate=substrate,
        layers=[{"material": n, "range_mm": None if r is None else list(r),
                 **({"spec": mat} if isinstance(mat, str) else {})}
                for n, r, (mat, _) in zip(names, ranges, spec, strict=True)],
        cement=None if cement is None else {"material": str(getattr(cement[0], "name",
                                                                    "material")),
                                            "thickness_mm": cement[1]},
        seconds=time.perf_counter() - start, cpu_seconds=time.process_time() - cpu0,
        photons_per_band=max(d["photons_per_band"] for d in out),
        bands_nm=[float(b) for b in wl])


__all__ = ["EvaluationResult", "evaluate", "parse_candidates", "parse_layers"]
