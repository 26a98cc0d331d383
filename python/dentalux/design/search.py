"""``dentalux.design.optimise``: which thickness of each layer matches a target tooth.

1. The fast model (:mod:`dentalux.design.forward`) reads the specimen by Monte Carlo at the
   nodes of a thickness grid and interpolates between them.
2. The search evaluates it on a dense grid (``step``, 0.01 mm by default for one or two
   layers: finer than a technician can hold) inside the layer ranges and the total range and
   ranks the points by the objective ΔE00 to the target colour over the white backing, plus
   |TP00 - target TP00| when a translucency target is given (both are ΔE00 units). The best
   points at least ``spacing`` apart (0.1 mm, Chebyshev distance) are the candidate designs.
3. Each design is read by the full Monte Carlo :func:`dentalux.dental.read` through the
   instrument with an independent seed (:mod:`dentalux.design.verify`); its reported numbers
   are the Monte Carlo's, ``verified`` says whether the fast model agreed within 4 standard
   errors.
4. Sensitivity: for each layer, ΔE00 between the design's colour and the colour with that
   layer 0.1 mm thicker or thinner (the larger of the two; one-sided at a range limit), from
   the fast model: how far a technician's ±0.1 mm moves the shade.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from dentalux import dental, inputs, limits, reading
from dentalux import instrument as instruments
from dentalux.color import delta_e00
from dentalux.design import constraints, substrates, targets, verify
from dentalux.design.forward import DEFAULT_NODES, ColourMap, Surface, check_data
from dentalux.spectra import resolve_bands

DEFAULT_PHOTONS = 10_000
TOLERANCE_MM = 0.1  # what a technician can hold: the sensitivity step and design spacing
MAX_DENSE_POINTS = 300_000


class Design(dict):
    """One design: a dict (the ``designs[i]`` object of ``dentalux design --json``) whose
    keys also read as attributes (``d.thickness_mm``, ``d.delta_e00``), with a short repr."""

    def __getattr__(self, key):
        try:
            return self[key]
        except KeyError:
            raise AttributeError(key) from None

    def __repr__(self) -> str:
        mm = " / ".join(f"{t:.2f}" for t in self["thickness_mm"])
        return (f"Design({mm} mm: ΔE00 {self['delta_e00']:.2f} ± "
                f"{self['delta_e00_stderr']:.2f}, {self['verdict']}, "
                f"{'verified' if self['verified'] else 'not verified'})")


@dataclass(repr=False)
class DesignResult:
    """The ranked designs and what produced them (``to_json`` is the CLI's object)."""

    target: targets.Target
    designs: list[dict]
    instrument: dict
    seconds: float
    search_seconds: float
    verify_seconds: float
    search_cpu_seconds: float
    verify_cpu_seconds: float
    substrate: str
    layers: list[dict]
    photons: int
    photons_per_band: int = 0
    plane: dict | None = None
    surface: Surface | None = field(default=None, repr=False)
    # what a render of a design needs (dentalux.design.render): the resolved layer
    # materials (top to bottom), the cement (material, mm) or None, the bands [nm]
    parts: list = field(default_factory=list, repr=False)
    cement: tuple | None = field(default=None, repr=False)
    bands: list = field(default_factory=list, repr=False)
    # with a requested precision: the pilot's numbers and the photons they chose
    precision: dict | None = None

    def __repr__(self) -> str:
        best = repr(self.designs[0]) if self.designs else "no design"
        return (f"DesignResult({len(self.designs)} designs on {self.substrate}, read by "
                f"{self.instrument.get('name', '?')}; best {best})")

    def to_json(self) -> dict:
        out = {"target": self.target.to_json(), "designs": [dict(d) for d in self.designs],
               "instrument": self.instrument, "seconds": self.seconds,
               "cpu_seconds": self.search_cpu_seconds + self.verify_cpu_seconds,
               "photons_per_band": self.photons_per_band}
        if self.precision is not None:
            out["precision"] = self.precision
        return out


def _axes(ranges, step: float) -> list[np.ndarray]:
    out = []
    for lo, hi in ranges:
        n = max(2, int(math.floor((hi - lo) / step + 1e-9)) + 1)
        ax = lo + step * np.arange(n)
        if hi - ax[-1] > 1e-9:
            ax = np.append(ax, hi)
        out.append(np.round(ax, 6))
    return out


def _pick(order, points, spacing: float, n: int) -> list[int]:
    """Greedy: the best points at least ``spacing`` apart (Chebyshev)."""
    chosen: list[int] = []
    for i in order:
        if all(np.max(np.abs(points[i] - points[j])) >= spacing - 1e-9 for j in chosen):
            chosen.append(int(i))
            if len(chosen) == n:
                break
    return chosen


def _sensitivity(surface: Surface, point: np.ndarray) -> list[float]:
    """ΔE00 per 0.1 mm for each layer (module doc, item 4)."""
    base = surface.metrics(surface.readings(point[None, :])[0])["lab_white"][0]
    out = []
    for d, (lo, hi) in enumerate(surface.ranges):
        worst = 0.0
        for sign in (1.0, -1.0):
            p = point.copy()
            p[d] = min(hi, max(lo, p[d] + sign * TOLERANCE_MM))
            h = abs(p[d] - point[d])
            if h < 1e-9:
                continue
            lab = surface.metrics(surface.readings(p[None, :])[0])["lab_white"][0]
            worst = max(worst, float(delta_e00(lab, base)) * TOLERANCE_MM / h)
        out.append(worst)
    return out


def jacobian(surface: Surface, point, h: float = 0.02) -> np.ndarray:
    """d(L*, a*, b*)/d(thickness) [1/mm] of the fast model at ``point``, (3, layers), by
    central differences of ``h`` mm (one-sided at a range limit)."""
    point = np.asarray(point, dtype=float)
    out = np.zeros((3, len(point)))
    for d, (lo, hi) in enumerate(surface.ranges):
        up, down = point.copy(), point.copy()
        up[d], down[d] = min(hi, point[d] + h), max(lo, point[d] - h)
        labs = surface.metrics(surface.readings(np.stack([up, down]))[0])["lab_white"]
        out[:, d] = (labs[0] - labs[1]) / (up[d] - down[d])
    return out


def _thickness_stderr(surface: Surface, point, lab_err, target_err) -> list:
    """How well the colour pins each thickness: the fast model's and the target's L*, a*,
    b* errors mapped through J = dLab/dt, Cov(t) = (J^T C^-1 J)^-1 (None where the colour
    does not pin a layer: J rank-deficient)."""
    var = np.maximum(np.asarray(lab_err) ** 2 + np.asarray(target_err) ** 2, 1e-12)
    j = jacobian(surface, point)
    info = j.T @ np.diag(1.0 / var) @ j
    try:
        cov = np.linalg.inv(info)
    except np.linalg.LinAlgError:
        return [None] * len(point)
    diag = np.diag(cov)
    return [float(np.sqrt(x)) if np.isfinite(x) and x >= 0 else None for x in diag]


@reading.engine.sharing()
def optimise(target, layers, total=None, substrate: str = "dentin", cement=None,
             instrument=instruments.DEFAULT, bands=dental.DEFAULT_BANDS,
             target_tp: float | None = None, photons: int = DEFAULT_PHOTONS,
             verify_photons: int | None = None, seed: int = 1, designs: int = 3,
             nodes: int | None = None, step: float | None = None,
             spacing: float = TOLERANCE_MM, check: bool = True, illuminant: str = "D65",
             observer: str = "2", reconstruction: str = "hold", estimator: str = "weighted",
             threads: int | None = None, progress: bool | None = False,
             precision: float | None = None, solver: str = reading.DEFAULT_SOLVER) -> DesignResult:
    """Search layer thicknesses that match ``target`` read through ``instrument``.

    ``target``: ``lab:L,a,b``, ``GUIDE:TAB`` (data/shade_guides.csv), ``stack:MAT:MM/...``,
    an (L, a, b) triple or a :class:`dentalux.design.targets.Target`; ``target_tp`` adds a
    TP00 target. ``layers``: 1 to 3 of (material, (min, max) [mm]) or ``MATERIAL:MIN-MAX``,
    top to bottom. ``total``: (min, max) [mm] of the restoration (cement excluded) or None.
    ``substrate``, ``cement``: :mod:`dentalux.design.substrates`. ``photons`` per band and
    run for the fast model's nodes, ``verify_photons`` (default the same) for the Monte Carlo
    verification; ``designs``: how many to return; ``nodes`` per layer (default 6, 4, 3 for
    1, 2, 3 layers); ``step`` of the dense search grid [mm]; ``check=False`` skips the
    verification (the numbers are then the fast model's and ``verified`` is false).
    ``precision`` (a standard error in ΔE00 units) chooses ``photons`` and
    ``verify_photons`` instead: a pilot reading of the specimen at the middle of every
    thickness range sizes them (:func:`dentalux.dental.photons_for_precision`).
    ``solver``: how every reading is computed (:data:`dentalux.reading.engine.SOLVERS`).
    """
    if precision is not None:
        dental.check_precision(precision)
    start = time.perf_counter()
    cpu0 = time.process_time()
    spec = constraints.check_layers(layers)
    ranges = [r for _, r in spec]
    total = constraints.check_total(total, ranges)
    substrate = substrates.check(substrate)
    inst_plain = instruments.get(instrument)
    try:
        inst = inst_plain.override(**substrates.backings(substrate))
    except ValueError as exc:
        if not substrate.endswith(".csv"):
            raise
        raise ValueError(f"substrate = {substrate!r}: the instrument model does not take this "
                         f"spectral backing ({exc}); give reflectance:R for now") from None
    wl = resolve_bands(bands)
    limits.check_reading_args(photons, seed, reconstruction, threads)
    if nodes is not None:  # a whole number, never truncated (3.5 was read as 3)
        nodes = inputs.integer(nodes, "nodes", 2, limits.MAX_DESIGN_NODES)
    # the fast model's photons, before any is traced (two runs per node with a TP target)
    limits.check_design_work(nodes or DEFAULT_NODES[len(spec)], len(spec), len(wl),
                             limits.check_reading_args(photons), 2 if target_tp is not None else 1)
    for name, value in (("photons", photons), ("designs", designs)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} = {value!r} is out of range: allowed an integer >= 1")
    verify_photons = photons if verify_photons is None else verify_photons
    if isinstance(verify_photons, bool) or not isinstance(verify_photons, int) \
            or verify_photons < 1:
        raise ValueError(f"verify_photons = {verify_photons!r} is out of range: allowed an "
                         "integer >= 1")
    if not (isinstance(spacing, (int, float)) and 0 <= spacing < 10):
        raise ValueError(f"spacing = {spacing!r} is out of range: allowed [0, 10) mm")
    if step is not None and not (isinstance(step, (int, float)) and 0 < step <= 1):
        raise ValueError(f"step = {step!r} is out of range: allowed (0, 1] mm")
    parts = []
    for i, (material, _) in enumerate(spec):
        m = dental._resolve_material(material)
        check_data(m, wl, f"layer[{i}] material")
        parts.append(m)
    tail = []
    if cement is not None:
        mat, mm = constraints.parse_cement(cement)
        cm = dental._resolve_material(mat)
        check_data(cm, wl, "cement material")
        tail.append((cm, mm))
        cement = (cm, mm)
    for m, t in substrates.layers(substrate):
        tail.append((dental._resolve_material(m), t))
    rb_black = dental.backing_spectrum(inst.backing_black, wl, "backing_black")
    rb_white = dental.backing_spectrum(inst.backing_white, wl, "backing_white")
    common = dict(bands=wl, illuminant=illuminant, observer=observer,
                  reconstruction=reconstruction, estimator=estimator, threads=threads,
                  solver=solver)

    def read_stack(stack):
        return dental.read(stack, instrument=inst_plain, photons=verify_photons,
                           seed=seed + 2, **common)

    plan = None
    if precision is not None:
        middle = [(m, 0.5 * (lo + hi)) for m, (lo, hi) in zip(parts, ranges, strict=True)]
        photons, plan = dental.photons_for_precision(
            middle + tail, precision, seed=seed, instrument=inst, **common)
        verify_photons = photons
        # the fast model's photons again, now that the precision has chosen them
        limits.check_design_work(nodes or DEFAULT_NODES[len(spec)], len(spec), len(wl),
                                 photons, 2 if target_tp is not None else 1)

    tgt = targets.parse(target, target_tp, read=read_stack)
    tp = tgt.tp00 is not None
    if tp and substrates.backings(substrate):
        raise ValueError(f"target_tp with substrate = {substrate!r}: an opaque core replaces "
                         "both backings, so TP is 0 by construction; a TP target needs "
                         "substrate none, dentin or stump")

    colour = ColourMap(wl, illuminant, observer, reconstruction)
    surface = Surface(parts, ranges, tail, inst, wl, rb_white, rb_black, colour, photons,
                      seed, black=tp, nodes=nodes, estimator=estimator, threads=threads,
                      progress=progress, solver=solver)

    # dense search
    k = len(parts)
    if step is None:
        step = 0.01 if k <= 2 else 0.025
    axes = _axes(ranges, float(step))
    while np.prod([len(a) for a in axes]) > MAX_DENSE_POINTS:
        step *= 1.5
        axes = _axes(ranges, step)
    m = surface.metrics(surface.grid(axes))
    de = np.asarray(delta_e00(m["lab_white"], np.asarray(tgt.lab)))
    objective = de + (np.abs(m["tp00"] - tgt.tp00) if tp else 0.0)
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    feasible = np.ones(de.shape, dtype=bool)
    if total is not None:
        s = mesh.sum(axis=-1)
        feasible = (s >= total[0] - 1e-9) & (s <= total[1] + 1e-9)
    if not feasible.any():
        raise ValueError(f"total = {total[0]:g}-{total[1]:g} mm: no point of the search grid "
                         f"(step {step:g} mm) meets it; widen the total or the layer ranges")
    flat_obj = np.where(feasible, objective, np.inf).ravel()
    points = mesh.reshape(-1, k)
    order = np.argsort(flat_obj, kind="stable")
    order = order[np.isfinite(flat_obj[order])]
    chosen = _pick(order, points, float(spacing), int(designs))
    plane = None
    if k == 2:
        plane = {"axes": [a.tolist() for a in axes], "delta_e00": de, "feasible": feasible,
                 "objective": objective}
    search_seconds = time.perf_counter() - start
    search_cpu = time.process_time() - cpu0

    out = []
    verify_seconds = 0.0
    names = [str(getattr(p, "name", "material")) for p in parts]
    exact = reading.engine.use_layered(inst, solver)
    for i in chosen:
        point = points[i].astype(float)
        thick = [round(float(x), 4) for x in point]
        fast = surface.at(point, tgt.lab)
        fast_de_err = verify.delta_e_stderr(fast["values"]["lab_white"],
                                            fast["stderr"]["lab_white"], tgt.lab, tgt.lab_stderr)
        fast_json = {"lab": fast["values"]["lab_white"], "lab_stderr": fast["stderr"]["lab_white"],
                     "delta_e00": fast["values"]["delta_e00"], "delta_e00_stderr": fast_de_err}
        if tp:
            fast_json.update(tp00=fast["values"]["tp00"], tp00_stderr=fast["stderr"]["tp00"])
        design = Design({"thickness_mm": thick, "materials": names,
                  "sensitivity": _sensitivity(surface, point),
                  "thickness_stderr_mm": _thickness_stderr(
                      surface, point, np.asarray(fast["stderr"]["lab_white"]),
                      np.asarray(tgt.lab_stderr))})
        if check:
            t0 = time.perf_counter()
            specimen = substrates.specimen(list(zip(parts, thick, strict=True)), substrate, cement)
            mc = dental.read(specimen, instrument=inst, photons=verify_photons, seed=seed + 1,
                             **common)
            seconds = time.perf_counter() - t0
            verify_seconds += seconds
            cmp = verify.compare(fast, mc, tp)
            lab = mc.lab_white
            lab_err = [mc.stderr[f"lab_white.{c}"] for c in "Lab"]
            de_mc = float(delta_e00(np.asarray(lab), np.asarray(tgt.lab)))
            de_err = verify.delta_e_stderr(lab, lab_err, tgt.lab, tgt.lab_stderr)
            noise_free = mc.photons == 0
            read_by = "the layered solver's read" if exact else "the Monte Carlo read"
            if cmp["verified"]:
                note = (f"the fast model agrees with {read_by} within "
                        f"{verify.SIGMAS:g} standard errors (max |z| = "
                        f"{cmp['max_abs_z']:.2f}), which would have caught a disagreement of "
                        f"ΔE00 {cmp['resolution_delta_e00']:.2f}")
            elif not cmp["agrees"] and exact:
                note = (f"NOT VERIFIED: the fast model's interpolation and the layered "
                        f"solver's read differ by max |z| = {cmp['max_abs_z']:.2f} > "
                        f"{verify.SIGMAS:g} standard errors; the numbers reported are the "
                        "solver's read")
            elif not cmp["agrees"]:
                note = (f"NOT VERIFIED: the fast model and the Monte Carlo read differ by max "
                        f"|z| = {cmp['max_abs_z']:.2f} > {verify.SIGMAS:g} standard errors; "
                        "the numbers reported are the Monte Carlo's")
            else:
                note = (f"NOT VERIFIED (inconclusive): {verify.SIGMAS:g} standard errors "
                        f"amount to ΔE00 {cmp['resolution_delta_e00']:.2f}, more than a "
                        f"perceptible {dental.PT}; the check could not have failed. Give more "
                        "photons (--verify-photons, --photons or --precision)")
            design.update(lab=lab, lab_stderr=lab_err, delta_e00=de_mc, delta_e00_stderr=de_err,
                          verdict=dental.verdict(de_mc, de_err),
                          verdict_probability=dental.verdict_probabilities(de_mc, de_err),
                          verified=cmp["verified"])
            if tp:
                dtp = abs(mc.tp00 - tgt.tp00)
                design.update(tp00=mc.tp00, tp00_stderr=mc.stderr["tp00"], delta_tp00=dtp,
                              delta_tp00_stderr=math.hypot(mc.stderr["tp00"], tgt.tp00_stderr),
                              translucency_verdict=dental.translucency_verdict(dtp))
            design["verification"] = {
                "method": "dentalux.dental.read through the instrument, " + (
                    "the layered solver alone (no Monte Carlo part)" if noise_free
                    else "independent seed"),
                "photons_per_band_and_run": 0 if noise_free else verify_photons,
                "seed": seed + 1,
                "sigmas": verify.SIGMAS, "z": cmp["z"], "max_abs_z": cmp["max_abs_z"],
                "delta_e00_fast_vs_mc": cmp["delta_e00_fast_vs_mc"], "seconds": seconds,
                "resolution_delta_e00": cmp["resolution_delta_e00"],
                "could_fail": cmp["could_fail"], "note": note}
        else:
            de_f = fast["values"]["delta_e00"]
            design.update(lab=fast["values"]["lab_white"], lab_stderr=fast["stderr"]["lab_white"],
                          delta_e00=de_f, delta_e00_stderr=fast_de_err,
                          verdict=dental.verdict(de_f, fast_de_err),
                          verdict_probability=dental.verdict_probabilities(de_f, fast_de_err),
                          verified=False)
            if tp:
                dtp = abs(fast["values"]["tp00"] - tgt.tp00)
                design.update(tp00=fast["values"]["tp00"], tp00_stderr=fast["stderr"]["tp00"],
                              delta_tp00=dtp, delta_tp00_stderr=fast["stderr"]["tp00"],
                              translucency_verdict=dental.translucency_verdict(dtp))
            design["verification"] = {"note": "not verified (check=False): the numbers are "
                                              "the fast model's"}
        design["fast_model"] = fast_json
        out.append(design)

    def rank(d):
        return d["delta_e00"] + (d.get("delta_tp00", 0.0) if tp else 0.0)

    # verified designs first; with the layered solver every checked design's numbers are
    # its own noise-free read, so they rank by those alone
    out.sort(key=lambda d: (not d["verified"] and not exact, rank(d)) if check else rank(d))
    seconds = time.perf_counter() - start
    inst_json = inst.to_json()
    return DesignResult(
        target=tgt, designs=out, instrument=inst_json, seconds=seconds,
        search_seconds=search_seconds, verify_seconds=verify_seconds,
        search_cpu_seconds=search_cpu, verify_cpu_seconds=time.process_time() - cpu0 - search_cpu,
        substrate=substrate,
        layers=[{"material": n, "range_mm": list(r)} for n, r in zip(names, ranges, strict=True)],
        photons=surface.photons, photons_per_band=int(photons), plane=plane, surface=surface,
        parts=parts, cement=cement, bands=[float(b) for b in wl], precision=plan)
