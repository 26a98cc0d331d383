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
where they leave inside its window, so light that travels sideways is lost (edge loss), and
each backing is one run (plus one for the transmitted colour where the black backing is not
ideal or the disc is in optical contact). The ``infinite`` instrument is the adding formula
above, unchanged.

Metrics: CIELAB over black, over white and in transmission (the disc's total transmittance
for the normal beam, disc in air, against a perfect transmitter); TP = ΔE*ab(black, white);
TP00 = ΔE00(black, white); CR = Y_black / Y_white; OP = sqrt(Δa*² + Δb*²) between the
transmitted colour and the colour reflected over black. Monte Carlo standard errors are
propagated to every metric by the delta method (first-order, numerical derivatives with
respect to each band's R1, T1, R2, T2, T; the small within-run covariance of R and T is
neglected).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from dentalux import instrument as instruments
from dentalux import limits
from dentalux.color import delta_e00, delta_e76, system
from dentalux.progress import bar
from dentalux.slab import Layer, simulate
from dentalux.spectra import Reconstruction, resolve_bands

PT, AT = 0.8, 1.8  # ΔE00 50:50 % perceptibility / acceptability (Paravina et al. 2015)
TPT, TAT = 0.62, 2.62  # ΔTP00 50:50 % perceptibility / acceptability thresholds
JSON_KEYS = ("lab_black", "lab_white", "lab_transmitted", "tp", "tp00", "cr", "op",
             "instrument", "edge_loss")
DEFAULT_PHOTONS = 20_000
# the bands a reading integrates by default: 380-780 nm every 10 nm (spectra.full_bands)
DEFAULT_BANDS = "full"


@dataclass
class DentalMetrics:
    """Colour numbers of a disc, each scalar with its Monte Carlo standard error in ``stderr``."""

    material: str
    thickness: float
    lab_black: list[float]
    lab_white: list[float]
    lab_transmitted: list[float]
    tp: float
    tp00: float
    cr: float
    op: float
    stderr: dict[str, float]
    wavelengths_nm: list[float]
    spectra: dict[str, list[float]] = field(default_factory=dict)
    photons: int = 0
    seconds: float = 0.0
    instrument: dict = field(default_factory=dict)
    edge_loss: dict = field(default_factory=dict)
    layers: list = field(default_factory=list)

    def to_json(self) -> dict:
        """The ``dentalux shade --json`` keys."""
        d = asdict(self)
        return {k: d[k] for k in JSON_KEYS}


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


def over_backing(r1, t1, r2, t2, rb):
    """Reflectance of a disc on a Lambertian backing rb (adding formula, see module doc)."""
    return r1 + t1 * rb * t2 / (1.0 - rb * r2)


def _colour(r1, t1, r2, t2, tt, rb_black, rb_white, cs, rec, op_backing):
    """Vectorised metrics of the adding formula: inputs (..., bands) -> dict of arrays (...)."""
    r_b = over_backing(r1, t1, r2, t2, rb_black)
    r_w = over_backing(r1, t1, r2, t2, rb_white)
    return _colour_of(r_b, r_w, tt, cs, rec, op_backing)


def _colour_of(r_b, r_w, tt, cs, rec, op_backing):
    """Vectorised metrics from the readings over black, over white and in transmission."""
    xyz_b, xyz_w, xyz_t = (cs.grid_to_XYZ(rec(s)) for s in (r_b, r_w, tt))
    lab_b, lab_w, lab_t = (cs.XYZ_to_Lab(x) for x in (xyz_b, xyz_w, xyz_t))
    lab_r = lab_b if op_backing == "black" else lab_w
    return {
        "lab_black": lab_b,
        "lab_white": lab_w,
        "lab_transmitted": lab_t,
        "tp": delta_e76(lab_b, lab_w),
        "tp00": delta_e00(lab_b, lab_w),
        "cr": xyz_b[..., 1] / xyz_w[..., 1],
        "op": np.hypot(lab_t[..., 1] - lab_r[..., 1], lab_t[..., 2] - lab_r[..., 2]),
    }


def _propagate(colour, vals: np.ndarray, errs: np.ndarray) -> tuple[dict, dict]:
    """Metrics of ``vals`` (inputs × bands) and their standard errors by the delta method:
    ``colour`` evaluated on a batch holding ``vals`` and each input of each band moved by h."""
    h = 1e-6
    n_in = vals.size
    batch = np.broadcast_to(vals, (1 + n_in,) + vals.shape).copy()
    idx = np.arange(n_in)
    batch.reshape(1 + n_in, -1)[1 + idx, idx] += h
    out = colour(batch)
    sig = errs.ravel()
    stderr = {}
    for key in ("tp", "tp00", "cr", "op"):
        d = (out[key][1:] - out[key][0]) / h
        stderr[key] = float(np.sqrt(np.sum((d * sig) ** 2)))
    for key in ("lab_black", "lab_white", "lab_transmitted"):
        d = (out[key][1:] - out[key][0]) / h
        for j, c in enumerate("Lab"):
            stderr[f"{key}.{c}"] = float(np.sqrt(np.sum((d[:, j] * sig) ** 2)))
    return {key: value[0] for key, value in out.items()}, stderr


def _check_thickness(name: str, thickness) -> float:
    try:
        ok = not isinstance(thickness, bool) and float(thickness) > 0 and np.isfinite(thickness)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"{name} = {thickness!r}: must be a finite number > 0 [mm]")
    return float(thickness)


def _stack(specimen, lam: float) -> list[Layer]:
    return [Layer(mua=float(o.mua), mus=float(o.mus), g=float(o.g), n=float(o.n),
                  thickness=t, fd=float(o.fd))
            for o, t in ((m.at(float(lam)), t) for m, t in specimen)]


def _infinite_runs(specimen, wl, contact, photons, seed, estimator, threads, progress):
    """R1, T1 (beam from above), R2, T2 (diffuse from below, the stack flipped) and the
    transmittance in air per band, with standard errors: the adding formula's inputs."""
    n_below = 1.0 if contact is None else float(contact)
    runs = 2 if contact is None else 3
    vals = np.zeros((5, len(wl)))
    errs = np.zeros((5, len(wl)))
    with bar(len(wl) * runs, "bands", progress) as cb:
        for k, lam in enumerate(wl):
            stack = _stack(specimen, lam)
            common = dict(n_photons=int(photons), estimator=estimator, threads=threads)
            a = simulate(stack, seed=seed, band=k, n_above=1.0, n_below=n_below, **common)
            b = simulate(stack[::-1], seed=seed, band=100_000 + k, n_above=n_below,
                         n_below=1.0, incidence="diffuse", **common)
            c = a
            if contact is not None:
                c = simulate(stack, seed=seed, band=200_000 + k, **common)
            for i, (res, key) in enumerate(((a, "total_reflectance"), (a, "total_transmittance"),
                                            (b, "total_reflectance"), (b, "total_transmittance"),
                                            (c, "total_transmittance"))):
                vals[i, k] = getattr(res, key)
                errs[i, k] = res.stderr[key]
            if cb:
                cb((k + 1) * runs)
    return vals, errs, runs


def _windowed_runs(specimen, wl, inst, rb_black, rb_white, contact, photons, seed, estimator,
                   threads, progress):
    """The instrument's readings over black, over white and in transmission per band, with
    standard errors, and the edge loss (outside the window + rim) of each backing run."""
    n_below = 1.0 if contact is None else float(contact)
    incidence = inst.spec.incidence
    extra_t = contact is not None or bool(np.any(rb_black > 0))
    runs = 3 if extra_t else 2
    vals = np.zeros((3, len(wl)))
    errs = np.zeros((3, len(wl)))
    loss = np.zeros((2, len(wl)))
    f = inst.white_fraction()
    with bar(len(wl) * runs, "bands", progress) as cb:
        for k, lam in enumerate(wl):
            stack = _stack(specimen, lam)
            common = dict(n_photons=int(photons), estimator=estimator, threads=threads,
                          seed=seed, incidence=incidence, n_above=1.0)
            for i, (rb, band) in enumerate(((rb_black[k], k), (rb_white[k], 100_000 + k))):
                res = simulate(stack, band=band, n_below=n_below, window=inst.window(rb),
                               **common)
                vals[i, k], errs[i, k] = inst.reading(res.window, res.window_stderr)
                loss[i, k] = res.window["outside_reflectance"] + res.window["rim_loss"]
                if i == 0:
                    t_run = res
            if extra_t:
                t_run = simulate(stack, band=200_000 + k, n_below=1.0,
                                 window=inst.window(0.0), **common)
            vals[2, k] = t_run.window["viewed_transmittance"] / f
            errs[2, k] = t_run.window_stderr["viewed_transmittance"] / f
            if cb:
                cb((k + 1) * runs)
    return vals, errs, loss, runs


def read(specimen, bands=DEFAULT_BANDS, instrument=None, backing_black=None, backing_white=None,
         contact: float | None = None, photons: int = DEFAULT_PHOTONS, seed: int = 1,
         estimator: str = "weighted", illuminant: str = "D65", observer: str = "2",
         op_backing: str = "black", reconstruction: str = "hold", threads: int | None = None,
         progress: bool | None = False) -> DentalMetrics:
    """Colour metrics of a layered specimen as ``instrument`` reads it (see module doc).

    ``specimen``: a list of (material, thickness [mm]) from top to bottom; a material is a
    Material, a library name, a TOML file or ``FILE.toml:NAME``. ``instrument``: an
    :class:`dentalux.instrument.Instrument`, a preset name or a TOML file (None: the
    ``infinite`` geometry). ``backing_black``, ``backing_white``, ``contact`` override the
    instrument's (None keeps them). ``photons`` per band and run.
    """
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
    start = time.perf_counter()
    if inst.is_infinite:
        vals, errs, runs = _infinite_runs(parts, wl, contact, photons, seed, estimator,
                                          threads, progress)
        out, stderr = _propagate(
            lambda b: _colour(*(b[:, i] for i in range(5)), rb_black, rb_white, cs, rec,
                              op_backing), vals, errs)
        names = ("r1", "t1", "r2", "t2", "transmitted")
        spectra = {
            **{k: vals[i] for i, k in enumerate(names)},
            **{f"{k}_stderr": errs[i] for i, k in enumerate(names)},
            "over_black": over_backing(*vals[:4], rb_black),
            "over_white": over_backing(*vals[:4], rb_white),
        }
        edge_loss = {"black": 0.0, "white": 0.0}
    else:
        vals, errs, loss, runs = _windowed_runs(parts, wl, inst, rb_black, rb_white, contact,
                                                photons, seed, estimator, threads, progress)
        out, stderr = _propagate(
            lambda b: _colour_of(b[:, 0], b[:, 1], b[:, 2], cs, rec, op_backing), vals, errs)
        names = ("over_black", "over_white", "transmitted")
        spectra = {
            **{k: vals[i] for i, k in enumerate(names)},
            **{f"{k}_stderr": errs[i] for i, k in enumerate(names)},
            "edge_loss_black": loss[0],
            "edge_loss_white": loss[1],
        }
        edge_loss = {"black": float(loss[0].mean()), "white": float(loss[1].mean())}
    seconds = time.perf_counter() - start
    return DentalMetrics(
        material=" / ".join(str(getattr(m, "name", "material")) for m, _ in parts),
        thickness=float(sum(t for _, t in parts)),
        lab_black=out["lab_black"].tolist(),
        lab_white=out["lab_white"].tolist(),
        lab_transmitted=out["lab_transmitted"].tolist(),
        tp=float(out["tp"]),
        tp00=float(out["tp00"]),
        cr=float(out["cr"]),
        op=float(out["op"]),
        stderr=stderr,
        wavelengths_nm=wl.tolist(),
        spectra={k: np.asarray(v).tolist() for k, v in spectra.items()},
        photons=int(photons) * runs * len(wl),
        seconds=seconds,
        instrument=inst.to_json(),
        edge_loss=edge_loss,
        layers=[{"material": str(getattr(m, "name", "material")), "thickness_mm": t}
                for m, t in parts],
    )


def metrics(material, thickness: float, bands=DEFAULT_BANDS, backing_black=None, backing_white=None,
            contact: float | None = None, photons: int = DEFAULT_PHOTONS, seed: int = 1,
            estimator: str = "weighted", illuminant: str = "D65", observer: str = "2",
            op_backing: str = "black", reconstruction: str = "hold", threads: int | None = None,
            progress: bool | None = False, instrument=None) -> DentalMetrics:
    """Colour metrics of a ``thickness`` [mm] disc of ``material`` (see module doc).

    ``material``: a Material (anything with ``.at(l)`` giving mua, mus, g, fd, n), a library
    name, a TOML file path (one material) or ``FILE.toml:NAME``. ``bands``: 'full'
    (380-780 nm every 10 nm), 'paper' or a list [nm]. ``photons`` per band and run.
    ``instrument``: None (the ``infinite`` geometry, black 0 and white 0.9 backings), a
    preset name, a TOML file or an Instrument; ``backing_*`` and ``contact`` override it.
    ``reconstruction``: extrapolation basis outside the bands ('hold' or 'zero').
    """
    _check_thickness("thickness", thickness)
    return read([(material, thickness)], bands=bands, instrument=instrument,
                backing_black=backing_black, backing_white=backing_white, contact=contact,
                photons=photons, seed=seed, estimator=estimator, illuminant=illuminant,
                observer=observer, op_backing=op_backing, reconstruction=reconstruction,
                threads=threads, progress=progress)


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
        out.update({k: cmp[k] for k in ("delta_e00", "delta_tp00", "verdict")})
        out["delta_e00_stderr"] = cmp["delta_e00_stderr"]
    if match:
        from dentalux import shade_guides

        lab = getattr(m, f"lab_{MATCH_BACKING}")
        out["shade_match"] = [{"tab": tab, "delta_e00": float(de)}
                              for tab, de in shade_guides.nearest(lab, match)]
        out["shade_match_over"] = MATCH_BACKING
    return out


def verdict(delta_e: float) -> str:
    """ΔE00 against the 50:50 % thresholds: imperceptible (< 0.8), acceptable (<= 1.8),
    unacceptable."""
    if delta_e < PT:
        return "imperceptible"
    return "acceptable" if delta_e <= AT else "unacceptable"


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
    return {"delta_e00": de, "delta_tp00": dtp, "verdict": verdict(de),
            "translucency_verdict": translucency_verdict(dtp),
            "delta_e00_stderr": float(np.sqrt(var)),
            "delta_tp00_stderr": float(np.hypot(sample.stderr["tp00"], reference.stderr["tp00"]))}
