"""Can one enamel and one dentin read as three instruments read teeth? (issue 40, item 2)

An exploration, not a default: nothing here changes materials.toml or any preset. It fits
the two tissues' smooth spectra at once to three published readings, each through its own
instrument preset and the deterministic layered solver (``dental.read(solver="layered")``):

- (a) Yu, Ahn & Lee 2009: TP of 1 mm human enamel and dentin through a 3 mm window
  (tooth_measurements.csv), read by ``contact-probe-3mm`` as ``m.tp``;
- (b) Wee et al. 2023 (45:0), read by ``45-0`` on the natural incisor's labial middle third
  (enamel 0.9 / dentin 2.9 / enamel 0.6 mm, over the preset's white backing, as
  ``dentalux instruments validate`` reads it);
- (c) the clinical contact-probe class (Oh et al. 2022, SD borrowed from Wee et al.;
  instrument_classes.toml), read by ``contact-probe-3mm`` on the same stack.

Residuals are (reading - mean) / sd: the published between-tooth SD for (b) and (c); Yu et
al. give no SD in the abstract, so TP gets an assumed sd of 2, half the 15-19 range that Lee's
review gives for 1 mm enamel (tooth_measurements.csv, rows lee2016rde-*).

Spectral models (g, fd and n stay those of the default tissues, from the literature):

- ``current``: the defaults' shapes refitted, μs = f x default μs(λ), μa = a (λ/700)^-p;
- ``flat``:    μs' = (1 - g) μs flat in λ, μa a power law as above;
- ``slope``:   μs' = s (λ/550)^-b with b free (b < 0: μs' rises towards red), μa as above.

The Jacobian uses that every band is read independently: a reading's spectra at band i depend
only on the tissues' μa, μs at band i, so one extra reading per tissue and coefficient (all
bands perturbed together) gives every band's derivative, and the chain rule to the spectral
parameters and through the colour computation does the rest. The fit runs the solver with
5 nodes per interval and 10 Legendre moments (its defaults: 8 and 16) and without the contact
probe's 10 mm rim, whose Monte Carlo correction (the only noise) is added as a fixed defect
correction renewed once; every table reads through the presets themselves, and two fits are
re-read with the solver's defaults at 8 and 16 bands.

    python python/dentalux/data/fit_tissues_joint.py                  # the note's runs
    python python/dentalux/data/fit_tissues_joint.py slope             # one fit, all readings
    python python/dentalux/data/fit_tissues_joint.py current tp,45-0   # one fit, some readings
    python python/dentalux/data/fit_tissues_joint.py current tp,45-0,contact 4  # from mus x 4

The note's runs took 12 minutes wall (21 CPU-minutes) on the shared 2-core development
machine; docs/notes/2026-12-07-joint-tissue-fit.md reports their output.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import functools
import hashlib
import sys
from pathlib import Path

import numpy as np
from dentalux import dental, instrument_classes, materials
from dentalux import instrument as instruments
from dentalux.color import system
from dentalux.reading import engine, layered
from dentalux.reading.layered import operators as ops
from dentalux.reading.layered import stack as layered_stack
from dentalux.spectra import Reconstruction
from scipy.optimize import least_squares

DATA = Path(__file__).parent
FIT_BANDS = np.linspace(400.0, 700.0, 8)
CHECK_BANDS = np.arange(400.0, 701.0, 20.0)
PHOTONS, SEED = 2000, 1  # the contact probe's rim walk (the only noise); common random numbers
CONTACT, NONCONTACT = "contact-probe-3mm", "45-0"
STACK = (("enamel", 0.9), ("dentin", 2.9), ("enamel", 0.6))  # design.render.NATURAL_STACK
TISSUES = ("enamel", "dentin")
LOG_STEP = 0.05  # per-band perturbation of log μa, log μs for the Jacobian


# ---------------------------------------------------------------------------------- targets

def targets() -> list[tuple[str, float, float]]:
    """[(name, mean, sd)] in residual order, every number read from the data files."""
    with open(DATA / "tooth_measurements.csv", newline="") as f:
        rows = {r["id"]: r for r in csv.DictReader(f)}
    lo, hi = (float(rows[f"lee2016rde-enamel-human-1mm-tp-{e}"]["value"]) for e in ("low", "high"))
    sd_tp = (hi - lo) / 2  # assumed: Yu et al. give no SD in the abstract
    out = [(f"TP {t} 1 mm (Yu 2009, {CONTACT})",
            float(rows[f"yu2009-{t}-human-1mm-3mm"]["value"]), sd_tp) for t in TISSUES]
    cls = instrument_classes.classes()
    for label, klass in (("Wee 2023, 45-0", "noncontact-45-0"),
                         ("Oh 2022, contact probe", "clinical-contact-probe")):
        pub = cls[klass]["published"]
        out += [(f"{c}* ({label})", m, s) for c, m, s in zip("Lab", pub["mean"], pub["sd"],
                                                             strict=True)]
    return out


# ------------------------------------------------------------------------- spectral models

MODELS = {"current": ("log f", "log mua700", "p"),
          "flat": ("log mus'", "log mua700", "p"),
          "slope": ("log mus'550", "b", "log mua700", "p")}


def optics(model: str, theta, bands) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{tissue: (μa, μs) at ``bands``} for the parameters ``theta`` (enamel's, then dentin's)."""
    k = len(MODELS[model])
    out = {}
    for i, t in enumerate(TISSUES):
        x = theta[i * k:(i + 1) * k]
        base = materials.get(t).at(bands)
        mua = np.exp(x[-2]) * (bands / 700.0) ** -x[-1]
        if model == "current":
            mus = np.exp(x[0]) * base.mus
        else:
            slope = 0.0 if model == "flat" else x[1]
            mus = np.exp(x[0]) * (bands / 550.0) ** -slope / (1 - (1 - base.fd) * base.g)
        out[t] = (mua, mus)
    return out


def start(model: str, scatter: float = 1.0) -> np.ndarray:
    """The default tissues expressed in ``model`` (μs' at 550 nm where μs' is a parameter),
    both scattering coefficients times ``scatter``."""
    x = []
    for t in TISSUES:
        o = materials.get(t).at(np.array([400.0, 550.0, 700.0]))
        p = np.log(o.mua[0] / o.mua[2]) / np.log(700 / 400)
        mua = [np.log(o.mua[2]), p]
        msr = np.log(scatter * o.mus[1] * (1 - (1 - o.fd[1]) * o.g[1]))
        x += {"current": [np.log(scatter)], "flat": [msr], "slope": [msr, 0.0]}[model] + mua
    return np.array(x)


def material(tissue: str, mua, mus, bands) -> materials.Material:
    base = materials.get(tissue)
    o = base.at(bands)
    return materials.Material(
        name=f"{tissue}@joint-trial", wavelength_nm=np.asarray(bands, float), mua=mua, mus=mus,
        g=o.g, fd=o.fd, n=o.n, extrapolate=True, material_class="tissue",
        provenance={"kind": "fitted", "source": "fit_tissues_joint.py trial"})


# -------------------------------------------------------------------------------- readings

@contextlib.contextmanager
def solver_settings(per_interval: int | None, order: int | None):
    """The layered solver with fewer direction nodes and moments (None: its defaults)."""
    if per_interval is None:
        yield
        return
    saved = layered.responses, ops.layer, ops.add
    layered.responses = functools.partial(layered_stack.responses, per_interval=per_interval,
                                          order=order)
    ops.layer, ops.add = _memo(ops.layer), _memo(ops.add)
    engine._SOLVED.clear()  # its cache does not key on the settings
    try:
        yield
    finally:
        layered.responses, ops.layer, ops.add = saved
        engine._SOLVED.clear()


def _memo(func, size: int = 64):
    """``func`` remembering its last ``size`` results by the content of its arguments: the
    two stack readings (contact probe, 45-0) share every layer and addition; only the
    detector cone and the window differ. Speed only: the numbers are the same."""
    cache: dict = {}

    def digest(x, h):
        if isinstance(x, np.ndarray):
            h.update(str((x.shape, x.dtype)).encode())
            h.update(np.ascontiguousarray(x).tobytes())
        elif isinstance(x, (tuple, list)):
            for y in x:
                digest(y, h)
        elif dataclasses.is_dataclass(x):
            digest([getattr(x, f.name) for f in dataclasses.fields(x)], h)
        else:
            h.update(repr(x).encode())

    def wrapped(*args):
        h = hashlib.blake2b()
        digest(args, h)
        key = h.digest()
        if key not in cache:
            if len(cache) >= size:
                cache.pop(next(iter(cache)))
            cache[key] = func(*args)
        return cache[key]

    return wrapped


#: residual rows of each group of readings (targets() order)
ROWS = {"tp": (0, 1), "45-0": (2, 3, 4), "contact": (5, 6, 7)}
READINGS = {"tp_enamel": ((("enamel", 1.0),), CONTACT),
            "tp_dentin": ((("dentin", 1.0),), CONTACT),
            "45-0": (STACK, NONCONTACT), "contact": (STACK, CONTACT)}


def read_spectra(key: str, opt: dict, bands, instrument=None, unbounded=False) -> np.ndarray:
    """(3 channels: over black, over white, transmitted; bands) read for ``key``; with
    ``unbounded`` the specimen has no rim (no Monte Carlo walk: no noise)."""
    layers, inst = READINGS[key]
    inst = instruments.get(instrument or inst)
    if unbounded:
        inst = dataclasses.replace(inst, specimen_diameter_mm=None, name=f"{inst.name}+unbounded")
    mats = {t: material(t, *opt[t], bands) for t in TISSUES}
    m = dental.read([(mats[t], d) for t, d in layers], instrument=inst,
                    solver="layered", bands=list(bands), photons=PHOTONS, seed=SEED)
    return np.array([m.spectra[c] for c in ("over_black", "over_white", "transmitted")])


@functools.cache
def _colour(bands: tuple):
    cs = system("D65", "2")
    return cs, Reconstruction(np.array(bands), grid=cs.wavelengths, basis="hold")


def values(spectra: dict, bands) -> np.ndarray:
    """The eight readings in targets() order from the readings' spectra (NaN where unread)."""
    cs, rec = _colour(tuple(bands))
    out = np.full(8, np.nan)
    for k, s in spectra.items():
        c = dental.colour_of(s, cs, rec, "black")
        if k.startswith("tp_"):
            out[ROWS["tp"][TISSUES.index(k[3:])]] = c["tp"]
        else:
            out[list(ROWS[k])] = c["lab_white"]
    return out


class Fit:
    """Residuals and their Jacobian for one model; ``keys`` picks the readings fitted."""

    def __init__(self, model: str, use=("tp", "45-0", "contact"), bands=FIT_BANDS):
        self.model, self.bands, self.targets = model, bands, targets()
        self.rows = [i for u in use for i in ROWS[u]]
        self.keys = [k for k in READINGS if k in use or (k.startswith("tp") and "tp" in use)]
        self.mean = np.array([m for _, m, _ in self.targets])
        self.sd = np.array([s for _, _, s in self.targets])
        self._cache: dict = {}
        self.rim = {k: 0.0 for k in self.keys}  # what the specimen's rim takes (spectra)

    def spectra(self, theta) -> dict:
        """The readings without a rim (deterministic) plus the rim's last correction."""
        key = tuple(np.round(theta, 12))
        if key not in self._cache:
            opt = optics(self.model, theta, self.bands)
            self._cache = {key: {k: read_spectra(k, opt, self.bands, unbounded=True)
                                 for k in self.keys}}
        return {k: v + self.rim[k] for k, v in self._cache[key].items()}

    def correct_rim(self, theta) -> None:
        """The rim correction at ``theta``: the preset's reading (its rim by a Monte Carlo
        walk) less the reading without a rim; held fixed while the fit runs."""
        opt = optics(self.model, theta, self.bands)
        bare = {k: read_spectra(k, opt, self.bands, unbounded=True) for k in self.keys}
        for k in self.keys:
            self.rim[k] = read_spectra(k, opt, self.bands) - bare[k]
        moved = values({k: bare[k] + self.rim[k] for k in self.keys}, self.bands) - values(
            bare, self.bands)
        print(f"    rim correction (preset less unbounded specimen): "
              f"{np.round(moved[self.rows], 2).tolist()}", flush=True)

    def residuals(self, theta) -> np.ndarray:
        r = self._scaled(self.spectra(theta))
        print(f"    [{self.model}] sum of squares {np.sum(r ** 2):9.3f} at "
              f"{np.round(theta, 3).tolist()}", flush=True)
        return r

    def _scaled(self, spectra: dict) -> np.ndarray:
        return ((values(spectra, self.bands) - self.mean) / self.sd)[self.rows]

    def jacobian(self, theta) -> np.ndarray:
        s0, opt = self.spectra(theta), optics(self.model, theta, self.bands)
        # per band: d spectra / d log(μa or μs of a tissue), one reading each
        local = {}
        for t in TISSUES:
            for j in (0, 1):
                bumped = dict(opt)
                q = list(opt[t])
                q[j] = q[j] * np.exp(LOG_STEP)
                bumped[t] = tuple(q)
                for k in self.keys:  # the stack's two readings one after the other (_memo)
                    if t in {t for t, _ in READINGS[k][0]}:
                        local[k, t, j] = (read_spectra(k, bumped, self.bands, unbounded=True)
                                          + self.rim[k] - s0[k]) / LOG_STEP
        # d log q / d theta (analytic models, differenced), then the chain rule per band
        eps, cols = 1e-6, []
        for n in range(len(theta)):
            step = np.array(theta, float)
            step[n] += eps
            opt1 = optics(self.model, step, self.bands)
            ds = {}
            for k in self.keys:
                ds[k] = sum(local[k, t, j] * (np.log(opt1[t][j]) - np.log(opt[t][j])) / eps
                            for (kk, t, j) in local if kk == k)
            delta = 1e-4
            moved = {k: s0[k] + delta * ds[k] for k in self.keys}
            cols.append((self._scaled(moved) - self._scaled(s0)) / delta)
        return np.array(cols).T

    def run(self, x0, max_nfev=(20, 6)):
        """Least squares on the readings without a rim plus a fixed rim correction, the
        correction renewed at each round's end point (a defect correction)."""
        # bounds: exponents -6..15, μa(700 nm) 1e-5..10 /mm, μs' (or the factor) 1e-5..100
        names = MODELS[self.model] * 2
        lo = np.array([-6.0 if n in ("p", "b") else np.log(1e-5) for n in names])
        hi = np.array([15.0 if n in ("p", "b") else np.log(10.0 if "mua" in n else 100.0)
                       for n in names])
        x = np.asarray(x0, float)
        with solver_settings(5, 10):
            for nfev in max_nfev:  # a round per entry, the rim renewed before each
                self.correct_rim(x)
                res = least_squares(self.residuals, x, jac=self.jacobian, bounds=(lo, hi),
                                    x_scale="jac", max_nfev=nfev, ftol=1e-3, xtol=1e-3)
                print(f"    round: {res.nfev} evaluations, status {res.status}, "
                      f"{res.message}", flush=True)
                x = res.x
        return res


def describe(model: str, theta) -> str:
    """The parameters and the coefficients they give at 400 / 550 / 700 nm."""
    k, lam, parts = len(MODELS[model]), np.array([400.0, 550.0, 700.0]), []
    opt = optics(model, theta, lam)
    for i, t in enumerate(TISSUES):
        o = materials.get(t).at(lam)
        mua, mus = opt[t]
        names = ", ".join(f"{n} {v:.4g}" for n, v in zip(MODELS[model], theta[i * k:(i + 1) * k],
                                                         strict=True))
        parts.append(f"{t}: {names} | mua 400/550/700 {np.round(mua, 4).tolist()} /mm, "
                     f"mus' {np.round(mus * (1 - (1 - o.fd) * o.g), 3).tolist()} /mm")
    return "\n  ".join(parts)


def table(fit: Fit, theta, bands=FIT_BANDS, settings=(5, 10)) -> np.ndarray:
    """Print every reading, target and scaled residual at ``theta``; return the residuals."""
    with solver_settings(*settings):
        opt = optics(fit.model, theta, bands)
        spectra = {k: read_spectra(k, opt, bands) for k in READINGS}
    vals = values(spectra, bands)
    res = (vals - fit.mean) / fit.sd
    for (name, mean, sd), v, r in zip(fit.targets, vals, res, strict=True):
        print(f"  {name:42s} read {v:7.2f}  target {mean:6.2f} +- {sd:4.1f}  residual {r:+6.2f}")
    print(f"  sum of squares {np.sum(res ** 2):.2f}")
    # Yu et al.: translucency rises with wavelength (abstract); R_white - R_black per band
    for t in TISSUES:
        d = spectra[f"tp_{t}"][1] - spectra[f"tp_{t}"][0]
        print(f"  1 mm {t}: R_white - R_black {d[0]:.3f} at {bands[0]:g} nm, {d[-1]:.3f} at "
              f"{bands[-1]:g} nm")
    return res


def fit(model: str, use=("tp", "45-0", "contact"), x0=None) -> np.ndarray:
    """Fit ``model`` to the readings ``use`` from ``x0`` (None: the default tissues); print
    the parameters and all eight residuals (those not fitted too)."""
    f = Fit(model, use)
    res = f.run(start(model) if x0 is None else x0)
    print(f"\n== {model}, fitted to {' + '.join(use)}: {res.nfev} evaluations, "
          f"status {res.status}\n  {describe(model, res.x)}")
    table(f, res.x)
    return res.x


def scan(factors=(1.0, 2.0, 4.0, 8.0, 16.0)) -> None:
    """The default tissues with both μs multiplied by each factor: the two stack readings
    and the two TPs (why the contact probe and the TPs pull apart)."""
    print("\n== the default tissues, both mus x factor: TP enamel, TP dentin | 45-0 L*a*b* | "
          "contact L*a*b*")
    with solver_settings(5, 10):
        for f in factors:
            x = start("current")
            x[0] = x[3] = np.log(f)
            opt = optics("current", x, FIT_BANDS)
            v = values({k: read_spectra(k, opt, FIT_BANDS) for k in READINGS}, FIT_BANDS)
            print(f"  x{f:<4g} TP {v[0]:5.2f} {v[1]:5.2f} | 45-0 {np.round(v[2:5], 2).tolist()}"
                  f" | contact {np.round(v[5:], 2).tolist()}", flush=True)


def geometry(model: str, theta, diameters=((2, 2), (3, 3), (4, 4), (6, 6), (10, 10), (3, 6),
                                          (3, 10))) -> None:
    """The contact probe's reading of the stack, and the 1 mm TPs, with other lit / viewed
    diameters (the preset's are assumed), at ``theta``."""
    probe = instruments.get(CONTACT)
    opt = optics(model, theta, FIT_BANDS)
    print(f"\n== {model}: {CONTACT} with other lit / viewed diameters [mm]")
    with solver_settings(5, 10):
        for lit, view in diameters:
            inst = probe.override(illuminated_diameter_mm=float(lit),
                                  viewed_diameter_mm=float(view))
            s = {k: read_spectra(k, opt, FIT_BANDS, inst) for k in
                 ("tp_enamel", "tp_dentin", "contact")}
            v = values(s, FIT_BANDS)
            print(f"  lit {lit:>2} / viewed {view:>2}: stack L*a*b* "
                  f"{np.round(v[5:], 2).tolist()}, TP enamel {v[0]:.2f}, dentin {v[1]:.2f}")


if __name__ == "__main__":
    # python fit_tissues_joint.py [MODEL [GROUP,GROUP [SCATTER]]]: one fit (from the default
    # tissues with both μs times SCATTER); no argument: the note's runs
    if len(sys.argv) > 1:
        use = tuple(sys.argv[2].split(",")) if len(sys.argv) > 2 else ("tp", "45-0", "contact")
        scatter = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0
        fit(sys.argv[1], use, start(sys.argv[1], scatter))
        sys.exit(0)
    print("== the default tissues (enamel@fitted-yu2009, dentin@fitted-wee2023)")
    table(Fit("current"), start("current"))
    scan()
    current = fit("current")
    fit("current", x0=start("current", 4.0))  # another start: both μs x 4
    fit("flat")
    best = fit("slope")
    for use in (("tp", "45-0"), ("tp", "contact"), ("45-0", "contact")):
        fit("current", use)
    fit("slope", ("tp", "contact"))
    for model, theta in (("current", current), ("slope", best)):
        print(f"\n== {model}, all readings: re-read with the solver's defaults, 8 and 16 bands")
        table(Fit(model), theta, FIT_BANDS, (None, None))
        table(Fit(model), theta, CHECK_BANDS, (None, None))
        geometry(model, theta)
