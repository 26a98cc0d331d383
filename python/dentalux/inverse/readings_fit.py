"""Fit μa(λ), μs(λ) of a material to a lab's instrument readings (``dentalux fit --readings``).

Two forward models of the same readings (:mod:`dentalux.readings`,
:mod:`dentalux.inverse.readings_model`):

- ``mc``: the reading engine (:func:`dentalux.dental.read`) through the instrument model,
  edge loss included, with one of its solvers (``solver``, :data:`SOLVERS`): 'auto' (the
  default) reads with the layered solver wherever the instrument's beam is normal and with
  the Monte Carlo walks elsewhere (d/8). The layered solver's only noise is its Monte Carlo
  correction for the disc's rim; the walks' is all of it. Every evaluation uses the same seed
  (common random numbers), so that noise is a fixed, smooth error of the model rather than a
  jitter that stalls the optimiser. The model's error (the standard error and, with the
  layered solver, its stated accuracy ``stack.ACCURACY``) weighs the residuals and is
  reported beside them (``mc_stderr_de00``).
- ``km``: Kubelka–Munk with the Saunderson correction, the field's baseline. A disc of
  thickness X on a backing of reflectance R_g has, with a = 1 + K/S, b = sqrt(a² − 1),
  R = (1 − R_g (a − b coth bSX)) / (a − R_g + b coth bSX) inside its faces; the faces add
  R_m = k1 + (1 − k1)(1 − k2) R / (1 − k2 R) (k1 the normal Fresnel reflectance: its own
  term only where the geometry includes the specular reflection, the entering light's
  1 − k1 always; k2 the diffuse internal
  reflectance, :func:`dentalux.inverse.models.boundary.moments`). The backing's R_g is the
  instrument's, used as it is. K and S map to the transport coefficients as in
  :mod:`dentalux.inverse.models.km`: K = 2 μa, S = (3/4) μs (1 − g). Kubelka–Munk knows no
  window, so it ignores edge loss.

Parameters: for spectral readings, log μa and log μs per band (the bands are independent,
so one perturbed evaluation gives every band's derivative); for CIELAB-only readings a smooth
five-parameter spectrum, log μa(λ) = c0 + c1 x + c2 x², log μs(λ) = s0 − b ln(λ/550 nm),
x = (λ − 550 nm)/100 nm, fitted on :data:`LAB_BANDS`. Levenberg–Marquardt with
finite-difference Jacobians, started from the Kubelka–Munk fit.

The ``mc`` model is not called at every step. A reading depends on the band only through the
material (the backings and n are the same in every band), so one reading whose "bands" are
the nodes of a (log μa, log μs) grid around the Kubelka–Munk fit tabulates each thickness's
readings over black and white (:meth:`Problem.build_table`, a smoothing spline whose misfit
is the nodes' noise). The fit runs on the table; the fitted coefficients are then read by the
model at the readings' bands and the difference moves the table's target (a defect
correction, at most :data:`CORRECTIONS` times, until the table and the model agree within
:data:`DEFECT_TOLERANCE` of every residual's spread); the best verified iterate is kept, band
by band. Measured: docs/notes/2026-12-07-fit-readings.md (a fit calling the Monte Carlo at
every step needed about 20 readings per thickness and stalled at 1–3 ΔE00; with the layered
solver one verification is usually enough).

The uncertainty of each parameter comes from the Jacobian with the readings' sd (or
:data:`DEFAULT_SD`) and the Monte Carlo standard error, widened by the residuals' chi-square
per degree of freedom where that exceeds 1 (:func:`_misfit_scale`); a parameter whose
standard deviation in log exceeds :data:`PINNED_SD` is not pinned by the readings, and one
thickness over one backing never pins both coefficients (``identifiable`` false).
"""

from __future__ import annotations

import datetime as _dt
import math
import time
from dataclasses import dataclass, field

import numpy as np

from dentalux.color import delta_e00, delta_e00_scale
from dentalux.inverse import readings_smooth
from dentalux.inverse.readings_model import (
    TABLE_PHOTON_FRACTION,
    Problem,
    km_reflectance,  # noqa: F401 (tests, callers)
)
from dentalux.reading import engine
from dentalux.reading.layered.stack import ACCURACY
from dentalux.readings import BackingFile, Readings

MODELS = ("mc", "km")
#: how the ``mc`` model reads: the solvers of :func:`dentalux.dental.read`; 'auto' is the
#: layered solver wherever the instrument's beam is normal, else the Monte Carlo walks
SOLVERS = engine.SOLVERS
DEFAULT_SOLVER = engine.DEFAULT_SOLVER
#: g and n when the user gives none: typical of resin composites and glass ceramics
#: (n 1.50-1.55; g of filled resins 0.6-0.8 in the inverse-adding-doubling literature)
ASSUMED_G, ASSUMED_N = 0.6, 1.5
#: the spread assumed for a reading without sd columns: instrument repeatability
DEFAULT_SD = {"spectral": 0.003, "lab": 0.3}
#: bands on which a CIELAB-only fit evaluates its smooth spectrum [nm]
LAB_BANDS = tuple(float(w) for w in range(380, 781, 20))
#: bands written to the material file of a CIELAB-only fit [nm]
LAB_OUT_BANDS = tuple(float(w) for w in range(380, 781, 20))
LAB_PARAMS = ("log_mua_550", "mua_slope", "mua_curvature", "log_mus_550", "mus_power")
#: a parameter is pinned by the readings when its standard deviation (in log for the
#: coefficients) is below this (a factor of about 1.65)
PINNED_SD = 0.5
#: bounds of log μa and log μs [1/mm]
LOG_BOUNDS = (math.log(1e-6), math.log(1e3))
#: finite-difference step in log: large enough to rise above the Monte Carlo noise that
#: common random numbers leave, small against the curvature of a reading in log μ
TABLE_STEP, KM_STEP = 1e-3, 1e-4
DEFAULT_PHOTONS = 20_000
DEFAULT_ITERATIONS = {"table": 40, "km": 60}
#: the Monte Carlo model's table: nodes in (log μa, log μs), and how far it reaches beyond
#: the Kubelka-Munk fit (in log: μa down 100x, up 3x, as edge loss makes Kubelka-Munk
#: over-estimate absorption; μs 5x either way)
TABLE_NODES = (12, 10)
#: the layered solver's table is smooth (no noise for the spline to average), so fewer nodes
#: do: 8 x 7 left the fits' residuals within 0.03 ΔE00 of 12 x 10 at 0.6-0.7 of the CPU
#: (docs/notes/2026-12-07-fit-readings.md)
LAYERED_TABLE_NODES = (8, 7)
TABLE_SPAN = {"mua": (math.log(100.0), math.log(3.0)), "mus": (math.log(3.0), math.log(3.0))}
#: defect corrections: the table fit is read by Monte Carlo at the fitted coefficients and
#: the difference moves the target of the next table fit
CORRECTIONS = 3
#: with the layered solver the corrections stop once the table and the model agree at the
#: fit within this part of every residual's spread (or within their noise)
DEFECT_TOLERANCE = 0.1
#: the noise of a table-against-model difference, in standard errors of the verifying
#: reading's noise: 3 of the difference, whose table half has 1 / TABLE_PHOTON_FRACTION the
#: variance
NOISE_SPAN = 3.0 * math.sqrt(1.0 + 1.0 / TABLE_PHOTON_FRACTION)
#: a residual above this (ΔE00) gets a warning: the model cannot reproduce the reading
WARN_RESIDUAL = 2.0


@dataclass
class ReadingsFit:
    """The fitted coefficients at :attr:`wavelength_nm`, with residuals and diagnostics."""

    model: str
    wavelength_nm: np.ndarray
    mua: np.ndarray
    mus: np.ndarray
    mua_ci: np.ndarray
    mus_ci: np.ndarray
    g: float
    n: float
    assumed: dict
    residuals: list[dict]
    identifiable: bool
    identifiability: str
    pinned: dict
    seconds: float
    evaluations: int
    photons: int = 0
    seed: int = 1
    warnings: list[str] = field(default_factory=list)
    mc_stderr_de00: float = 0.0
    cpu_seconds: float = 0.0
    #: how the mc model read: 'layered' or 'monte-carlo' ('' for km)
    solver: str = ""
    #: the weight of the smoothness penalty across bands (0: none)
    smooth: float = 0.0


def _lab_spread(prob: Problem, spectrum, sd) -> np.ndarray:
    """The standard deviation of L*, a*, b* from independent errors ``sd`` of each band, to
    first order (one derivative per band)."""
    spectrum, sd = np.asarray(spectrum, float), np.asarray(sd, float)
    if not np.any(sd):
        return np.zeros(3)
    base = prob.lab(spectrum)
    steps = spectrum[None, :] + np.diag(sd)
    return np.sqrt(np.sum((prob.lab(steps) - base) ** 2, axis=0))


def _model_lab_err(prob: Problem, spectrum, err) -> np.ndarray:
    """The model's error of L*, a*, b*: its noise, independent from band to band, and the
    layered solver's accuracy, which may move every band together (so it moves L* most)."""
    spectrum = np.asarray(spectrum, float)
    acc = prob.accuracy * spectrum
    noise = _lab_spread(prob, spectrum, np.sqrt(np.maximum(np.asarray(err) ** 2 - acc ** 2, 0)))
    if not prob.accuracy:
        return noise
    return np.hypot(noise, np.abs(prob.lab(spectrum + acc) - prob.lab(spectrum)))


# --- parametrisations ---------------------------------------------------------------------


def _lab_spectrum(theta, bands):
    """The smooth CIELAB-only spectrum (module doc): theta (..., 5) -> mua, mus (..., bands)."""
    x = (np.asarray(bands) - 550.0) / 100.0
    t = np.asarray(theta)
    log_mua = t[..., 0:1] + t[..., 1:2] * x + t[..., 2:3] * x * x
    log_mus = t[..., 3:4] - t[..., 4:5] * np.log(np.asarray(bands) / 550.0)
    return (np.exp(np.clip(log_mua, *LOG_BOUNDS)), np.exp(np.clip(log_mus, *LOG_BOUNDS)))


class _Spectral:
    """Per-band parameters: theta (bands, 2) = log μa, log μs; residuals (bands, readings);
    ``pen``: the smoothness penalty's rows (:mod:`readings_smooth`), or None."""

    def __init__(self, prob: Problem, pen=None):
        self.p, self.pen = prob, pen
        rows = prob.r.rows
        self.meas = np.array([r.spectrum for r in rows])
        sd = np.array([r.sd_spectrum if r.sd_spectrum is not None
                       else np.full(len(prob.bands), DEFAULT_SD["spectral"]) for r in rows])
        self.sd = np.maximum(sd, 1e-4)

    def coefficients(self, theta):
        return np.exp(theta[:, 0]), np.exp(theta[:, 1])

    def residuals(self, theta):
        pred, err = self.p.spectra(*self.coefficients(theta))
        sigma = np.sqrt(self.sd ** 2 + err ** 2)
        return ((pred - self.meas) / sigma).T, pred, err

    def noise(self, pred, err):
        """The model's noise (not its accuracy) in units of each residual's spread."""
        se = np.sqrt(np.maximum(err ** 2 - (self.p.accuracy * pred) ** 2, 0.0))
        return (se / np.sqrt(self.sd ** 2 + err ** 2)).T


class _Lab:
    """Five smooth-spectrum parameters in one block; residuals in L*, a*, b* per reading."""

    def __init__(self, prob: Problem):
        self.p = prob
        rows = prob.r.rows
        self.meas = np.array([r.lab for r in rows])
        sd = np.array([r.sd_lab if r.sd_lab is not None else (DEFAULT_SD["lab"],) * 3
                       for r in rows])
        self.sd = np.maximum(sd, 0.05)

    def coefficients(self, theta):
        return _lab_spectrum(theta[0], self.p.bands)

    def residuals(self, theta):
        pred, err = self.p.spectra(*self.coefficients(theta))
        lab = self.p.lab(pred)
        # the model's error of each L*, a*, b*, to first order through the reconstruction
        lab_err = np.array([_model_lab_err(self.p, p, e) for p, e in zip(pred, err, strict=True)])
        sigma = np.sqrt(self.sd ** 2 + lab_err ** 2)
        return ((lab - self.meas) / sigma).reshape(1, -1), pred, err

    def noise(self, pred, err):
        """The model's noise (not its accuracy) in units of each residual's spread."""
        acc = self.p.accuracy * pred
        se = np.sqrt(np.maximum(err ** 2 - acc ** 2, 0.0))
        lab_se = np.array([_lab_spread(self.p, p, e) for p, e in zip(pred, se, strict=True)])
        lab_err = np.array([_model_lab_err(self.p, p, e) for p, e in zip(pred, err, strict=True)])
        return (lab_se / np.sqrt(self.sd ** 2 + lab_err ** 2)).reshape(1, -1)


# --- Levenberg–Marquardt over independent blocks -------------------------------------------


def _bounds(theta_shape, form):
    lo, hi = np.full(theta_shape, LOG_BOUNDS[0]), np.full(theta_shape, LOG_BOUNDS[1])
    if form == "lab":
        lo[:, [1, 2, 4]], hi[:, [1, 2, 4]] = -10.0, 10.0
    return lo, hi


def _jacobian(obj, theta, r0, step, lo, hi):
    k = theta.shape[1]
    jac = np.empty(r0.shape + (k,))
    for j in range(k):
        t = theta.copy()
        h = np.where(theta[:, j] + step > hi[:, j], -step, step)
        t[:, j] += h
        jac[..., j] = (obj.residuals(t)[0] - r0) / h[:, None]
    return jac


def _lm(obj, theta, step, iterations, lo, hi, final_jacobian=True):
    """Block Levenberg–Marquardt; returns theta, residuals, prediction, error, Jacobian."""
    if getattr(obj, "pen", None) is not None:  # the bands coupled by smoothness
        return readings_smooth.lm(obj, theta, step, iterations, lo, hi, obj.pen, _jacobian)
    r, pred, err = obj.residuals(theta)
    cost = np.sum(r * r, axis=1)
    lam = np.full(theta.shape[0], 1e-2)
    jac = None
    for it in range(iterations):
        jac = _jacobian(obj, theta, r, step, lo, hi)
        jtj = np.einsum("bmi,bmj->bij", jac, jac)
        jtr = np.einsum("bmi,bm->bi", jac, r)
        damp = jtj + lam[:, None, None] * (np.eye(theta.shape[1]) * np.maximum(
            np.diagonal(jtj, axis1=1, axis2=2)[:, :, None], 1e-9))
        # pseudo-inverse: a reading insensitive to a parameter (a flat Jacobian column,
        # e.g. a thick opaque disc) leaves that parameter where it is instead of failing
        delta = -np.einsum("bij,bj->bi", np.linalg.pinv(np.nan_to_num(damp)),
                           np.nan_to_num(jtr))
        delta = np.clip(delta, -2.0, 2.0)  # at most a factor e^2 a step
        trial = np.clip(theta + delta, lo, hi)
        r_t, pred_t, err_t = obj.residuals(trial)
        cost_t = np.sum(r_t * r_t, axis=1)
        better = cost_t < cost
        theta = np.where(better[:, None], trial, theta)
        r = np.where(better[:, None], r_t, r)
        # the prediction is (readings, bands): per band for spectral blocks, whole otherwise
        mask = better[None, :] if isinstance(obj, _Spectral) else better[0]
        pred, err = np.where(mask, pred_t, pred), np.where(mask, err_t, err)
        lam = np.where(better, lam / 5.0, lam * 10.0)
        cost = np.where(better, cost_t, cost)
        if it >= 1 and np.all(np.abs(delta) < 1e-3):
            break
    if jac is None or final_jacobian:  # at the fitted point (the last one is a step behind)
        jac = _jacobian(obj, theta, r, step, lo, hi)
    return theta, r, pred, err, jac


# --- the fit ------------------------------------------------------------------------------


def _start(form, bands):
    if form == "spectral":
        return np.column_stack([np.full(len(bands), math.log(0.05)),
                                np.full(len(bands), math.log(5.0))])
    return np.array([[math.log(0.05), 0.0, 0.0, math.log(5.0), 1.0]])


def _fit_table(prob: Problem, wrap, theta, lo, hi, form, iterations):
    """The ``mc`` fit from the Kubelka–Munk fit ``theta``: on the table, with defect
    corrections verified by the model itself (module doc)."""
    mua0, mus0 = wrap(prob).coefficients(theta)
    span_a = (max(math.log(float(np.min(mua0))) - TABLE_SPAN["mua"][0], LOG_BOUNDS[0]),
              min(math.log(float(np.max(mua0))) + TABLE_SPAN["mua"][1], LOG_BOUNDS[1]))
    span_s = (max(math.log(float(np.min(mus0))) - TABLE_SPAN["mus"][0], LOG_BOUNDS[0]),
              min(math.log(float(np.max(mus0))) + TABLE_SPAN["mus"][1], LOG_BOUNDS[1]))
    prob.build_table(span_a, span_s, LAYERED_TABLE_NODES if prob.layered else TABLE_NODES)
    obj = wrap(prob)
    if form == "spectral":
        lo[:, 0], hi[:, 0] = span_a
        lo[:, 1], hi[:, 1] = span_s
        theta = np.clip(theta, lo, hi)
    its = DEFAULT_ITERATIONS["table"] if iterations is None else iterations
    best = None
    for _ in range(CORRECTIONS + 1):
        theta, r_t, pred_t, err_t, jac = _lm(obj, theta, TABLE_STEP, its, lo, hi)
        prob.model = "mc"  # the reading at the fit, through the instrument
        r, pred, err = obj.residuals(theta)
        prob.model = "table"
        # keep the best verified iterate, per block (band) where blocks are independent:
        # the corrections may oscillate within the Monte Carlo noise
        cost = np.sum(r * r, axis=1)
        total = np.sum(cost) + (np.sum((obj.pen @ theta.ravel()) ** 2)
                                if getattr(obj, "pen", None) is not None else 0.0)
        if best is None:
            best = [theta.copy(), r.copy(), pred.copy(), err.copy(), jac.copy(), cost, total]
        else:
            win = cost < best[5]
            if getattr(obj, "pen", None) is not None:  # coupled bands: the whole fit
                pen_cost = np.sum((obj.pen @ theta.ravel()) ** 2)
                win = np.full(cost.shape, np.sum(cost) + pen_cost < best[6])
            mask = win[None, :] if form == "spectral" else win[0]
            best = [np.where(win[:, None], theta, best[0]), np.where(win[:, None], r, best[1]),
                    np.where(mask, pred, best[2]), np.where(mask, err, best[3]),
                    np.where(win[:, None, None], jac, best[4]), np.where(win, cost, best[5]),
                    min(total, best[6])]
        # with the layered solver: the table agrees with the model at the fit within a small
        # part of every residual's spread, or within what the rim corrections' noise in
        # both resolves, so a further correction would move the fit by less than that (the
        # walks' tables are smoothed through their noise: they always correct)
        noise = obj.noise(pred, err) * NOISE_SPAN
        if prob.layered and np.all(np.abs(r - r_t) < DEFECT_TOLERANCE + noise):
            break
        # defect correction: the table's error at the fit moves the next fit's target
        prob.defect = prob.defect + (pred - pred_t)
    return (*best[:5], lo, hi, (span_a, span_s))


def _misfit_scale(r, theta, pen) -> np.ndarray:
    """Each block's covariance factor: the residuals' chi-square per degree of freedom where
    the readings scatter about the fit more than their stated (or assumed) spread, so that
    the intervals widen with the misfit; never below 1 (a close fit does not shrink the
    readings' sd), 1 where no degree of freedom is left. With the smoothness penalty the
    bands are one block, the penalty's rows counted as observations."""
    if pen is None:
        chi2, dof = np.sum(r * r, axis=1), r.shape[1] - theta.shape[1]
    else:
        chi2 = np.full(r.shape[0], np.sum(r * r) + np.sum((pen @ theta.ravel()) ** 2))
        dof = r.size + pen.shape[0] - theta.size
    return np.maximum(chi2 / dof, 1.0) if dof > 0 else np.ones(r.shape[0])


def _edge_note(theta, lo, hi, bands, span_a) -> str:
    """A warning for bands whose fit sits at the table's edge (empty where none does)."""
    low_mua, edge = [], []
    for i in range(len(bands)):
        at_lo, at_hi = np.isclose(theta[i], lo[i]), np.isclose(theta[i], hi[i])
        if at_lo[0] and not (at_lo[1] or np.any(at_hi)):
            low_mua.append(i)  # absorption below what the readings resolve
        elif np.any(at_lo) or np.any(at_hi):
            edge.append(i)
    notes = []
    if low_mua:
        notes.append(f"μa is below what the readings resolve at {len(low_mua)} band(s) "
                     f"({', '.join(f'{bands[i]:g}' for i in low_mua[:5])} nm): at most "
                     f"{math.exp(span_a[0]):.2g} /mm there (the value written is that bound)")
    if edge:
        notes.append(f"the fit reached the edge of its table at {len(edge)} band(s) "
                     f"({', '.join(f'{bands[i]:g}' for i in edge[:5])} nm): the readings "
                     "may lie outside what g and n allow")
    return "; ".join(notes)


def fit(readings: Readings, instrument, g: float | None = None, n: float | None = None,
        model: str = "mc", photons: int = DEFAULT_PHOTONS, seed: int = 1,
        iterations: int | None = None, solver: str = DEFAULT_SOLVER,
        smooth: float = 0.0) -> ReadingsFit:
    """Fit a material to ``readings`` read by ``instrument`` (module doc); ``solver`` is how
    the ``mc`` model reads (:data:`SOLVERS`); ``smooth`` > 0 weighs a second-difference
    penalty across the bands of a spectral fit (:mod:`readings_smooth`)."""
    from dentalux import instrument as instruments

    if model not in MODELS:
        raise ValueError(f"--model = {model!r}: allowed {', '.join(MODELS)}")
    if solver not in SOLVERS:
        raise ValueError(f"--solver = {solver!r}: allowed {', '.join(SOLVERS)}")
    if not (math.isfinite(smooth) and smooth >= 0):
        raise ValueError(f"--smooth = {smooth!r}: a weight >= 0")
    if smooth and readings.form != "spectral":
        raise ValueError("--smooth: the readings are CIELAB only, fitted through a smooth "
                         "spectrum already; --smooth is for spectral readings")
    inst = instruments.get(instrument)
    if model == "mc":  # refuses 'layered' through an oblique beam before any work
        layered = engine.use_layered(inst, solver)
    assumed = {}
    if g is None:
        g, assumed["g"] = ASSUMED_G, (f"assumed: {ASSUMED_G} (typical of filled resins and "
                                      "glass ceramics; not given with --g)")
    else:
        assumed["g"] = f"assumed: {g:g}, given with --g"
    if n is None:
        n, assumed["n"] = ASSUMED_N, (f"assumed: {ASSUMED_N} (typical of composites and glass "
                                      "ceramics; not given with --n)")
    else:
        assumed["n"] = f"assumed: {n:g}, given with --n"
    if not -1.0 < g < 1.0:
        raise ValueError(f"--g = {g!r} is out of range: allowed (-1, 1)")
    if not 1.0 <= n <= 3.0:
        raise ValueError(f"--n = {n!r} is out of range: allowed [1, 3]")
    start = time.perf_counter()
    form = readings.form
    bands = readings.wavelength_nm if form == "spectral" else list(LAB_BANDS)
    pen = readings_smooth.penalty(bands, 2, smooth) if smooth else None
    wrap = (lambda p: _Spectral(p, pen)) if form == "spectral" else _Lab
    # Kubelka–Munk first: the baseline, and the start of the Monte Carlo fit
    km = Problem(readings, inst, g, n, "km", photons, seed, bands)
    obj = wrap(km)
    theta = _start(form, bands)
    lo, hi = _bounds(theta.shape, form)
    theta, r, pred, err, jac = _lm(obj, theta, KM_STEP, DEFAULT_ITERATIONS["km"], lo, hi)
    evaluations = km.evaluations
    prob = km
    edge_note = ""
    if model == "mc":
        prob = Problem(readings, inst, g, n, "mc", photons, seed, bands, solver)
        theta, r, pred, err, jac, lo, hi, spans = _fit_table(prob, wrap, theta, lo, hi, form,
                                                             iterations)
        evaluations = prob.mc_calls
        edge_note = _edge_note(theta, lo, hi, bands, spans[0]) if form == "spectral" else ""
    # uncertainty of each parameter: (J^T J)^-1 with residuals in units of their sigma (with
    # smoothing, the penalised problem's), widened by the misfit; singular: the readings
    # alone do not pin a band
    jtj = np.einsum("bmi,bmj->bij", jac, jac)
    cov = (np.linalg.pinv(jtj) if pen is None else readings_smooth.block_covariance(jac, pen))
    cov = cov * _misfit_scale(r, theta, pen)[:, None, None]
    sd = np.sqrt(np.clip(np.diagonal(cov, axis1=1, axis2=2), 0, None))
    singular = np.linalg.cond(jtj) > 1e12
    sd = np.where(singular[:, None], np.inf, sd)
    conditions = readings.conditions()
    if form == "spectral":
        out_bands = np.asarray(bands, float)
        mua, mus = np.exp(theta[:, 0]), np.exp(theta[:, 1])
        z = 1.96 * np.minimum(sd, 50.0)
        mua_ci = np.column_stack([mua * np.exp(-z[:, 0]), mua * np.exp(z[:, 0])])
        mus_ci = np.column_stack([mus * np.exp(-z[:, 1]), mus * np.exp(z[:, 1])])
        med = np.median(sd, axis=0)
        pinned = {"log_mua": bool(med[0] < PINNED_SD), "log_mus": bool(med[1] < PINNED_SD)}
        pinned_sd = {"log_mua": float(min(med[0], 1e6)), "log_mus": float(min(med[1], 1e6))}
    else:
        out_bands = np.asarray(LAB_OUT_BANDS)
        mua, mus = _lab_spectrum(theta[0], out_bands)
        rng = np.random.default_rng(0)
        c = cov[0] if np.all(np.isfinite(sd)) else np.diag(np.full(5, 25.0))
        draws = rng.multivariate_normal(theta[0], c, size=400, check_valid="ignore")
        a_d, s_d = _lab_spectrum(draws, out_bands)
        mua_ci = np.column_stack([np.percentile(a_d, 2.5, axis=0),
                                  np.percentile(a_d, 97.5, axis=0)])
        mus_ci = np.column_stack([np.percentile(s_d, 2.5, axis=0),
                                  np.percentile(s_d, 97.5, axis=0)])
        pinned = {p: bool(s < PINNED_SD) for p, s in zip(LAB_PARAMS, sd[0], strict=True)}
        pinned_sd = {p: float(min(s, 1e6)) for p, s in zip(LAB_PARAMS, sd[0], strict=True)}
        pinned.update(log_mua=pinned["log_mua_550"], log_mus=pinned["log_mus_550"])
    mua_ci = np.minimum(np.maximum(mua_ci, 0.0), 1e5)
    mus_ci = np.minimum(np.maximum(mus_ci, 0.0), 1e5)
    if len(conditions) < 2:
        identifiable = False
        why = (f"one thickness over one backing ({len(readings.rows)} reading(s) of one "
               "condition) cannot pin both μa and μs: read the disc over black and white, or "
               "at a second thickness")
    elif not (pinned["log_mua"] and pinned["log_mus"]):
        identifiable = False
        loose = [q for q, k in (("μa", "log_mua"), ("μs", "log_mus")) if not pinned[k]]
        why = (f"the readings barely constrain {' and '.join(loose)} (standard deviation in "
               f"log above {PINNED_SD}; e.g. backings that barely differ through a thick "
               "disc): read a thinner disc, or over a darker and a lighter backing")
    else:
        identifiable = True
        why = "both coefficients pinned by the readings"
    # residuals per reading in ΔE00, predicted against measured
    meas_lab = (np.array([row.lab for row in readings.rows]) if form == "lab"
                else prob.lab(np.array([row.spectrum for row in readings.rows])))
    pred_lab = prob.lab(pred)
    de = np.atleast_1d(delta_e00(pred_lab, meas_lab))
    residuals = []
    noise = []
    for i, row in enumerate(readings.rows):
        lab_err = _model_lab_err(prob, pred[i], err[i])
        noise.append(delta_e00_scale(pred_lab[i], lab_err) if np.any(lab_err) else 0.0)
        if form == "lab":
            sd_lab = np.asarray(row.sd_lab if row.sd_lab is not None else (0.0,) * 3)
        else:
            sd = row.sd_spectrum if row.sd_spectrum is not None else np.zeros(len(bands))
            sd_lab = _lab_spread(prob, row.spectrum, sd)
        spread = delta_e00_scale(meas_lab[i], sd_lab) if np.any(sd_lab) else 0.0
        residuals.append({"thickness_mm": row.thickness_mm,
                          "backing": row.backing_label if isinstance(row.backing, BackingFile)
                          else row.backing,
                          "delta_e00": float(de[i]), "line": row.line,
                          "measured_lab": [float(x) for x in meas_lab[i]],
                          "predicted_lab": [float(x) for x in pred_lab[i]],
                          "mc_stderr_de00": float(noise[-1]),
                          "reading_sd_de00": float(spread)})
    warnings = []
    # a residual beyond WARN_RESIDUAL plus three combined spreads (reading sd, Monte Carlo)
    # is more than noise: the model cannot reproduce that reading
    bad = [r for r in residuals if r["delta_e00"] > WARN_RESIDUAL + 3 * math.hypot(
        r["mc_stderr_de00"], r["reading_sd_de00"])]
    if bad:
        worst = max(bad, key=lambda x: x["delta_e00"])
        warnings.append(
            f"the fit leaves {worst['delta_e00']:.2f} ΔE00 at {worst['thickness_mm']:g} mm over "
            f"{worst['backing']} (line {worst['line']}): no μa, μs >= 0 with g {g:g} and n "
            f"{n:g} reproduces every reading through {inst.name}; check the backings, the "
            "instrument and g, n")
    if not identifiable:
        warnings.append(why)
    if edge_note:
        warnings.append(edge_note)
    return ReadingsFit(model=model, wavelength_nm=out_bands, mua=np.asarray(mua),
                       mus=np.asarray(mus), mua_ci=mua_ci, mus_ci=mus_ci, g=float(g),
                       n=float(n), assumed=assumed, residuals=residuals,
                       identifiable=identifiable, identifiability=why,
                       pinned={"pinned": pinned, "sd_log": pinned_sd},
                       seconds=time.perf_counter() - start, evaluations=evaluations,
                       photons=photons if model == "mc" else 0, seed=seed,
                       cpu_seconds=prob.cpu_seconds,
                       solver=("layered" if layered else "monte-carlo") if model == "mc" else "",
                       smooth=float(smooth),
                       warnings=warnings, mc_stderr_de00=float(np.max(noise)))


# --- the material file ----------------------------------------------------------------------


def _r(v: float) -> float:
    return float(f"{v:.6g}")


def material_doc(res: ReadingsFit, readings: Readings, inst, name: str,
                 date: str | None = None) -> dict:
    """The ``[materials.NAME]`` document of a fit, with its provenance."""
    from pathlib import Path

    form = ("spectral reflectance per band" if readings.form == "spectral" else
            "CIELAB only, through a smooth five-parameter spectrum (" + ", ".join(
                f"{p} {'pinned' if res.pinned['pinned'][p] else 'NOT pinned'}"
                for p in LAB_PARAMS) + ")")
    if res.solver == "layered":
        model = ("the layered solver through the instrument model (dentalux.dental.read, "
                 f"solver 'layered', edge loss included; {res.photons} photons per band for "
                 f"the rim correction, seed {res.seed}; model error, the rim correction's "
                 f"noise and the solver's stated accuracy {ACCURACY:.1%}, up to "
                 f"{res.mc_stderr_de00:.2f} ΔE00 per reading)")
    elif res.model == "mc":
        model = ("Monte Carlo through the instrument model (dentalux.dental.read, edge loss "
                 f"included; {res.photons} photons per band, seed {res.seed}, common random "
                 f"numbers; Monte Carlo noise up to {res.mc_stderr_de00:.2f} ΔE00 per reading)")
    else:
        model = ("Kubelka-Munk with the Saunderson correction (no edge loss; K = 2 mua, "
                 "S = 0.75 mus (1 - g))")
    resid = [f"{r['thickness_mm']:g} mm over {r['backing']}: {r['delta_e00']:.3f} ΔE00"
             for r in res.residuals]
    notes = (f"Fitted to {len(readings.rows)} readings ({form}) by {model}. Identifiable: "
             f"{'yes' if res.identifiable else 'NO'} ({res.identifiability}). mua_ci and "
             "mus_ci are 95 % intervals from the readings' sd (or the default "
             f"{DEFAULT_SD[readings.form]}) and the model's error (its noise and, with the "
             "layered solver, its stated accuracy), widened by the residuals' chi-square "
             "per degree of freedom where it exceeds 1."
             + (f" Smoothed across the bands (weight {res.smooth:g}): the intervals include "
                "that assumption." if res.smooth else ""))
    return {"materials": {name: {
        "description": f"fitted from the readings {Path(readings.path).name} read with "
                       f"{inst.name}",
        "extrapolate": True,
        "wavelength_nm": [float(w) for w in res.wavelength_nm],
        "mua": [_r(v) for v in res.mua],
        "mus": [_r(v) for v in res.mus],
        "g": [res.g] * len(res.wavelength_nm),
        "fd": [0.0] * len(res.wavelength_nm),
        "n": [res.n] * len(res.wavelength_nm),
        "mua_ci": [[_r(a), _r(b)] for a, b in res.mua_ci],
        "mus_ci": [[_r(a), _r(b)] for a, b in res.mus_ci],
        "provenance": {
            "kind": "fitted",
            "source": f"readings file {Path(readings.path).name} (sha256 {readings.sha256}), "
                      f"read with the instrument {inst.name}",
            "model": res.model,
            **({"solver": res.solver} if res.solver else {}),
            "instrument": inst.name,
            "readings_sha256": readings.sha256,
            "date": date or _dt.date.today().isoformat(),
            "identifiable": res.identifiable,
            "residuals_delta_e00": resid,
            "notes": notes,
            "values": {
                "mua": f"fitted: {res.model} fit to {Path(readings.path).name}",
                "mus": f"fitted: {res.model} fit to {Path(readings.path).name}",
                "g": res.assumed["g"],
                "n": res.assumed["n"],
                "fd": "assumed: 0 (pure Henyey-Greenstein)",
            },
        },
    }}}
