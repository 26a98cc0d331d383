"""Dental colour metrics of a disc: what a spectrophotometer reads off a specimen.

A disc (thickness d [mm]) of a material lies on a backing (a Lambertian reflector with
reflectance Rb(l): ideal black 0 and a white tile 0.9 by default) and is measured from above
with normal illumination and all reflected light collected (specular included, SCI), under
D65 with the CIE 1931 2 deg observer. For every band the slab simulator gives

- R1, T1: total reflectance and transmittance of the disc for the normal beam from above;
- R2, T2: total reflectance back down and transmittance up for diffuse (Lambertian) light
  from below (the disc flipped, lit diffusely),

and the backing is added by the adding (geometric series) formula

    R(Rb) = R1 + T1 Rb T2 / (1 - Rb R2).

This is exact for a laterally infinite disc on an ideal Lambertian backing: a Lambertian
backing sends back a Lambertian distribution whatever it receives, so only the disc's response
to Lambertian light from below is needed. It is not exact for a finite aperture and spot
(light lost sideways, which lowers TP as the aperture shrinks), nor for a glossy or
non-Lambertian backing. ``contact=None`` is an air gap (disc in air on both faces);
``contact=n_c`` is optical contact through a coupling medium of index n_c (e.g. 1.47,
glycerin; n_c equal to the disc's n removes the lower interface); Rb is then the backing's
reflectance as seen from inside that medium.

With an instrument (:mod:`dentalux.instrument`) other than ``infinite``, the backing is
inside the slab walk instead: photons enter over the instrument's lit spot and are read only
where they leave inside its window, so light that travels sideways is lost (edge loss). One
walk per band serves every backing (tallied by backing order, :mod:`dentalux.reading`), so
the readings over black and white and the transmitted light share their photons. The
``infinite`` instrument is the adding formula above.

Metrics: CIELAB over black, over white and in transmission (the disc's total transmittance
for the normal beam, disc in air, against a perfect transmitter); TP = ΔE*ab(black, white);
TP00 = ΔE00(black, white); CR = Y_black / Y_white; OP = sqrt(Δa*² + Δb*²) between the
transmitted colour and the colour reflected over black. Monte Carlo standard errors are
propagated to every metric to first order (numerical derivatives): through the replicates
of the shared walk, which carry the correlation of black, white and transmitted, or, for
the ``infinite`` geometry's independent runs, by adding their variances.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dentalux import instrument as instruments
from dentalux import limits, reading
from dentalux.color import delta_e00, delta_e00_scale, delta_e76, system
from dentalux.spectra import Reconstruction, resolve_bands
from dentalux.strict_json import check_finite

PT, AT = 0.8, 1.8  # ΔE00 50:50 % perceptibility / acceptability (Paravina et al. 2015)
TPT, TAT = 0.62, 2.62  # ΔTP00 50:50 % perceptibility / acceptability thresholds
# the keys of `dentalux shade --json` (DentalMetrics.to_json): the values, their standard
# errors under the same keys in `stderr`, the cost, and the spectra as the instrument reads them
JSON_KEYS = ("lab_black", "lab_white", "lab_transmitted", "tp", "tp00", "cr", "op",
             "instrument", "edge_loss", "stderr", "cpu_seconds", "photons", "method",
             "wavelength_nm",
             "reflectance_black", "reflectance_white", "reflectance_black_stderr",
             "reflectance_white_stderr")
DEFAULT_PHOTONS = 20_000
# the bands a reading integrates by default: 380-780 nm every 10 nm (spectra.full_bands)
DEFAULT_BANDS = "full"


class Lab(NamedTuple):
    """A CIELAB colour: L*, a*, b* (a tuple, so it indexes, iterates and prints to JSON as
    a list)."""

    L: float
    a: float
    b: float

    def __repr__(self) -> str:
        return f"Lab(L={self.L:.2f}, a={self.a:.2f}, b={self.b:.2f})"


class Measured(NamedTuple):
    """A number with its standard error."""

    value: float
    stderr: float

    def __repr__(self) -> str:
        return f"{self.value:.4g} ± {self.stderr:.2g}"


@dataclass(repr=False)
class DentalMetrics:
    """Colour numbers of a disc, each with its Monte Carlo standard error in ``stderr``
    (flat keys ``'lab_white.L'``, ``'tp00'``, ...; :meth:`error` and :meth:`measured` give
    them typed)."""

    material: str
    thickness: float
    lab_black: Lab
    lab_white: Lab
    lab_transmitted: Lab
    tp: float
    tp00: float
    cr: float
    op: float
    stderr: dict[str, float]
    wavelengths_nm: list[float]
    spectra: dict[str, list[float]] = field(default_factory=dict)
    photons: int = 0
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    method: str = ""
    # the part of cpu_seconds that does not grow with photons (the layered solver's)
    fixed_cpu_seconds: float = 0.0
    precision: dict = field(default_factory=dict)
    instrument: dict = field(default_factory=dict)
    edge_loss: dict = field(default_factory=dict)
    layers: list = field(default_factory=list)
    # where the rim walk saw no event: its photons per band, the bands of each channel, and
    # what their standard error is (rim_note); empty where it saw events everywhere
    rim_bound: dict = field(default_factory=dict)
    # with rim_bound: the standard errors from the replicates alone, without the zero
    # count's bound (not in the JSON)
    replicate_stderr: dict = field(default_factory=dict)

    def error(self, key: str) -> Lab | float:
        """The standard error of ``key``: a :class:`Lab` of errors for a colour, a float for
        a scalar (``tp``, ``tp00``, ``cr``, ``op``)."""
        if key.startswith("lab_"):
            return Lab(*(self.stderr[f"{key}.{c}"] for c in "Lab"))
        return self.stderr[key]

    def measured(self, key: str) -> Measured | tuple[Measured, Measured, Measured]:
        """``key`` with its standard error side by side: a :class:`Measured` for a scalar,
        three for a colour."""
        value, err = getattr(self, key), self.error(key)
        if key.startswith("lab_"):
            return tuple(Measured(v, e) for v, e in zip(value, err, strict=True))
        return Measured(value, err)

    def __repr__(self) -> str:
        name = self.instrument.get("name", "?")
        w, e = self.lab_white, self.error("lab_white")
        return (f"DentalMetrics({self.material}, {self.thickness:g} mm, read by {name}: "
                f"L*a*b* over white {w.L:.2f}±{e.L:.2f} {w.a:.2f}±{e.a:.2f} "
                f"{w.b:.2f}±{e.b:.2f}, TP00 {self.measured('tp00')}, "
                f"CR {self.measured('cr')})")

    def stderr_json(self) -> dict:
        """The standard errors under the same keys as the values they qualify."""
        out = {}
        for key in ("lab_black", "lab_white", "lab_transmitted"):
            out[key] = [self.stderr[f"{key}.{c}"] for c in "Lab"]
        out.update({k: self.stderr[k] for k in ("tp", "tp00", "cr", "op")})
        return out

    def to_json(self) -> dict:
        """The ``dentalux shade --json`` keys: the values, ``stderr`` (the same keys),
        ``cpu_seconds``, and the spectra as the instrument reads them."""
        d = asdict(self)
        out = {k: list(d[k]) if isinstance(d[k], tuple) else d[k]
               for k in JSON_KEYS if k in d and k != "stderr"}
        out["stderr"] = self.stderr_json()
        out["cpu_seconds"] = self.cpu_seconds
        out["photons"] = self.photons
        out["method"] = self.method
        if self.precision:
            out["precision"] = self.precision
        if self.rim_bound:
            out["rim_bound"] = self.rim_bound
        out["wavelength_nm"] = self.wavelengths_nm
        for backing in ("black", "white"):
            out[f"reflectance_{backing}"] = self.spectra.get(f"over_{backing}", [])
            out[f"reflectance_{backing}_stderr"] = self.spectra.get(f"over_{backing}_stderr", [])
        return out


def _resolve_material(material):
    if hasattr(material, "at"):
        return material
    if isinstance(material, (str, Path)):
        from dentalux import materials

        text = str(material)
        if ".toml:" in text:  # FILE.toml:NAME picks one material of a file
            path, name = text.rsplit(":", 1)
            found = materials.load(path)
            if name not in found:
                raise ValueError(f"material {name!r} not in {path}: allowed {', '.join(found)}")
            return found[name]
        p = Path(material)
        if p.suffix == ".toml" or p.is_file():
            if not p.is_file():
                raise FileNotFoundError(f"material file not found: {p}")
            found = materials.load(p)
            if len(found) != 1:
                raise ValueError(
                    f"material file {p} holds {len(found)} materials ({', '.join(found)}): "
                    "give one by name"
                )
            return next(iter(found.values()))
        return materials.get(str(material))
    raise ValueError(f"material = {material!r}: expected a Material, a name or a TOML path")


def backing_spectrum(backing, bands: np.ndarray, name: str) -> np.ndarray:
    """A backing reflectance: a number, (wavelengths_nm, values) or a callable of l [nm]."""
    if callable(backing):
        r = np.asarray([backing(float(w)) for w in bands], dtype=float)
    elif isinstance(backing, tuple) and len(backing) == 2:
        wl, val = (np.asarray(x, dtype=float) for x in backing)
        r = np.interp(bands, wl, val)
    else:
        try:
            r = np.full(len(bands), float(backing))
        except (TypeError, ValueError):
            raise ValueError(f"{name} = {backing!r}: expected a reflectance in [0, 1]") from None
    if not np.all(np.isfinite(r)) or np.any(r < 0) or np.any(r > 1):
        raise ValueError(f"{name}: reflectance must lie in [0, 1], got {r.min()}..{r.max()}")
    return r


def colour_of(spectra, cs, rec, op_backing):
    """Vectorised metrics of a batch of read spectra (..., channels, bands): CIELAB over
    black, over white and in transmission, TP, TP00, CR and OP."""
    r_b, r_w, tt = (spectra[..., i, :] for i in range(3))
    xyz_b, xyz_w, xyz_t = (cs.grid_to_XYZ(rec(s)) for s in (r_b, r_w, tt))
    lab_b, lab_w, lab_t = (cs.XYZ_to_Lab(x) for x in (xyz_b, xyz_w, xyz_t))
    lab_r = lab_b if op_backing == "black" else lab_w
    # a specimen that sends nothing back over white has no contrast ratio (0/0): left NaN,
    # which the finite check after the metrics reports by name
    with np.errstate(divide="ignore", invalid="ignore"):
        cr = xyz_b[..., 1] / xyz_w[..., 1]
    return {
        "lab_black": lab_b,
        "lab_white": lab_w,
        "lab_transmitted": lab_t,
        "tp": delta_e76(lab_b, lab_w),
        "tp00": delta_e00(lab_b, lab_w),
        "cr": cr,
        "op": np.hypot(lab_t[..., 1] - lab_r[..., 1], lab_t[..., 2] - lab_r[..., 2]),
    }


def _check_thickness(name: str, thickness) -> float:
    try:
        ok = not isinstance(thickness, bool) and float(thickness) > 0 and np.isfinite(thickness)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"{name} = {thickness!r}: must be a finite number > 0 [mm]")
    return float(thickness)


def read(specimen, bands=DEFAULT_BANDS, instrument=None, backing_black=None, backing_white=None,
         contact: float | None = None, photons: int = DEFAULT_PHOTONS, seed: int = 1,
         estimator: str = "weighted", illuminant: str = "D65", observer: str = "2",
         op_backing: str = "black", reconstruction: str = "hold", threads: int | None = None,
         progress: bool | None = False, precision: float | None = None,
         walks: str = "per-band", solver: str = reading.DEFAULT_SOLVER) -> DentalMetrics:
    """Colour metrics of a layered specimen as ``instrument`` reads it (see module doc).

    ``specimen``: a list of (material, thickness [mm]) from top to bottom; a material is a
    Material, a library name, a TOML file or ``FILE.toml:NAME``. ``instrument``: an
    :class:`dentalux.instrument.Instrument`, a preset name or a TOML file (None: the default
    instrument, :data:`dentalux.instrument.DEFAULT`, as ``dentalux shade``; ``'infinite'``
    for a laterally infinite disc over infinite areas). ``backing_black``,
    ``backing_white``, ``contact`` override the instrument's (None keeps them).
    ``photons`` per band and run; ``precision`` (a target standard error in ΔE00 units,
    :func:`photons_for_precision`) chooses them instead.
    ``walks``: 'per-band' (one walk per band) or 'shared' (every band of an instrument
    window from shared walks with a hero band per photon; :mod:`dentalux.reading.engine`).
    ``solver``: 'monte-carlo' (the slab walks), 'layered' (the deterministic solver,
    :mod:`dentalux.reading.layered`; ``photons`` then go to the walk that corrects for the
    specimen's rim) or 'auto' (layered where it holds).
    """
    limits.check_reading_args(photons, seed, reconstruction, threads, bands, contact)
    if precision is not None:
        kw = dict(bands=bands, instrument=instrument, backing_black=backing_black,
                  backing_white=backing_white, contact=contact, seed=seed,
                  estimator=estimator, illuminant=illuminant, observer=observer,
                  op_backing=op_backing, reconstruction=reconstruction, threads=threads,
                  walks=walks, solver=solver)
        photons, plan, pilot = _precision_plan(specimen, precision, **kw)
        # a reading without a Monte Carlo part (no rim walk) is its own pilot
        m = pilot if plan["noise_free"] else read(specimen, photons=photons,
                                                  progress=progress, **kw)
        m.precision = {**plan, "achieved": reading_precision(m)}
        return m
    if isinstance(specimen, (str, bytes)) or not hasattr(specimen, "__iter__"):
        raise ValueError(f"specimen = {specimen!r}: expected a list of (material, thickness)")
    parts = []
    for i, item in enumerate(specimen):
        try:
            material, thickness = item
        except (TypeError, ValueError):
            raise ValueError(f"specimen[{i}] = {item!r}: expected (material, thickness)") from None
        parts.append((_resolve_material(material), _check_thickness(f"specimen[{i}] thickness",
                                                                    thickness)))
    if not parts:
        raise ValueError("specimen: at least one layer is needed")
    inst = instruments.get(instrument)
    if contact is not None and not (float(contact) >= 1.0):
        raise ValueError(f"contact = {contact!r}: refractive index of the coupling medium >= 1")
    inst = inst.override(backing_black=backing_black, backing_white=backing_white,
                         contact_index=contact)
    if op_backing not in ("black", "white"):
        raise ValueError(f"op_backing = {op_backing!r}: allowed 'black' or 'white'")
    wl = resolve_bands(bands)
    for m, _ in parts:  # one band rule: the colour range and each material's data range
        known = getattr(m, "wavelength_nm", None)
        if known is not None and len(known):
            limits.check_bands_in(wl.tolist(), float(known[0]), float(known[-1]), m.name,
                                  "bands", extrapolate=bool(getattr(m, "extrapolate", False)))
    rb_black = backing_spectrum(inst.backing_black, wl, "backing_black")
    rb_white = backing_spectrum(inst.backing_white, wl, "backing_white")
    contact = inst.contact_index
    cs = system(illuminant, str(observer))
    rec = Reconstruction(wl, grid=cs.wavelengths, basis=reconstruction)
    spectra = reading.measure(reading.stacks(parts, wl), wl, inst, rb_black, rb_white,
                              photons, seed, estimator, threads, progress, walks, solver)
    out, errs, alone = spectra.propagate_parts(lambda b: colour_of(b, cs, rec, op_backing))
    stderr = _flat_stderr(errs)
    # the replicates' part alone, where a rim walk's zero count bounds the rest: the two
    # fall differently with photons (_precision_plan)
    replicate_stderr = _flat_stderr(alone) if spectra.rim_bounds else {}
    names = reading.CHANNELS
    spectra_out = {
        **{k: spectra.values[i] for i, k in enumerate(names)},
        **{f"{k}_stderr": spectra.stderr[i] for i, k in enumerate(names)},
    }
    if spectra.rim_bounds:  # the noise alone, which `fit --readings` weighs by (not in JSON)
        spectra_out.update({f"{k}_replicate_stderr": v
                            for k, v in zip(names, spectra.replicate_stderr(), strict=True)})
    if inst.is_infinite:
        spectra_out.update({k: spectra.extra[k] for k in reading.engine.ADDING_INPUTS})
        spectra_out.update({f"{k}_stderr": spectra.extra[f"{k}_stderr"]
                            for k in reading.engine.ADDING_INPUTS})
        edge_loss = {"black": 0.0, "white": 0.0}
    else:
        spectra_out.update(edge_loss_black=spectra.edge_loss[0],
                           edge_loss_white=spectra.edge_loss[1])
        edge_loss = {"black": float(spectra.edge_loss[0].mean()),
                     "white": float(spectra.edge_loss[1].mean())}
    # a NaN or inf reading (coefficients at the edge of their ranges) is an error, never a
    # number handed on
    check_finite({"values": out, "stderr": stderr}, "dental.read")
    return DentalMetrics(
        material=" / ".join(str(getattr(m, "name", "material")) for m, _ in parts),
        thickness=float(sum(t for _, t in parts)),
        lab_black=Lab(*out["lab_black"].tolist()),
        lab_white=Lab(*out["lab_white"].tolist()),
        lab_transmitted=Lab(*out["lab_transmitted"].tolist()),
        tp=float(out["tp"]),
        tp00=float(out["tp00"]),
        cr=float(out["cr"]),
        op=float(out["op"]),
        stderr=stderr,
        wavelengths_nm=wl.tolist(),
        spectra={k: np.asarray(v).tolist() for k, v in spectra_out.items()},
        photons=spectra.photons,
        seconds=spectra.extra["seconds"],
        cpu_seconds=spectra.cpu_seconds,
        method=spectra.method,
        fixed_cpu_seconds=float(spectra.extra.get("solver_cpu_seconds", 0.0)),
        instrument=inst.to_json(),
        edge_loss=edge_loss,
        layers=[{"material": str(getattr(m, "name", "material")), "thickness_mm": t}
                for m, t in parts],
        rim_bound=rim_note(spectra),
        replicate_stderr=replicate_stderr,
    )


def _flat_stderr(errs: dict) -> dict[str, float]:
    """Propagated standard errors under DentalMetrics.stderr's flat keys."""
    stderr = {k: float(errs[k]) for k in ("tp", "tp00", "cr", "op")}
    for key in ("lab_black", "lab_white", "lab_transmitted"):
        for j, c in enumerate("Lab"):
            stderr[f"{key}.{c}"] = float(errs[key][j])
    return stderr


def rim_note(spectra) -> dict:
    """Where the layered solver's rim walk saw no event (no photon brought light past the
    specimen's rim into the window) in a band and channel: ``{}`` if nowhere, else the
    photons it launched per band (one per engine.RIM_SHARE of the budget), those bands per
    channel, and what their standard error is."""
    zero = np.zeros(spectra.values.shape, dtype=bool)
    for b in spectra.rim_bounds:
        zero |= b.effect != 0
    if not zero.any():
        return {}
    launched = spectra.extra.get("rim_launched_per_band")
    wl = np.asarray(spectra.wavelengths_nm, dtype=float)
    return {"launched_per_band": launched,
            "bands_nm": {k: wl[zero[i]].tolist() for i, k in enumerate(reading.CHANNELS)},
            "note": f"no photon of the rim walk ({launched} launched per band) brought light "
                    "past the specimen's rim into the window in these bands: their standard "
                    "error is the bound from that zero count (the rule of three and the most "
                    "one photon can carry), not a spread between replicates"}


# photons per band of the pilot reading that sizes a run for a requested precision: 32
# batches of the core's smallest size (slab.rs MIN_BATCH, 256), so its standard error rests
# on 32 replicates (itself uncertain by about 13 %)
PILOT_PHOTONS = 8_192
# the pilot's seed is the reading's plus this, so the reading does not reuse its photons
PILOT_SEED_OFFSET = 7_919
# margin on the pilot's estimate of the photons needed (see PILOT_PHOTONS)
PRECISION_MARGIN = 1.2


def reading_precision(m: DentalMetrics, stderr: dict | None = None) -> float:
    """The reading's standard error in ΔE00 units: the larger of the colours over black and
    over white (:func:`dentalux.color.delta_e00_scale`); ``stderr``: other standard errors
    of the same reading (default ``m.stderr``)."""
    return max(_backing_precision(m, b, stderr) for b in ("black", "white"))


def _backing_precision(m: DentalMetrics, backing: str, stderr: dict | None = None) -> float:
    se = m.stderr if stderr is None else stderr
    return delta_e00_scale(getattr(m, f"lab_{backing}"),
                           [se[f"lab_{backing}.{c}"] for c in "Lab"])


def _photons_needed(pilot: DentalMetrics, target: float) -> int:
    """Photons per band that bring ``pilot``'s precision to ``target`` with the margin: the
    replicates' variance falls as 1 / photons; where a rim walk saw no event, the zero
    count's bound (sqrt(3) B / N) falls as 1 / photons^2 in variance."""
    if not pilot.replicate_stderr:
        p0 = reading_precision(pilot)
        return int(np.ceil(PILOT_PHOTONS * PRECISION_MARGIN * (p0 / target) ** 2))
    need = 0.0
    aim = target**2 / PRECISION_MARGIN
    for b in ("black", "white"):
        rep = _backing_precision(pilot, b, pilot.replicate_stderr) ** 2
        bound = max(_backing_precision(pilot, b) ** 2 - rep, 0.0)
        # x = PILOT_PHOTONS / photons solves rep x + bound x^2 = aim
        if bound > 0.0:
            x = (np.sqrt(rep**2 + 4.0 * bound * aim) - rep) / (2.0 * bound)
        else:
            x = aim / rep if rep > 0.0 else np.inf
        need = max(need, PILOT_PHOTONS / x)
    return int(np.ceil(need))


def check_precision(precision, name: str = "precision") -> float:
    """A target standard error in ΔE00 units: a finite number > 0."""
    try:
        ok = not isinstance(precision, bool) and float(precision) > 0 \
            and np.isfinite(float(precision))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"{name} = {precision!r} is out of range: allowed a finite number > 0 "
                         "(a standard error in ΔE00 units, e.g. 0.05)")
    return float(precision)


def photons_for_precision(specimen, precision, seed: int = 1, name: str = "precision",
                          **kw) -> tuple[int, dict]:
    """Photons per band that bring the reading's standard error (ΔE00 units, over black and
    over white) to ``precision``: a pilot reading of :data:`PILOT_PHOTONS` measures it, and
    the variance falls as 1/photons. A count over the slab ceiling or a run over
    :data:`dentalux.limits.MAX_READING_CPU_SECONDS` is refused before it starts, with the
    estimate. Returns the count and the plan (pilot numbers and estimates); where the pilot
    walked no photons (the layered solver on a laterally infinite specimen: no noise) the
    plan says ``noise_free``."""
    need, plan, _ = _precision_plan(specimen, precision, seed, name, **kw)
    return need, plan


def _precision_plan(specimen, precision, seed: int = 1, name: str = "precision",
                    **kw) -> tuple[int, dict, DentalMetrics]:
    """:func:`photons_for_precision`, and its pilot reading."""
    target = check_precision(precision, name)
    pilot = read(specimen, photons=PILOT_PHOTONS, seed=int(seed) + PILOT_SEED_OFFSET, **kw)
    if pilot.photons == 0:
        return PILOT_PHOTONS, {"requested": target, "noise_free": True, "pilot_photons": 0,
                               "pilot_precision": 0.0, "photons_per_band": 0,
                               "estimated_cpu_seconds": pilot.cpu_seconds}, pilot
    p0 = reading_precision(pilot)
    need = max(_photons_needed(pilot, target), PILOT_PHOTONS)
    fixed = pilot.fixed_cpu_seconds
    cpu = fixed + (pilot.cpu_seconds - fixed) * need / PILOT_PHOTONS
    plan = {"requested": target, "noise_free": False, "pilot_photons": PILOT_PHOTONS,
            "pilot_precision": p0,
            "photons_per_band": need, "estimated_cpu_seconds": cpu}
    if need > limits.MAX_SLAB_PHOTONS or cpu > limits.MAX_READING_CPU_SECONDS:
        raise ValueError(
            f"{name} = {target:g} ΔE00 would need about {need:.3g} photons per band "
            f"(about {cpu:.3g} CPU-s; the pilot of {PILOT_PHOTONS} read {p0:.3g}); allowed at "
            f"most {limits.MAX_SLAB_PHOTONS:.3g} photons and "
            f"{limits.MAX_READING_CPU_SECONDS:g} CPU-s: ask for a coarser precision")
    return need, plan, pilot


def metrics(material, thickness: float, bands=DEFAULT_BANDS, backing_black=None, backing_white=None,
            contact: float | None = None, photons: int = DEFAULT_PHOTONS, seed: int = 1,
            estimator: str = "weighted", illuminant: str = "D65", observer: str = "2",
            op_backing: str = "black", reconstruction: str = "hold", threads: int | None = None,
            progress: bool | None = False, instrument=None,
            precision: float | None = None, solver: str = reading.DEFAULT_SOLVER) -> DentalMetrics:
    """Colour metrics of a ``thickness`` [mm] disc of ``material`` (see module doc).

    ``material``: a Material (anything with ``.at(l)`` giving mua, mus, g, fd, n), a library
    name, a TOML file path (one material) or ``FILE.toml:NAME``. ``bands``: 'full'
    (380-780 nm every 10 nm), 'paper' or a list [nm]. ``photons`` per band and run.
    ``instrument``: None (:data:`dentalux.instrument.DEFAULT`, as ``dentalux shade``), a
    preset name (``'infinite'``: a laterally infinite disc on black 0 and white 0.9
    backings), a TOML file or an Instrument; ``backing_*`` and ``contact`` override it.
    ``reconstruction``: extrapolation basis outside the bands ('hold' or 'zero').
    """
    _check_thickness("thickness", thickness)
    return read([(material, thickness)], bands=bands, instrument=instrument,
                backing_black=backing_black, backing_white=backing_white, contact=contact,
                photons=photons, seed=seed, estimator=estimator, illuminant=illuminant,
                observer=observer, op_backing=op_backing, reconstruction=reconstruction,
                threads=threads, progress=progress, precision=precision, solver=solver)


MATCH_BACKING = "white"  # shade tabs are matched to the reading over the white backing


def shade(material, thickness: float = 1.0, against=None, instrument=None, match=None,
          specimen=None, **kw) -> dict:
    """The object ``dentalux shade --json`` prints: :meth:`DentalMetrics.to_json` (with
    ``instrument`` and ``edge_loss``), ΔE00/ΔTP00 and verdict against ``against``, and the
    nearest tabs of the shade guide ``match`` as ``shade_match``.

    ``instrument`` None is the command's default, :data:`dentalux.instrument.DEFAULT`.
    ``specimen``: a layered specimen [(material, thickness), ...] read instead of
    ``material`` at ``thickness`` (then ``against`` is read at the specimen's total
    thickness). ``kw``: the keyword arguments of :func:`read`.
    """
    inst = instruments.get(instruments.DEFAULT if instrument is None else instrument)
    kw.setdefault("progress", False)
    layers = specimen if specimen is not None else [(material, thickness)]
    m = read(layers, instrument=inst, **kw)
    out = m.to_json()
    if specimen is not None:
        out["layers"] = m.layers
    if against:
        ref = read([(against, m.thickness)], instrument=inst, **kw)
        cmp = compare(m, ref)
        out.update({k: cmp[k] for k in ("delta_e00", "delta_tp00", "verdict",
                                        "verdict_probability")})
        out["delta_e00_stderr"] = cmp["delta_e00_stderr"]
        out["delta_tp00_stderr"] = cmp["delta_tp00_stderr"]
    if match:
        from dentalux import shade_guides

        lab = getattr(m, f"lab_{MATCH_BACKING}")
        out["shade_match"] = [{"tab": tab, "delta_e00": float(de)}
                              for tab, de in shade_guides.nearest(lab, match)]
        out["shade_match_over"] = MATCH_BACKING
    return out


VERDICTS = ("imperceptible", "acceptable", "unacceptable")
# a verdict names every class within this many standard errors of the estimate (95 %)
VERDICT_SIGMAS = 2.0


def _classify(delta_e: float) -> str:
    if delta_e < PT:
        return VERDICTS[0]
    return VERDICTS[1] if delta_e <= AT else VERDICTS[2]


def verdict(delta_e: float, stderr: float = 0.0) -> str:
    """ΔE00 against the 50:50 % thresholds: imperceptible (< 0.8), acceptable (<= 1.8),
    unacceptable. With a standard error, every class that ΔE00 ± 2 s.e. reaches, joined by
    " or " (e.g. "imperceptible or acceptable"): a verdict never claims more than the
    estimate's precision allows."""
    lo, hi = delta_e - VERDICT_SIGMAS * stderr, delta_e + VERDICT_SIGMAS * stderr
    first, last = VERDICTS.index(_classify(max(lo, 0.0))), VERDICTS.index(_classify(hi))
    return " or ".join(VERDICTS[first:last + 1])


def verdict_probabilities(delta_e: float, stderr: float) -> dict:
    """Probability of each class for a normally distributed estimate ΔE00 ± s.e."""
    from scipy.stats import norm

    if stderr <= 0:
        return {v: float(v == _classify(delta_e)) for v in VERDICTS}
    below_pt = float(norm.cdf((PT - delta_e) / stderr))
    below_at = float(norm.cdf((AT - delta_e) / stderr))
    return {VERDICTS[0]: below_pt, VERDICTS[1]: below_at - below_pt, VERDICTS[2]: 1 - below_at}


def translucency_verdict(delta_tp00: float) -> str:
    """ΔTP00 against 0.62 / 2.62: imperceptible, acceptable, unacceptable."""
    if delta_tp00 < TPT:
        return "imperceptible"
    return "acceptable" if delta_tp00 <= TAT else "unacceptable"


def compare(sample: DentalMetrics, reference: DentalMetrics, backing: str = "white") -> dict:
    """ΔE00 (over the given backing) and ΔTP00 of ``sample`` against ``reference``."""
    if backing not in ("black", "white"):
        raise ValueError(f"backing = {backing!r}: allowed 'black' or 'white'")
    key = f"lab_{backing}"
    lab_s, lab_r = np.array(getattr(sample, key)), np.array(getattr(reference, key))
    de = float(delta_e00(lab_s, lab_r))
    dtp = float(abs(sample.tp00 - reference.tp00))
    # first-order error of ΔE00 from the six Lab standard errors (runs taken as independent)
    var = 0.0
    for lab, other, res, sign in ((lab_s, lab_r, sample, 0), (lab_r, lab_s, reference, 1)):
        for j, c in enumerate("Lab"):
            step = np.zeros(3)
            step[j] = 1e-4
            pair = (lab + step, other) if sign == 0 else (other, lab + step)
            d = (float(delta_e00(*pair)) - de) / 1e-4
            var += (d * res.stderr.get(f"{key}.{c}", 0.0)) ** 2
    se = float(np.sqrt(var))
    return {"delta_e00": de, "delta_tp00": dtp, "verdict": verdict(de, se),
            "verdict_probability": verdict_probabilities(de, se),
            "translucency_verdict": translucency_verdict(dtp),
            "delta_e00_stderr": se,
            "delta_tp00_stderr": float(np.hypot(sample.stderr["tp00"], reference.stderr["tp00"]))}
